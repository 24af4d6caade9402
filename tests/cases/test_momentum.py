#!/usr/bin/env python3
"""Momentum and kinetic energy of grains and water exchanging forces (tests/data/in.momentum,
docs/theory/projection.md "Momentum of grains and fluid"): 300 grains settle through water in a box
periodic in x and y, free-slip floor, frictionless contacts, a constant force fx on every grain.
Nothing else acts along x, so the x momentum of points + grains must be N fx t (a bound computed
from the inputs alone), and the kinetic energy gained since the release can be no more than the
work of gravity and fx (the code's own dissipation, drag and viscosity, only lowers it).

    test_momentum.py CASE --exe build/liggghts_mpm --inputs inputs --work DIR [--mpirun "..."]

Cases: eos (cells of 3 and 1.5 grain diameters: momentum within 1e-4 of the impulse, no energy
above the work), every (the fluid every 4 DEM steps, eos and projection), projection (cells of 3 diameters, and of 1.5 with theta_smooth of one cell: no
energy above the work, momentum within the bound measured for this build). The projection does not
meet 1e-4 (0.19 % at 3 diameters, 0.06 % at 1.5 with theta_smooth) nor is it stable at 1.5
diameters without theta_smooth or at 1 diameter with it (docs/theory/projection.md): those bounds are a
guard against regressions, not the target.
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from cases import DATA, check, driver_main, read_csv  # noqa: E402

TARGET = 1e-4        # |P - N fx t| / (N fx t), the conservation target (eos meets it)
# projection: measured 4.8e-3 (0.03 s) / 1.2e-3 (0.02 s) with the energy-stable surface (1.9e-3 /
# 6.2e-4 before it); guards, the target 1e-4 is not met (docs/theory/projection.md, "Momentum of grains and fluid")
PROJ_BOUND = {3.0: 1e-2, 1.5: 2e-3}


def run(r, name, cellf, pressure, tend, extra="", every=1):
    v = {"pressure": pressure, "cellf": cellf, "tend": tend, "outdt": 0.0025}
    if extra:
        v["extra"] = extra
    if every != 1:
        v["every"] = every
    d, _ = r.run(f"momentum/{name}", os.path.join(DATA, "in.momentum"), v)
    f = read_csv(os.path.join(d, "momentum.csv"))
    err, rise = 0.0, -1e300
    ke0 = f["ke_f"][0] + f["ke_g"][0]
    for i in range(1, len(f["t"])):
        p = f["px_f"][i] + f["px_g"][i] - (f["px_f"][0] + f["px_g"][0])
        err = max(err, abs(p - f["px_ref"][i]) / f["px_ref"][i])
        # energy gained beyond the work of the external forces, relative to that work
        rise = max(rise, (f["ke_f"][i] + f["ke_g"][i] - ke0 - f["wz"][i]) / f["wz"][i])
    print(f"  {name}: largest |P - N fx t| / (N fx t) {err:.3e}; largest (KE gained - work) / work {rise:+.3f}; "
          f"at the end KE {f['ke_f'][-1] + f['ke_g'][-1]:.3e} J, work {f['wz'][-1]:.3e} J, "
          f"largest point speed {f['vmax'][-1]:.4f} m/s")
    check(len(f["t"]) > 4, f"{name}: {len(f['t'])} output rows")
    return err, rise


def case_eos(r):
    for c in (3.0, 1.5):
        err, rise = run(r, f"eos_c{c:g}", c, "eos", 0.02)
        check(err < TARGET, f"eos, cells of {c:g} grain diameters: momentum within {TARGET:g} of the impulse ({err:.2e})")
        check(rise < 0.0, f"eos, cells of {c:g} diameters: kinetic energy gained below the work of gravity and fx")


def case_projection(r):
    for c, extra, tend in ((3.0, "", 0.03), (1.5, "theta_smooth 0.0015", 0.02)):
        err, rise = run(r, f"projection_c{c:g}", c, "projection", tend, extra)
        check(rise < 0.0, f"projection, cells of {c:g} diameters{' (' + extra + ')' if extra else ''}: kinetic "
              "energy gained below the work of gravity and fx")
        b = PROJ_BOUND[c]
        check(err < b, f"projection, cells of {c:g} diameters: momentum within {b:g} of the impulse ({err:.2e}; "
              f"the target {TARGET:g} is not met)")


def case_every(r):
    """every 4: the fluid step's force reaches the grains on each of the 4 DEM steps it covers. The
    rows fall on the last of those steps (in.momentum aligns them), where the grains have received
    the whole impulse the fluid gave up but the half of the last step's force that px_g adds: the
    momentum of fluid + grains equals N fx t to round-off with eos (measured 5e-14) and within the
    projection's own bound (measured 3.4e-3 at 0.02 s, as with every 1)."""
    err, rise = run(r, "eos_c3_every4", 3.0, "eos", 0.02, every=4)
    check(err < TARGET, f"eos, every 4: momentum within {TARGET:g} of the impulse ({err:.2e})")
    check(rise < 0.0, "eos, every 4: kinetic energy gained below the work of gravity and fx")
    err, rise = run(r, "projection_c3_every4", 3.0, "projection", 0.02, every=4)
    b = PROJ_BOUND[3.0]
    check(err < b, f"projection, every 4: momentum within {b:g} of the impulse ({err:.2e})")
    check(rise < 0.0, "projection, every 4: kinetic energy gained below the work of gravity and fx")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
