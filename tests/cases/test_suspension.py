#!/usr/bin/env python3
"""A uniform suspension settles at its drag law's hindered velocity:
inputs/suspension/in.suspension at reduced size, solid fraction 0.3, `pressure projection`. The
mean settling velocity of the grains of the middle region against the steady velocity of a
uniform suspension computed from the inputs alone (tools/suspension.py, docs/validation/suspension.md), and
no acoustic ringing: the velocity's deviation from its 10 ms running mean stays small.

    test_suspension.py CASE --exe build/liggghts_mpm --inputs inputs --work DIR [--mpirun "..."]
"""
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools"))
from cases import check, driver_main  # noqa: E402
import suspension  # noqa: E402

# reduced: 4 x 4 x 12 cells of 2 mm, about 880 grains at phi 0.3, 0.15 s after the release, the
# water damped (200 1/s) while the grains are held
SMALL = {"nxy": 4, "nsus": 12, "tend": 0.15, "damp": 200.0}
TOL = 0.07    # settling velocity / reference at this size: 1.010 measured with the grains on the
              # acceleration pressure (grain_pressure's default; 1.052-1.067 on the
              # multiplier), window 0.08-0.15 s after the release. The middle region holds about 260 grains: the count's
              # sampling scatter (about 2 %, hard spheres) moves the reference by about 4 %, so the 3 %
              # of the acceptance is checked at full size (docs/validation/suspension.md: 0.999-1.010), not here
RING = 0.1    # largest deviation of the velocity from its 10 ms running mean / v_ref: 0.033 measured here
              # (0.0017 measured here), eos 0.12-0.16 at phi 0.3, no dtheta_source 7-20 (full size)
PRING = 0.05  # the same for the largest pressure / its mean: 0.006 here; full size eos 1.7-4.0, projection 0.002-0.009


def settle(r, case, t1=0.08, **v):
    d, p = r.run(f"suspension/{case}", os.path.join(r.inputs, "suspension", "in.suspension"), dict(SMALL, **v))
    info = suspension.result_line(p.stdout)
    check(info is not None, f"{case}: result printed")
    if not info:
        return None
    csv = os.path.join(d, "suspension.csv")
    res = suspension.analyse(csv, 1.0, t1=t1)
    phi = suspension.phi_mid(res, info)  # solid fraction of the middle region over the window
    vref = suspension.reference(phi)[0]
    res = suspension.analyse(csv, vref, t1=t1)
    print(f"  {case}: {int(info['grains'])} grains, phi {info['phi']:.4f} (middle {phi:.4f}), v_ref "
          f"{1e3 * vref:.2f} mm/s, v/v_ref {res['ratio']:.4f}, ringing {res['ring']:.4f}, "
          f"largest |v|/v_ref {res['swing']:.3f}, pressure ringing {res['pring']:.4f}")
    return res


def case_projection(r):
    # the chosen options: dtheta_source yes (the default; without it the column rings at 60-120 Hz
    # and settles 2-4x too fast) and theta_smooth of one cell (without it the grains' own velocity
    # fluctuations grow and the suspension settles 12 % slow at phi 0.1); docs/validation/suspension.md
    res = settle(r, "projection_phi03", phi=0.3, pressure="projection", extra="transfer apic theta_smooth 0.002")
    if res is None:
        return
    check(abs(res["ratio"] - 1.0) < TOL, f"projection, phi 0.3: settles within {TOL:.0%} of the reference "
          f"({res['ratio']:.4f})")
    check(res["ring"] < RING, f"projection, phi 0.3: no ringing (deviation {res['ring']:.4f} < {RING} v_ref)")
    check(res["pring"] < PRING, f"projection, phi 0.3: no pressure ringing (deviation {res['pring']:.4f} < {PRING} "
          "of the mean largest pressure)")
    check(res["swing"] < 1.1, f"projection, phi 0.3: no overshoot (largest |v| {res['swing']:.3f} v_ref < 1.1)")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
