#!/usr/bin/env python3
"""Reference outputs of example scenes at reduced size (the bit-identity set as a test).

    python3 tests/regression/check_outputs.py check  --exe build/liggghts_mpm --work DIR
    python3 tests/regression/check_outputs.py update --exe build/liggghts_mpm --work DIR

Each scene below runs an example input of inputs/ at reduced size; every CSV file it writes is
compared, column by column, with the reference kept in tests/regression/<scene>.json (a sample of
at most 13 rows: evenly spaced and the last). A value passes if it is within
    rtol * max |column| + atol
of the reference (per scene and column in TOLERANCE, else the defaults below). On the same build
and libraries the outputs are identical; the tolerances leave room for another compiler or math
library's round-off and for nothing else: any change of the physics or the numerics moves these
short runs by far more. 'update' re-generates the references after a change that is meant to
change results (say which and why in the commit). Standard library only.
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.normpath(os.path.join(HERE, "..", ".."))

RTOL, ATOL = 1e-7, 1e-12
# name: (input relative to inputs/, variables)
SCENES = {
    "hydrostatic": ("hydrostatic/in.hydrostatic", {"cells": 16, "tend": 0.2}),
    "dambreak16": ("dambreak/in.dambreak", {"cells": 16, "tend": 1.0}),
    "settling": ("settling/in.settling", {"tend": 0.03}),
    "porewave": ("porewave/in.porewave", {"jitter": 0.0008, "v0": 0.1, "nsteps": 300}),
    "wave20": ("sloshing/in.wave", {"cells": 20, "tend": 1.4}),
    "wave20_eos": ("sloshing/in.wave", {"cells": 20, "tend": 0.7, "pressure": "eos"}),
}
# (scene, file, column) -> (rtol, atol); None: not compared
TOLERANCE = {}
ROWS = 13


def run_scene(exe, work, name):
    inp, variables = SCENES[name]
    d = os.path.join(work, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    shutil.copy(os.path.join(TOP, "inputs", inp), d)
    cmd = [exe, "-in", os.path.basename(inp), "-echo", "none", "-screen", os.devnull]
    for k, v in variables.items():
        cmd += ["-var", k, str(v)]
    p = subprocess.run(cmd, cwd=d, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode != 0:
        log = os.path.join(d, "log.liggghts")
        tail = open(log, errors="replace").read().splitlines()[-5:] if os.path.exists(log) else []
        raise RuntimeError(f"{name}: liggghts_mpm exit {p.returncode}: " + " | ".join(tail))
    out = {}
    for fn in sorted(os.listdir(d)):
        if not fn.endswith(".csv"):
            continue
        with open(os.path.join(d, fn), newline="") as f:
            rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
        head, body = rows[0], rows[1:]
        if not body:
            continue
        pick = sorted({round(i * (len(body) - 1) / (ROWS - 1)) for i in range(ROWS)}) if len(body) > ROWS else \
            list(range(len(body)))
        out[fn] = {"columns": head, "rows": pick, "values": [[float(x) for x in body[i]] for i in pick]}
    return out


def compare(name, ref, new):
    bad = []
    for fn, r in ref.items():
        if fn not in new:
            bad.append(f"{fn}: missing")
            continue
        n = new[fn]
        if n["columns"] != r["columns"] or n["rows"] != r["rows"]:
            bad.append(f"{fn}: columns or rows differ ({len(n['rows'])} rows against {len(r['rows'])})")
            continue
        for c, col in enumerate(r["columns"]):
            tol = TOLERANCE.get((name, fn, col), (RTOL, ATOL))
            if tol is None:
                continue
            a = [row[c] for row in r["values"]]
            b = [row[c] for row in n["values"]]
            scale = max(abs(x) for x in a)
            worst = max(abs(x - y) for x, y in zip(a, b))
            if worst > tol[0] * scale + tol[1]:
                bad.append(f"{fn}:{col}: largest difference {worst:.3g} (scale {scale:.3g}, allowed "
                           f"{tol[0] * scale + tol[1]:.3g})")
    for fn in new:
        if fn not in ref:
            bad.append(f"{fn}: no reference")
    return bad


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=("check", "update"))
    ap.add_argument("--exe", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--only", nargs="*", choices=list(SCENES))
    a = ap.parse_args()
    exe = os.path.abspath(a.exe)
    failed = 0
    for name in a.only or list(SCENES):
        path = os.path.join(HERE, name + ".json")
        new = run_scene(exe, os.path.abspath(a.work), name)
        if a.mode == "update":
            with open(path, "w") as f:
                json.dump(new, f, indent=0, sort_keys=True)
                f.write("\n")
            print(f"{name}: reference written ({', '.join(sorted(new))})")
            continue
        with open(path) as f:
            ref = json.load(f)
        bad = compare(name, ref, new)
        print(f"{name}: " + ("as the reference (" + ", ".join(sorted(ref)) + ")" if not bad else "DIFFERS"))
        for b in bad:
            print("   " + b)
        failed += bool(bad)
    print(f"{failed} scene(s) differ" if failed else "all scenes as their references")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
