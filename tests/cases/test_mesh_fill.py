#!/usr/bin/env python3
"""Whole-program tests of `fill region-ID nx ny nz type T inside mesh-ID [outside mesh-ID ...]` of
fix mpm/fluid (docs/fix_mpm_fluid.md, keyword `fill`): the drum of inputs/drum (drum.stl
of tools/make_drum_stl.py with its defaults: inner diameter 0.16 m, length 0.04 m, 72 mantle
segments circumscribing the circle, 6 lifter bars 8 x 8 mm), filled below h = 0.065 m with cells of
5 mm and 2 x 2 x 2 points per cell (spacing s = 2.5 mm), at rest (run 0). The fill takes the
lattice points inside the mesh, as a region's fill takes those inside the region; a point within
g = s / 1000 of a triangle is neither inside nor outside and is left out.
Standard library only.

    test_mesh_fill.py CASE --exe build/liggghts_mpm --work DIR [--mpirun "mpirun ..."]

CASE is one of: inside, outside, regions, inside_np2, bad_input.

References, from the drum's outline alone (make_drum_stl.outline, the polygon its mesh extrudes):
  * the inside volume below h: the outline clipped to z < h (shoelace) times the length. Each point
    stands for a cube s^3. The caps (y = 0 and L) and h lie on faces of the points' lattice, so
    they cost no volume; along the mantle and the bars the lattice's cubes cross the wall, and
    the points inside sample the inside without a bias: V_fill = V_exact to the lattice's
    sampling error, which is below 1 % here (tolerance; P_w s L, P_w the wetted perimeter, is
    the volume of one row of points along the wall: 9.0 % of V_exact; -0.08 % measured).
  * the points themselves: a lattice point (x, z) below h is filled exactly when it lies inside the
    outline (2-D parity, computed here) and at least g from each of its edges (the caps are s/2
    away from every point of the lattice): the count must equal this prediction times the points
    along y; no point outside the mantle polygon or inside a bar.
  * outside: the points below h outside the drum (the grid's corners) are the lattice points
    outside the outline and at least g from it, the same prediction.
  * regions: the same inside built from plane regions (a cylinder of radius R and three planes
    per lifter) gives the count it gives; the mesh fill is compared with it (reported; the polygon
    mantle lies outside the cylinder, so the mesh fill holds slightly more).
"""
import math
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "data")
ROOT = os.path.join(HERE, "..", "..")
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(ROOT, "tools"))
import cases  # noqa: E402
from cases import check  # noqa: E402
from make_drum_stl import outline  # noqa: E402

D, L, H, DX, PPC = 0.16, 0.04, 0.065, 0.005, 2
XC = ZC = 0.5 * D
S = DX / PPC
G = 1e-3 * S


def poly_abs():
    """The drum's outline (make_drum_stl defaults) in absolute x, z."""
    return [(XC + x, ZC + z) for x, z in outline(D, 72, 6, 0.008, 0.008, 90.0)]


def clip_below(poly, h):
    """Sutherland-Hodgman: the polygon cut to z < h."""
    out = []
    for i in range(len(poly)):
        a, b = poly[i - 1], poly[i]
        ain, bin_ = a[1] < h, b[1] < h
        if ain != bin_:
            t = (h - a[1]) / (b[1] - a[1])
            out.append((a[0] + t * (b[0] - a[0]), h))
        if bin_:
            out.append(b)
    return out


def area(poly):
    return 0.5 * abs(sum(poly[i - 1][0] * poly[i][1] - poly[i][0] * poly[i - 1][1] for i in range(len(poly))))


def wetted_perimeter(poly, h):
    """Length of the outline below h (the clipped polygon's edges off the line z = h)."""
    c = clip_below(poly, h)
    tot = 0.0
    for i in range(len(c)):
        a, b = c[i - 1], c[i]
        if abs(a[1] - h) < 1e-12 and abs(b[1] - h) < 1e-12:
            continue
        tot += math.hypot(b[0] - a[0], b[1] - a[1])
    return tot


def inside2d(poly, x, z):
    n, c = len(poly), False
    for i in range(n):
        (ax, az), (bx, bz) = poly[i - 1], poly[i]
        if (az > z) != (bz > z) and x < ax + (z - az) * (bx - ax) / (bz - az):
            c = not c
    return c


def dist2d(poly, x, z):
    best = float("inf")
    for i in range(len(poly)):
        (ax, az), (bx, bz) = poly[i - 1], poly[i]
        ex, ez = bx - ax, bz - az
        u = max(0.0, min(1.0, ((x - ax) * ex + (z - az) * ez) / (ex * ex + ez * ez)))
        best = min(best, math.hypot(x - ax - u * ex, z - az - u * ez))
    return best


def predicted(poly, inside):
    """Lattice points (x, z) below H in the grid [0, D]^2 that the fill must create, per y row."""
    n = round(D / S)
    count = 0
    for k in range(n):
        z = (k + 0.5) * S
        if z >= H:
            break
        for i in range(n):
            x = (i + 0.5) * S
            if inside2d(poly, x, z) == inside and dist2d(poly, x, z) >= G * (1 - 1e-6):
                count += 1
    return count


def read_points(d):
    text = open(os.path.join(d, "pts.dump")).read().split("ITEM: TIMESTEP")[-1].splitlines()
    start = next(i for i, ln in enumerate(text) if ln.startswith("ITEM: ATOMS")) + 1
    return sorted(tuple(float(v) for v in ln.split()[1:4]) for ln in text[start:] if ln.strip())


class Runner(cases.Runner):
    def drum(self, case, mode, np=1, expect_ok=True):
        d = self.fresh(case)
        shutil.copy(os.path.join(DATA, "in.mesh_fill_drum"), d)
        subprocess.run([sys.executable, os.path.join(ROOT, "tools", "make_drum_stl.py"), os.path.join(d, "drum.stl")],
                       check=True, stdout=subprocess.DEVNULL)
        p = self.execute(d, "in.mesh_fill_drum", {"mode": mode, "h": H, "dx": DX, "ppc": PPC}, np=np,
                         expect_ok=expect_ok)
        return d, p


def check_points(pts, poly, inside, label):
    bad_side = sum(1 for x, y, z in pts if inside2d(poly, x, z) != inside)
    near = min(dist2d(poly, x, z) for x, y, z in pts)
    ys = [y for _, y, _ in pts]
    print(f"  {label}: {len(pts)} points, {bad_side} on the wrong side of the outline, nearest to the outline "
          f"{near * 1e3:.4f} mm (g {G * 1e3:.4f} mm), y in [{min(ys):.6g}, {max(ys):.6g}]")
    check(bad_side == 0, f"{label}: no point on the wrong side of the mantle polygon and the bars")
    check(near >= G * (1 - 1e-6), f"{label}: every point at least s / 1000 from the mantle and the bars")
    check(min(ys) >= 0.5 * S * (1 - 1e-6) and max(ys) <= L - 0.5 * S * (1 - 1e-6),
          f"{label}: every point at least s/2 from the caps")
    check(max(z for _, _, z in pts) < H, f"{label}: every point below h")


def case_inside(r):
    """inside: volume against the drum's geometry, the points against an independent prediction."""
    d, _ = r.drum("drum", "inside")
    pts = read_points(d)
    poly = poly_abs()
    n = len(pts)
    vfill = n * S ** 3
    vexact = area(clip_below(poly, H)) * L
    pw = wetted_perimeter(poly, H)
    print(f"  V_fill = {vfill:.6e} m3 ({n} points of {S} m), V_exact = {vexact:.6e} m3 (outline below h times L), "
          f"V_fill / V_exact - 1 = {vfill / vexact - 1:+.4%}; one row of points along the wetted wall "
          f"(P_w s L, P_w = {pw:.5f} m) {pw * S * L / vexact:.4%} of V_exact")
    check(abs(vfill / vexact - 1) < 0.01, "fill volume within 1 % of the exact inside volume")
    pred = predicted(poly, True) * round(L / S)
    print(f"  predicted from the outline: {pred} points")
    check(n == pred, f"point count equals the independent prediction ({n} vs {pred})")
    check_points(pts, poly, True, "inside")
    mass = float(open(os.path.join(d, "mesh_fill.txt")).read().split("mass =")[1].split()[0])
    check(abs(mass - 1000.0 * vfill) < 1e-9 * mass, f"fluid mass f_ID[1] = rho0 V_fill ({mass:.6g} kg)")


def case_outside(r):
    """outside: the grid's corners below h, outside the drum mesh, against the same prediction."""
    d, _ = r.drum("outside", "outside")
    pts = read_points(d)
    poly = poly_abs()
    pred = predicted(poly, False) * round(L / S)
    print(f"  {len(pts)} points, predicted {pred}")
    check(len(pts) == pred, f"point count equals the independent prediction ({len(pts)} vs {pred})")
    check_points(pts, poly, False, "outside")


def case_regions(r):
    """inputs/drum/in.drum's plane regions against 'inside drum': the water volume of each."""
    d1, _ = r.drum("regions_mesh", "inside")
    d2, _ = r.drum("regions_planes", "regions")
    n1, n2 = len(read_points(d1)), len(read_points(d2))
    vexact = area(clip_below(poly_abs(), H)) * L
    print(f"  inside drum: {n1} points ({n1 * S ** 3 / vexact:.4f} of V_exact); plane regions: {n2} points "
          f"({n2 * S ** 3 / vexact:.4f}); mesh / regions - 1 = {n1 / n2 - 1:+.4%}")
    check(n1 >= n2, "the mesh fill holds at least the points of the plane regions (its mantle polygon lies outside "
                    "their cylinder)")
    check(abs(n1 / n2 - 1) < 0.01, "the two fills' water volumes within 1 %")
    check_points(read_points(d2), poly_abs(), True, "regions")


def case_inside_np2(r):
    """inside on 2 ranks: the same points as on 1."""
    d1, _ = r.drum("np1", "inside")
    d2, _ = r.drum("np2", "inside", np=2)
    p1, p2 = read_points(d1), read_points(d2)
    diff = max((max(abs(a - b) for a, b in zip(u, v)) for u, v in zip(p1, p2)), default=0.0)
    print(f"  np 1: {len(p1)} points, np 2: {len(p2)} points, largest position difference {diff:.3g} m")
    check(len(p1) == len(p2), "np 2 creates as many points as np 1")
    check(diff < 1e-12, "np 2 creates the points of np 1")


BASE = """atom_style sphere
atom_modify map array sort 0 0
boundary f f f
units si
region box block 0 1 0 1 0 1 units box
create_box 2 box
neighbor 0.01 bin
region water block 0 1 0 1 0 0.5 units box
fix grav all gravity 9.81 vector 0 0 -1
"""


def write_plate(path):
    """An open mesh: one square of two triangles."""
    with open(path, "w") as f:
        f.write("solid plate\n")
        a, b, c, e = (0.2, 0.2, 0.3), (0.8, 0.2, 0.3), (0.8, 0.8, 0.3), (0.2, 0.8, 0.3)
        for t in ((a, b, c), (a, c, e)):
            f.write(" facet normal 0 0 1\n  outer loop\n")
            for p in t:
                f.write(f"   vertex {p[0]} {p[1]} {p[2]}\n")
            f.write("  endloop\n endfacet\n")
        f.write("endsolid plate\n")


def case_bad_input(r):
    """fill inside/outside refuses a missing fix, a fix that is no mesh and an open mesh."""
    fix = "fix fluid all mpm/fluid cell 0.1 density 1000 fill water 2 2 2 type 1 "
    for case, words, needles in [
        ("no_fix", "inside nosuch", ["keyword 'fill inside' expects the ID of a fix mesh/surface", "got 'nosuch'",
                                     "no such fix"]),
        ("not_mesh", "outside grav", ["keyword 'fill outside' expects the ID of a fix mesh/surface of triangles",
                                      "got 'grav'", "fix gravity"]),
        ("open", "inside plate", ["keyword 'fill inside' expects a closed mesh", "got 'plate'", "not closed",
                                  "4 belong to one triangle only"]),
    ]:
        d = r.fresh(f"bad_{case}")
        write_plate(os.path.join(d, "plate.stl"))
        with open(os.path.join(d, "in.script"), "w") as f:
            f.write(BASE + "fix plate all mesh/surface file plate.stl type 2\n" + fix + words + "\nrun 1\n")
        p = r.execute(d, "in.script", expect_ok=False, timeout=60)
        msg = next((ln for ln in p.stdout.splitlines() if "ERROR" in ln), "")
        check(p.returncode != 0 and all(n in msg for n in ["ERROR", "Fix mpm/fluid"] + needles),
              f"{case} (got: {msg.strip()[:200]})")


if __name__ == "__main__":
    sys.exit(cases.driver_main(globals()))
