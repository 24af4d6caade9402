#!/usr/bin/env python3
"""Grains held in still water feel Archimedes' force: a random bed
(inputs/archimedes/in.bed, reduced), the fluid force on the grains against rho g sum V, a bound from
the inputs alone. With `pressure eos` and the standard model (the fluid's own nodal
gradient as its points see it, the reaction through the points) within 2 % mid-depth and resting on the floor, at
cells of 1.5 and 3 grain diameters (at 3 d the water is 3 cells deep: the bed lies within 1.5 cells
of the floor and of the free surface), with and without theta_smooth (measured 0.9963-1.0008,
docs/theory/projection.md "Archimedes with eos"). The dissertation's literal coupling (model yang2016) must
miss on the floor by more than 2 %, so that the case can tell the two apart.

    test_archimedes.py CASE --exe build/liggghts_mpm --inputs inputs --work DIR [--mpirun "..."]
"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import check, driver_main  # noqa: E402

# reduced: 150 grains of 2 mm at solid fraction 0.3, cell 1.5 d, 0.05 s damped (200 1/s) + 0.01 s
# averaged, pressure eos unless the case names another, APIC
SMALL = {"nbeads": 150, "tsettle": 0.05, "tavg": 0.01, "damp": 200.0, "pressure": "eos"}
TOL = 0.02


def ratio(r, case, **v):
    v = dict(SMALL, **v)
    v["extra"] = ("transfer apic " + v.get("extra", "")).strip()
    d, p = r.run(f"archimedes/{case}", os.path.join(r.inputs, "archimedes", "in.bed"), v)
    m = re.search(r"RESULT ratio (\S+) grains (\S+)", p.stdout)
    check(m is not None, f"{case}: result printed")
    if not m:
        return float("nan")
    q = float(m.group(1))
    print(f"  {case}: {int(float(m.group(2)))} grains, fluid force / Archimedes = {q:.4f}")
    return q


# cell 3 d: 600 grains asked (437 inserted), the bed as high as the 150 grains' at cell 1.5 d
CELL3 = {"nbeads": 600, "cellf": 3}
ROWS = [(f"{where}_{cell}{'_smooth' if sm else ''}", dict(v, floor=fl, **({"extra": "theta_smooth 0.004"} if sm else {})))
        for where, fl in (("mid", 0), ("floor", 1))
        for cell, v in (("c1.5", {}), ("c3", CELL3))
        for sm in (False, True)]


def rows(r, *names):
    for name, v in ROWS:
        if name in names:
            q = ratio(r, name, **v)
            check(abs(q - 1.0) < TOL, f"{name}: within {TOL:.0%} of Archimedes ({q:.4f})")


def case_bed_mid_c15(r):
    """default coupling, the bed mid-depth, cell 1.5 d"""
    rows(r, "mid_c1.5")


def case_bed_mid_c15_smooth(r):
    """default coupling, the bed mid-depth, cell 1.5 d, theta_smooth 0.004"""
    rows(r, "mid_c1.5_smooth")


def case_bed_mid_c3(r):
    """default coupling, the bed mid-depth (3 cells of water), cell 3 d, theta_smooth 0 / 0.004"""
    rows(r, "mid_c3", "mid_c3_smooth")


def case_bed_floor_c15(r):
    """default coupling, the bed on the floor, cell 1.5 d"""
    rows(r, "floor_c1.5")


def case_bed_floor_c15_smooth(r):
    """default coupling, the bed on the floor, cell 1.5 d, theta_smooth 0.004"""
    rows(r, "floor_c1.5_smooth")


def case_bed_floor_c3(r):
    """default coupling, the bed on the floor, cell 3 d, theta_smooth 0 / 0.004; and the text's
    coupling (model yang2016) there, which this case must tell apart"""
    rows(r, "floor_c3", "floor_c3_smooth")
    qt = ratio(r, "floor_c3_yang2016", floor=1, extra="model yang2016", **CELL3)
    check(abs(qt - 1.0) > TOL, f"model yang2016 on the floor at cell 3 d is off by more than {TOL:.0%} ({qt:.4f})")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
