#!/usr/bin/env python3
"""mpm_case.starter: the starter scene inputs/starter/in.pour_and_collapse at reduced size
(-var quick 1: 300 beads poured, a water column of 36 points released onto them, a few seconds).

Checks: the run ends normally with the default model; the largest point pressure stays below
5 (rho g h + rho U^2) of the column; every thermo value is finite; the fluid mass f_fluid[1] is the same
in every thermo line of the coupled runs and lies between 0.5 and 1 x rho0 x the column volume (the
points' mass is reduced by the beads inside the column); all beads are in the last dump, inside the
box, with finite values; the HDF5 index lists the point files; tools/render_run.py (through
tools/python) draws the run, reports the points and the beads, and every HDF5 data set is finite.
If tools/python cannot provide numpy, matplotlib and h5py (no network to create .venv), only that
last part is skipped, with a message. Standard library only otherwise.
  test_starter.py --exe build/liggghts_mpm --inputs inputs --work DIR
"""
import argparse
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.path.normpath(os.path.join(HERE, "..", "..", "tools"))
sys.path.insert(0, HERE)
import cases  # noqa: E402
from cases import check  # noqa: E402

# the quick scene (values of in.pour_and_collapse)
NBEADS, L, W, H, XGATE, HWATER, RHO = 300, 0.12, 0.02, 0.09, 0.03, 0.06, 1000.0
NPOINTS = 3 * 2 * 6  # cell 0.01, 1 point per cell: the column XGATE x W x HWATER


def thermo_blocks(text):
    """[(header words, [rows of floats])] of the thermo output, one block per run. LIGGGHTS prints
    v_nb as nb and f_fluid[1] as fluid[1] (cut to 8 characters: fluid[10)."""
    blocks, cur = [], None
    for ln in text.splitlines():
        w = ln.split()
        if w[:2] == ["Step", "Time"]:
            cur = (w, [])
            blocks.append(cur)
        elif cur is not None:
            try:
                vals = [float(x) for x in w]
            except ValueError:
                if ln.startswith("Loop time"):
                    cur = None
                continue
            if len(vals) == len(cur[0]):
                cur[1].append(vals)
    return blocks


def last_dump(d):
    steps = sorted(int(f[6:-5]) for f in os.listdir(d) if f.startswith("beads_") and f.endswith(".dump"))
    with open(os.path.join(d, "beads_%d.dump" % steps[-1])) as f:
        lines = f.read().splitlines()
    i = next(k for k, s in enumerate(lines) if s.startswith("ITEM: ATOMS"))
    names = lines[i].split()[2:]
    rows = [[float(x) for x in s.split()] for s in lines[i + 1:] if s.strip()]
    return steps[-1], names, rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--exe", required=True)
    ap.add_argument("--inputs", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--mpirun", default="mpirun --allow-run-as-root --oversubscribe")
    a = ap.parse_args()
    r = cases.Runner(a)
    d, p = r.run("starter", os.path.join(r.inputs, "starter", "in.pour_and_collapse"), {"quick": 1})
    check("ERROR" not in p.stdout, "the quick starter scene runs without error")

    blocks = thermo_blocks(p.stdout)
    check(len(blocks) == 3, f"three runs: pour, water behind the gate, release ({len(blocks)} thermo blocks)")
    finite = all(math.isfinite(v) for _, rows in blocks for row in rows for v in row)
    check(finite and all(rows for _, rows in blocks), "every thermo value finite, every run has thermo lines")
    pour_hdr, pour = blocks[0]
    check(pour and pour[-1][pour_hdr.index("nb")] == NBEADS, f"{NBEADS} beads poured")
    masses = [row[h.index("fluid[1]")] for h, rows in blocks[1:] for row in rows]
    m0 = RHO * XGATE * W * HWATER
    check(masses and max(masses) == min(masses),
          f"fluid mass f_fluid[1] the same in all {len(masses)} lines of the coupled runs ({masses[0]!r} kg)")
    check(0.5 * m0 < masses[0] <= m0 * (1 + 1e-12), f"fluid mass {masses[0]:.6g} kg within 0.5..1 x rho0 x column volume {m0:.6g}")
    fh, fl = blocks[2]
    # a bound from the inputs alone: the largest single point pressure (c_ppoint) below
    # 5 (rho g h + rho U^2), U the column's free-fall speed sqrt(2 g h); f_fluid[10], the largest
    # cell-mean pressure, between 0 and it
    g = 9.81
    bound = 5.0 * (RHO * g * HWATER + RHO * 2.0 * g * HWATER)
    pmax = max(row[h.index("ppoint")] for h, rows in blocks[1:] for row in rows)
    check(0.0 < pmax < bound, f"largest point pressure {pmax:.4g} Pa below 5 (rho g h + rho U^2) = {bound:.4g} Pa")
    cell_ok = all(row[h.index("fluid[10")] <= row[h.index("ppoint")] for h, rows in blocks[1:] for row in rows)
    check(cell_ok, "f_fluid[10] (largest cell-mean pressure) at most the largest single point pressure in every line")
    front = [row[fh.index("fluid[4]")] for row in fl]
    check(front[-1] > front[0], f"the water front moves after the gate opens ({front[0]:.4f} -> {front[-1]:.4f} m)")

    step, names, rows = last_dump(d)
    check(len(rows) == NBEADS, f"all {NBEADS} beads in the last dump (step {step}: {len(rows)})")
    check("f_dragforce[3]" in names, "the dump carries the fluid force f_dragforce[1..3]")
    check(all(math.isfinite(v) for row in rows for v in row), "every dump value finite")
    ix, iy, iz, ir = (names.index(c) for c in ("x", "y", "z", "radius"))
    # centre inside the box, and the walls' soft Hertz contact overlapping a bead by under 10 % of its radius
    over = max(max(row[ir] - row[ix], row[ix] - (L - row[ir]), row[ir] - row[iy], row[iy] - (W - row[ir]),
                   row[ir] - row[iz], row[iz] - (H - row[ir])) / row[ir] for row in rows)
    inside = all(0 <= row[ix] <= L and 0 <= row[iy] <= W and 0 <= row[iz] <= H for row in rows)
    check(inside and over < 0.1, f"every bead inside the box (largest wall overlap {max(over, 0):.3f} radius)")
    xmf = open(os.path.join(d, "water.xmf")).read() if os.path.exists(os.path.join(d, "water.xmf")) else ""
    nh5 = sum(1 for f in os.listdir(d) if f.startswith("water_") and f.endswith(".h5"))
    check(nh5 > 1 and xmf.count("<!-- mpm-step ") == nh5, f"water.xmf lists the {nh5} point files")

    # the picture tool, in the project's Python environment
    py = os.path.join(TOOLS, "python")
    env = subprocess.run([py, "-c", "import numpy, matplotlib, h5py"], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, timeout=900)
    if env.returncode != 0:
        print("SKIP  render_run.py: tools/python could not provide numpy, matplotlib and h5py "
              "(creating .venv needs PyPI):\n" + env.stdout[-600:])
    else:
        out = os.path.join(d, "starter.png")
        q = subprocess.run([py, os.path.join(TOOLS, "render_run.py"), d, "--out", out], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, timeout=300)
        print(q.stdout.strip())
        check(q.returncode == 0 and os.path.getsize(out) > 10000 if os.path.exists(out) else False,
              "render_run.py draws the run")
        check("%d points, %d grains" % (NPOINTS, NBEADS) in q.stdout,
              "render_run.py drew %d points and %d grains" % (NPOINTS, NBEADS))
        code = ("import sys, numpy as np, h5py, glob\n"
                "bad = [f'{p}:{k}' for p in glob.glob(sys.argv[1] + '/water_*.h5') for k in ('xyz', 'v', 'p', 'theta')"
                " if not np.isfinite(h5py.File(p, 'r')['points/' + k][()]).all()]\n"
                "print('non-finite:', bad)\nsys.exit(1 if bad else 0)\n")
        fin = subprocess.run([py, "-c", code, d], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        check(fin.returncode == 0, "every HDF5 point value finite (" + fin.stdout.strip() + ")")
    print(f"starter: {len(cases.FAILURES)} failed check(s)")
    return 1 if cases.FAILURES else 0


if __name__ == "__main__":
    sys.exit(main())
