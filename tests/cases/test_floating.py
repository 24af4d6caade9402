#!/usr/bin/env python3
"""Grains at the free surface (default model): the fluid acts on the share of a grain's sphere that
lies below the surface, against bounds from the inputs alone (docs/theory/drag.md, "Grains at the
free surface").

held: one grain (d = 6 mm, cell 10 mm) held with its centre dz above the surface of water at rest
(tests/data/in.floating): the fluid's vertical force against f(dz) rho g V, f the share of a sphere
below a plane (the cap h = r - dz: h^2 (3 r - h) / (4 r^3)): within 2 % of Archimedes at r and 2 r
below, within 0.03 of f at 0 and +-r/2, below 0.01 at r and 2 r above (no force on a grain out of
the water); measured 0.9994 / 0.9991, 0.849 / 0.500 / 0.158 against 0.844 / 0.5 / 0.156, 0.001 / 0.000.
Without the immersion the grain took 0.8-1.0 of Archimedes up to 1.5 cells above the water.
held_mesh: the same water held by a wall mesh (the level read from the fill beside mesh walls;
measured 0.991 / 0.991, 0.870 / 0.527 / 0.176, 0.003 / 0.000, within 3 % of Archimedes in the bulk);
np2: held_mesh and held at dz = r/2 on 2 ranks (cut through the grain's cells) equal 1 rank.
free: 10 grains of density 500 released under the surface float up: their mean height over the
last 0.1 s within 2 mm (0.2 cells) of the surface hw + N m / (rho A); every grain in the water
(bottom below the surface) and out of it (top above); no water above the surface (measured 0.6 mm
below; before: every grain 10-13 mm above the water).

    test_floating.py CASE --exe build/liggghts_mpm --work DIR [--mpirun "..."]
"""
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import DATA, check, driver_main  # noqa: E402

R = 0.003  # grain radius (m)


def share(dz):
    """share of a sphere of radius R below a plane, its centre dz above it"""
    h = min(max(R - dz, 0.0), 2 * R)
    return h * h * (3 * R - h) / (4 * R ** 3)


def held(r, name, dz, np=1, **v):
    d, p = r.run(name, os.path.join(DATA, "in.floating"), dict(v, dz=dz), np=np,
                 extra_files=(os.path.join(DATA, "box.stl"),))
    m = re.search(r"RESULT dz \S+ ratio (\S+) fxy (\S+)", p.stdout)
    check(m is not None, f"{name}: result printed")
    if not m:
        return float("nan"), float("nan")
    q, fxy = float(m.group(1)), float(m.group(2))
    print(f"  {name}: dz {dz:+.4f} m, force / Archimedes {q:.4f} (share {share(dz):.4f}), sideways {fxy:.2e}")
    return q, fxy


def ladder(r, tag, full_tol, **v):
    for dz in (-2 * R, -R, -R / 2, 0.0, R / 2, R, 2 * R):
        q, fxy = held(r, f"{tag}_{dz:+.4f}", dz, **v)
        f = share(dz)
        if f == 1.0:
            check(abs(q - 1.0) < full_tol, f"{tag} dz {dz:+.4f}: within {full_tol:.0%} of Archimedes ({q:.4f})")
        elif f == 0.0:
            check(abs(q) < 0.01, f"{tag} dz {dz:+.4f}: out of the water, below 0.01 of Archimedes ({q:.4f})")
        else:
            check(abs(q - f) < 0.03, f"{tag} dz {dz:+.4f}: within 0.03 of the share {f:.4f} ({q:.4f})")
        check(fxy < 5e-3, f"{tag} dz {dz:+.4f}: sideways force below 0.5 % ({fxy:.2e})")


def case_held(r):
    """a grain held across the surface of water in a box of grid faces"""
    ladder(r, "held", 0.02)


def case_held_mesh(r):
    """the same in a box of a wall mesh"""
    # (a grain held mid-depth in this mesh box takes 0.98 of Archimedes with or without the
    # immersion: the mesh box's own error, measured at 1.2 and 2.5 cm depth)
    ladder(r, "held_mesh", 0.03, mesh=1)


def case_np2(r):
    """2 ranks equal 1, grid box and mesh box, grain across the rank cut"""
    for mesh in (0, 1):
        q1, _ = held(r, f"np1_mesh{mesh}", R / 2, mesh=mesh)
        q2, _ = held(r, f"np2_mesh{mesh}", R / 2, np=2, mesh=mesh)
        check(abs(q2 - q1) < 1e-9, f"mesh {mesh}: 2 ranks equal 1 ({q2:.12f} against {q1:.12f})")


def case_free(r):
    """light grains released under the surface float at it"""
    hw, rhob = 0.06, 500.0
    d, p = r.run("free", os.path.join(DATA, "in.floating_free"), {"rhob": rhob, "hw": hw})
    m = re.search(r"RESULT nb (\S+) zmean (\S+) zmin (\S+) zmax (\S+) wmax (\S+) mass (\S+)", p.stdout)
    check(m is not None, "free: result printed")
    if not m:
        return
    nb, zmean, zmin, zmax, wmax, mass = (float(x) for x in m.groups())
    # the surface: the water's depth raised by the volume the floating grains displace, N m / rho
    hs = hw + nb * mass / (1000.0 * 0.06 * 0.03)
    print(f"  {int(nb)} grains: mean centre {zmean:.5f} m, lowest {zmin:.5f}, highest {zmax:.5f}; "
          f"surface {hs:.5f} m; highest water point {wmax:.5f} m")
    check(nb == 10, f"10 grains inserted ({nb:g})")
    check(abs(zmean - hs) < 0.002, f"mean centre within 2 mm of the surface ({(zmean - hs) * 1e3:+.2f} mm)")
    check(zmax - R < hs, f"every grain in the water: the highest's bottom {(zmax - R - hs) * 1e3:+.2f} mm from the surface")
    check(zmin + R > hs, f"every grain afloat: the lowest's top {(zmin + R - hs) * 1e3:+.2f} mm from the surface")
    check(wmax < hs, f"no water above the surface (highest point {(wmax - hs) * 1e3:+.2f} mm from it)")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
