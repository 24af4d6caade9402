#!/usr/bin/env python3
"""The pressure projection and the fluid step (docs/theory/projection.md, "The step size"): the
released column with flip creates no energy at its step.

    test_step_size.py CASE --exe build/liggghts_mpm --inputs inputs --work DIR --mpirun "mpirun ..."
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import check, driver_main, read_csv  # noqa: E402
from test_projection import inviscid_column_ke_rate  # noqa: E402


def column_ratios(r, dt):
    """Kinetic energy of the released column (Grid20, free-slip, transfer flip) over the inviscid
    early-time value at 0.01 and 0.02 s, fluid step dt."""
    rate = inviscid_column_ke_rate(0.05, 0.1, 0.1)
    d, _ = r.run(f"step_size_column/dt{dt:g}", os.path.join(r.inputs, "tank", "in.column"),
                 {"cells": 20, "pressure": "projection", "dt": dt, "wallkind": "freeslip",
                  "extra": "transfer flip 1"})
    s = read_csv(os.path.join(d, "column.csv"))
    out = []
    for t in (0.01, 0.02):
        i = min(range(len(s["t"])), key=lambda j: abs(s["t"][j] - t))
        out.append(s["ke"][i] / (rate * s["t"][i] ** 2))
    return out


def case_column(r):
    """The released column (inputs/tank/in.column, Grid20, free-slip walls, transfer flip, fluid step
    5e-5 s): at most 1.02 of the inviscid kinetic energy at 0.01 and 0.02 s. Measured 1.008 / 1.019;
    with the padding nodes' own P2G velocity in FLIP's increment 1.015 / 1.030. At a four times smaller
    step the transfer's divergence still adds energy (1.107 / 1.102): reported, not asserted
    (docs/theory/projection.md, "The step size")."""
    f = column_ratios(r, 5e-5)
    for t, a in zip((0.01, 0.02), f):
        print(f"  {t} s: kinetic energy / inviscid {a:.4f} (dt 5e-5 s)")
        check(a <= 1.02, f"{t} s: at most 1.02 of the inviscid kinetic energy (no energy from nothing)")
        check(a >= 0.9, f"{t} s: at least 0.9 of the inviscid kinetic energy")
    fine = column_ratios(r, 1.25e-5)
    print("  dt 1.25e-5 s: " + " / ".join(f"{a:.4f}" for a in fine) + " (not asserted)")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
