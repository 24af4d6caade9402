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
Standard library only: tests/cases/test_wall_force.py (case tank_balance_*) runs balance() below.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

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


def balance(exe, model="projection", dx=0.025, time=0.6, width=0.4, work="wall_load_balance", mpirun=()):
    """Runs the tank and returns (M, dt, steps, rows): rows (t, dP, J, gap_z / (M g t)) at five times,
    dP the points' momentum change and J = gravity's impulse + the walls' (-integral of the loads)."""
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(work, "in.tank"), "w") as f:
        f.write(make_input(model, width))
    shutil.copy(os.path.join(DATA, "box.stl"), work)
    # eos: the weak water of the input (c = 14 m/s), a step within its acoustic limit
    dt = 1e-3 * dx / 0.025 if model == "projection" else 2e-4 * dx / 0.025
    steps = int(round(time / dt))
    cmd = list(mpirun) + [os.path.abspath(exe), "-in", "in.tank", "-echo", "none", "-var", "dx", str(dx),
                          "-var", "fill", "0.2", "-var", "dt", repr(dt), "-var", "steps", str(steps)]
    p = subprocess.run(cmd, cwd=work, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"run failed:\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}")
    M = float(next(m.group(1) for m in (re.match(r"\s*0\s+0\s+(\S+)", ln) for ln in p.stdout.splitlines()) if m))
    d = [[float(v) for v in ln.split()] for ln in open(os.path.join(work, "momentum.txt"))
         if ln.strip() and not ln.startswith("#")]
    P, F = [r[1:4] for r in d], [r[4:7] for r in d]
    g = 9.81
    rows = []
    for k in sorted({steps // 6, steps // 3, steps // 2, 2 * steps // 3, steps}):
        J = [-sum(F[s][c] for s in range(1, k + 1)) * dt for c in range(3)]
        J[2] -= M * g * k * dt
        dP = [P[k][c] - P[0][c] for c in range(3)]
        rows.append((k * dt, dP, J, (dP[2] - J[2]) / (M * g * k * dt)))
    return M, dt, steps, rows


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
    try:
        M, dt, steps, rows = balance(a.exe, a.model, a.dx, a.time, a.width, a.work)
    except RuntimeError as e:
        sys.exit(str(e))
    print(f"{a.model}, dx {a.dx} m, step {dt:g} s, {steps} steps; water mass M = {M:.4g} kg")
    print(f"{'t (s)':>7} {'dP_x':>9} {'J_x':>9} {'dP_z':>9} {'J_z':>9} {'gap_z / (M g t)':>16}")
    worst = 0.0
    for t, dP, J, rel in rows:
        worst = max(worst, abs(rel))
        print(f"{t:7.3f} {dP[0]:9.4f} {J[0]:9.4f} {dP[2]:9.4f} {J[2]:9.4f} {rel:16.3%}")
    print(f"largest gap in z over the run: {worst:.2%} of M g t (acceptance: 1 %)")


if __name__ == "__main__":
    main()
