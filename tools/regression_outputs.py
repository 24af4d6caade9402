#!/usr/bin/env python3
"""Runs the example inputs whose outputs a behaviour-preserving change must not alter, and compares
two such sets bit for bit.

    tools/python tools/regression_outputs.py run --exe build/liggghts_mpm --out /tmp/ref
    tools/python tools/regression_outputs.py run --exe build/liggghts_mpm --out /tmp/new
    tools/python tools/regression_outputs.py compare /tmp/ref /tmp/new

Scenes (each in its own folder below --out): the F2 dam break at MPM32 with HDF5 output, the F1
hydrostatic column, C1 settling, C3 tank and C4 jar in quick mode, and the pore-wave bed (jittered,
moving). 'compare' checks every CSV, LIGGGHTS dump and HDF5 dataset for exact equality, and the
thermo lines of each log (the LIGGGHTS timing lines and the fix's wall-time columns are left out).
It prints one line per file and exits 1 if anything differs. About 3 minutes on one core.
"""
import argparse
import math
import os
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.dirname(HERE)

# name: (input relative to inputs/, variables, preparation)
SCENES = {
    "dambreak32": ("dambreak/in.dambreak", {"cells": 32, "h5every": 400}, None),
    "hydrostatic": ("hydrostatic/in.hydrostatic", {"cells": 16}, None),
    "settling": ("settling/in.settling", {}, None),
    "tank_quick": ("tank/in.tank", {"quick": 1}, None),
    "jar_quick": ("jar/in.jar", {"quick": 1}, "jar"),
    "porewave": ("porewave/in.porewave", {"jitter": 0.0008, "v0": 0.1, "nsteps": 1000}, None),
}

# log lines that carry wall-clock time (they differ between any two runs)
TIMING = re.compile(r"Loop time|wall time|CPU|Performance|timesteps/s|Setting up run at|time \(%\) =|Pair +\||Neigh +\||Comm +\||"
                    r"Output +\||Modify +\||Other +\||Nlocal|Histogram|Neighbor list|Total wall|"
                    r"^ *[0-9.]+ +[0-9.]+ +[0-9.]+ +[0-9.]+ *$|Memory usage|Total # of neighbors|"
                    r"Ave neighs|Neighbor list builds|Dangerous builds|MPI task timing|^Section|^---")


def run(args):
    exe = os.path.abspath(args.exe)
    os.makedirs(args.out, exist_ok=True)
    names = args.only or list(SCENES)
    for name in names:
        inp, variables, prep = SCENES[name]
        d = os.path.join(args.out, name)
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        shutil.copy(os.path.join(TOP, "inputs", inp), d)
        if prep == "jar":
            subprocess.run([sys.executable, os.path.join(HERE, "make_jar_stl.py"), "jar.stl", "--axis", "y",
                            "--centre", "0.05", "0.05", "0.05"], cwd=d, check=True, stdout=subprocess.DEVNULL)
        cmd = [exe, "-in", os.path.basename(inp), "-echo", "none"]
        for k, v in variables.items():
            cmd += ["-var", k, str(v)]
        if args.np > 1:
            cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(args.np)] + cmd
        with open(os.path.join(d, "screen.txt"), "w") as out:
            p = subprocess.run(cmd, cwd=d, stdout=out, stderr=subprocess.STDOUT)
        print(f"{name}: exit {p.returncode}", flush=True)
        if p.returncode != 0:
            sys.exit(f"{name} failed; see {d}/screen.txt")


def thermo_lines(path):
    """Log lines without wall-clock content; the fix's wall-time outputs f_ID[14], f_ID[15] never
    appear in the inputs' thermo, the 'fix mpm/fluid: wall time' line is dropped, and thermo rows
    under a header with LIGGGHTS' CPU column lose that column."""
    keep = []
    cpu = None  # the CPU column of the thermo rows under a header that has one (LIGGGHTS' default style)
    with open(path, errors="replace") as f:
        for line in f:
            words = line.split()
            if "CPU" in words and "Step" in words:
                cpu = (words.index("CPU"), len(words))
            elif cpu and len(words) == cpu[1] and all(re.fullmatch(r"[-+.0-9eE]+", w) for w in words):
                del words[cpu[0]]
                keep.append(" ".join(words))
                continue
            elif line.startswith("Loop time"):  # the end of the run's thermo rows
                cpu = None
            # the fix's end-of-run lines: wall times, waits and peak memory (and builds without them)
            if TIMING.search(line) or line.startswith(("fix mpm/fluid: wall time", "fix mpm/fluid: halo exchanges",
                                                       "fix mpm/fluid: work per rank")):
                continue
            keep.append(line.rstrip("\n"))
    return keep


def h5_datasets(path):
    import h5py
    out = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset):
            out[name] = obj[()]
        for k, v in obj.attrs.items():
            out[f"{name}@{k}"] = v
    with h5py.File(path, "r") as f:
        f.visititems(visit)
        for k, v in f.attrs.items():
            out[f"/@{k}"] = v
    return out


def same_array(a, b):
    import numpy as np
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or a.dtype != b.dtype:
        return False, "shape/dtype"
    if a.dtype.kind == "f":
        eq = (a == b) | (np.isnan(a) & np.isnan(b))
        if eq.all():
            return True, ""
        diff = np.abs(a - b)[~eq]
        scale = np.max(np.abs(a)) if a.size else 1.0
        return False, f"{int((~eq).sum())} values differ, max abs {diff.max():.3g} (scale {scale:.3g})"
    return bool((a == b).all()), "values differ"


def compare(args):
    bad = 0
    for name in sorted(os.listdir(args.ref)):
        dref, dnew = os.path.join(args.ref, name), os.path.join(args.new, name)
        if not os.path.isdir(dref):
            continue
        for fn in sorted(os.listdir(dref)):
            pref, pnew = os.path.join(dref, fn), os.path.join(dnew, fn)
            if fn in ("screen.txt",) or fn.endswith((".stl", ".xmf")) or fn.startswith("in.") or \
                    os.path.isdir(pref) or "restart" in fn:
                continue
            if not os.path.exists(pnew):
                print(f"MISSING {name}/{fn}")
                bad += 1
                continue
            if fn.endswith(".h5"):
                a, b = h5_datasets(pref), h5_datasets(pnew)
                msgs = []
                for k in sorted(set(a) | set(b)):
                    if k not in a or k not in b:
                        msgs.append(f"{k} only in one")
                        continue
                    ok, why = same_array(a[k], b[k])
                    if not ok:
                        msgs.append(f"{k}: {why}")
                status = "identical" if not msgs else "DIFFERS " + "; ".join(msgs[:4])
            elif fn.startswith("log."):
                la, lb = thermo_lines(pref), thermo_lines(pnew)
                first = next((i for i, (x, y) in enumerate(zip(la, lb)) if x != y), None)
                if first is None and len(la) == len(lb):
                    status = "identical"
                else:
                    i = first if first is not None else min(len(la), len(lb))
                    status = f"DIFFERS at line {i}: {la[i] if i < len(la) else ''!r} vs {lb[i] if i < len(lb) else ''!r}"
            else:
                with open(pref, "rb") as f, open(pnew, "rb") as g:
                    status = "identical" if f.read() == g.read() else "DIFFERS"
            if status != "identical":
                bad += 1
            if status != "identical" or args.verbose:
                print(f"{name}/{fn}: {status}")
    print(f"{'all identical' if bad == 0 else f'{bad} files differ'}")
    return 1 if bad else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--exe", required=True)
    r.add_argument("--out", required=True)
    r.add_argument("--np", type=int, default=1)
    r.add_argument("--only", nargs="*", choices=list(SCENES))
    c = sub.add_parser("compare")
    c.add_argument("ref")
    c.add_argument("new")
    c.add_argument("-v", "--verbose", action="store_true")
    a = ap.parse_args()
    if a.cmd == "run":
        run(a)
        return 0
    return compare(a)


if __name__ == "__main__":
    sys.exit(main())
