#!/usr/bin/env python3
"""Grains held in still water feel Archimedes' force (issue #13, acceptance 4): a random bed
(inputs/archimedes/in.bed, reduced), the fluid force on the grains against rho g sum V, a bound from
the inputs alone. Mid-depth with the default coupling, on the floor with grad_p weak (with and
without theta_smooth) within 2 %; the default on the floor closer than the text's coupling
(grad_p fit, reaction direct), which must be off by more than 2 % so that the case can tell them
apart (docs/background/well_balanced.md).

    test_archimedes.py CASE --exe build/liggghts_mpm --inputs inputs --work DIR [--mpirun "..."]
"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import check, driver_main  # noqa: E402

# reduced: 150 grains of 2 mm at solid fraction 0.3, cell 1.5 d, 0.05 s damped + 0.01 s averaged
SMALL = {"nbeads": 150, "tsettle": 0.05, "tavg": 0.01}
TOL = 0.02


def ratio(r, case, **v):
    d, p = r.run(f"archimedes/{case}", os.path.join(r.inputs, "archimedes", "in.bed"), dict(SMALL, **v))
    m = re.search(r"RESULT ratio (\S+) grains (\S+)", p.stdout)
    check(m is not None, f"{case}: result printed")
    if not m:
        return float("nan")
    q = float(m.group(1))
    print(f"  {case}: {int(float(m.group(2)))} grains, fluid force / Archimedes = {q:.4f}")
    return q


def case_bed(r):
    # default coupling (grad_p nodal, reaction points): balanced inside the fluid
    q = ratio(r, "mid", **{})
    check(abs(q - 1.0) < TOL, f"mid-depth, default coupling: within {TOL:.0%} of Archimedes ({q:.4f})")
    # on the floor only grad_p weak is balanced (the anti-locked pressure's staircase at the wall)
    for name, extra in (("floor_weak", "grad_p weak"), ("floor_weak_smooth", "grad_p weak theta_smooth 0.004")):
        q = ratio(r, name, floor=1, extra=extra)
        check(abs(q - 1.0) < TOL, f"{name}: within {TOL:.0%} of Archimedes ({q:.4f})")
    # the default on the floor is closer than the text's coupling, which this case can tell apart
    qd = ratio(r, "floor_default", floor=1)
    qt = ratio(r, "floor_text", floor=1, extra="grad_p fit reaction direct")
    check(abs(qt - 1.0) > TOL, f"text's coupling on the floor is off by more than {TOL:.0%} ({qt:.4f})")
    check(abs(qd - 1.0) < abs(qt - 1.0), f"default on the floor closer than the text's ({qd:.4f} vs {qt:.4f})")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
