#!/usr/bin/env python3
"""Momentum balance of a closed mesh tank in motion: do the mesh walls' loads (f_ID[20..22] of
fix mpm/fluid, `mesh_wall ... loads yes`) account for what the walls do to the water?

    tools/python tools/wall_load_balance.py --exe build/liggghts_mpm [--model projection|eos]
        [--dx 0.025] [--time 0.6] [--width 0.4] [--work DIR]

The scene is tests/data/in.mesh_walls_box (a closed box of side 0.3 m made of a LIGGGHTS wall
mesh, tests/data/box.stl, inside a larger grid) with the water as a column 0.12 m wide and 0.2 m
deep against one wall (--width 1: the whole floor, water at rest), released at t = 0 (a dam break inside the box; no grid damping, so the
mesh walls and gravity are the only outside forces on the water). The water's momentum P comes
from the points (sum of m v, LIGGGHTS' compute reduce), not from the loads; over the run

    P(t) - P(0) = M g t - integral of F dt,     F the water's force on the walls,

so the table compares the momentum change with the impulse gravity and the loads give. The
figure that matters is the gap relative to M g t (the impulse the walls must supply on average).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "tests", "data")


def make_input(model, width):
    s = open(os.path.join(DATA, "in.mesh_walls_box")).read()
    s = s.replace("transfer apic damping 20.0", "transfer apic")
    if model == "projection":
        s = s.replace("pressure eos bulk ${bulk} ", "")
    s = s.replace("timestep        ${tstep}", "timestep        ${dt}")
    s = s.replace("side ${fside}", "side ${fside} loads yes")
    s = s.replace("region          water block ${lo} ${hi} ${lo} ${hi} ${lo} ${top} units box",
                  f"variable xw equal ${{lo}}+{width}*${{side}}\n"
                  "region          water block ${lo} ${xw} ${lo} ${hi} ${lo} ${top} units box")
    s = s.replace("run             ${steps}\n",
                  "variable pxa atom mass*vx\nvariable pya atom mass*vy\nvariable pza atom mass*vz\n"
                  "compute  pp all reduce sum v_pxa v_pya v_pza\n"
                  "fix  mom all ave/time 1 1 1 c_pp[1] c_pp[2] c_pp[3] f_fluid[20] f_fluid[21] f_fluid[22] "
                  "file momentum.txt\n"
                  "run             ${steps}\n", 1)
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--exe", required=True)
    ap.add_argument("--model", choices=("projection", "eos"), default="projection")
    ap.add_argument("--dx", type=float, default=0.025)
    ap.add_argument("--time", type=float, default=0.6)
    ap.add_argument("--width", type=float, default=0.4,
                    help="the column's width as a fraction of the box (1: water at rest, the tool's own check)")
    ap.add_argument("--work", default="wall_load_balance")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    with open(os.path.join(a.work, "in.tank"), "w") as f:
        f.write(make_input(a.model, a.width))
    shutil.copy(os.path.join(DATA, "box.stl"), a.work)
    # eos: the weak water of the input (c = 14 m/s), a step within its acoustic limit
    dt = 1e-3 * a.dx / 0.025 if a.model == "projection" else 2e-4 * a.dx / 0.025
    steps = int(round(a.time / dt))
    cmd = [os.path.abspath(a.exe), "-in", "in.tank", "-echo", "none", "-var", "dx", str(a.dx), "-var", "fill", "0.2",
           "-var", "dt", repr(dt), "-var", "steps", str(steps)]
    p = subprocess.run(cmd, cwd=a.work, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"run failed:\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}")
    M = float(next(m.group(1) for m in (re.match(r"\s*0\s+0\s+(\S+)", ln) for ln in p.stdout.splitlines()) if m))
    d = np.loadtxt(os.path.join(a.work, "momentum.txt"))
    P, F = d[:, 1:4], d[:, 4:7]
    g = 9.81
    print(f"{a.model}, dx {a.dx} m, step {dt:g} s, {steps} steps; water mass M = {M:.4g} kg")
    print(f"{'t (s)':>7} {'dP_x':>9} {'J_x':>9} {'dP_z':>9} {'J_z':>9} {'gap_z / (M g t)':>16}")
    worst = 0.0
    for k in sorted({steps // 6, steps // 3, steps // 2, 2 * steps // 3, steps}):
        J = -F[1:k + 1].sum(axis=0) * dt
        J[2] -= M * g * k * dt
        dP = P[k] - P[0]
        rel = (dP[2] - J[2]) / (M * g * k * dt)
        worst = max(worst, abs(rel))
        print(f"{k * dt:7.3f} {dP[0]:9.4f} {J[0]:9.4f} {dP[2]:9.4f} {J[2]:9.4f} {rel:16.3%}")
    print(f"largest gap in z over the run: {worst:.2%} of M g t (acceptance: 1 %)")


if __name__ == "__main__":
    main()
