#!/usr/bin/env python3
"""Grains held in still water feel exactly Archimedes' force (issue #13, acceptance 4): a random bed
(inputs/archimedes/in.bed, reduced) mid-depth and resting on the floor, with and without
theta_smooth; the fluid force on the grains against rho g sum V, a bound from the inputs alone.
The text's coupling (grad_p fit, reaction direct) is run too and must be off by more than the
tolerance, so that the case can tell the two apart (docs/background/well_balanced.md).

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
    for name, v in (("mid", {}), ("floor", {"floor": 1}), ("floor_smooth", {"floor": 1, "extra": "theta_smooth 0.004"})):
        q = ratio(r, name, **v)
        check(abs(q - 1.0) < TOL, f"{name}: within {TOL:.0%} of Archimedes ({q:.4f})")
    # the text's coupling on the floor: the check above can fail
    q = ratio(r, "floor_text", floor=1, extra="grad_p fit reaction direct")
    check(abs(q - 1.0) > TOL, f"text's coupling on the floor is off by more than {TOL:.0%} ({q:.4f})")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
