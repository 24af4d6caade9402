#!/usr/bin/env python3
"""The water's volume over a run from the fix's HDF5 point files: the points' mass spread on the
grid nodes by the quadratic B-spline (as the fix's P2G does), read where the water is deep (every
node of the 3 x 3 x 3 block around the node holding at least `--deep` of a full cell, away from the
walls). A point keeps its mass, so the water's volume is its mass over its density, and its density
relative to rest is the mean fill of those nodes: the volume relative to the first file is the first
file's mean fill over this file's. Also the occupied cells (cells holding a point) and the highest
point, and with --rest AXIS C1 C2 R (a horizontal cylinder, z up: the jar) the volume the points'
mean height gives when the water is at rest, a circular segment whose centroid is that height;
with --length L as well, the segment below the level at rest (where the fill averaged over the
columns across the middle 0.6 R falls through 1/2) times L over the points' own volume, and the
points within one cell of the mantle's lower half over an even fill's (the wall shell).

    tools/python tools/water_volume.py RUNDIR --prefix jar --dx 0.005556 --ppc 1 \
        [--origin 0 0 0] [--cylinder AXIS C1 C2 R] [--box LO HI LO HI LO HI] [--deep 0.9] [--rest AXIS C1 C2 R [--length L]] [--csv out.csv]

Equal point masses are assumed (a fluid filled without grains, one point spacing everywhere):
with grains the fill's masses differ from point to point and are not in the files. --cylinder
(the jar): nodes farther than R - 2 dx from the axis (AXIS x, y or z through C1 C2 in the other
two coordinates) are not read; --box: nodes closer than 2 dx to these planes are not read.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mpm_io import h5_series, read_points, write_rows  # noqa: E402


def bspline2(r):
    """Quadratic B-spline of the offset r (cells)."""
    a = np.abs(r)
    return np.where(a < 0.5, 0.75 - a * a, np.where(a < 1.5, 0.5 * (1.5 - a) ** 2, 0.0))


def node_fill(xyz, dx, origin, ppc):
    """{node index (i, j, k): fill} of points of equal mass, ppc^3 of them per full cell."""
    rel = (xyz - origin) / dx
    base = np.floor(rel - 0.5).astype(int)  # lowest node of each point's 3-node stencil
    w = [[bspline2(rel[:, d] - (base[:, d] + a)) for a in range(3)] for d in range(3)]
    keys, vals = [], []
    for a in range(3):
        for b in range(3):
            for c in range(3):
                keys.append(base + np.array([a, b, c]))
                vals.append(w[0][a] * w[1][b] * w[2][c] / ppc ** 3)
    uniq, inv = np.unique(np.concatenate(keys), axis=0, return_inverse=True)
    s = np.bincount(inv.ravel(), weights=np.concatenate(vals))
    return dict(zip(map(tuple, uniq), s))


def deep_fill(fill, dx, origin, deep, keep):
    """Mean fill of the nodes whose 3 x 3 x 3 block all hold at least `deep` and that keep(x) allows;
    (mean, count)."""
    vals = []
    offs = [(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)]
    for (i, j, k), f in fill.items():
        if f < deep:
            continue
        x = origin + dx * np.array([i, j, k], dtype=float)
        if not keep(x):
            continue
        if all(fill.get((i + a, j + b, k + c), 0.0) >= deep for a, b, c in offs):
            vals.append(f)
    return (float(np.mean(vals)) if vals else float("nan")), len(vals)


def cylinder(spec):
    """AXIS C1 C2 R (--cylinder, --rest) as (axis index, the two other indices in the order x, y,
    z, C1, C2, R)."""
    ax = "xyz".index(spec[0])
    return ax, [d for d in range(3) if d != ax], float(spec[1]), float(spec[2]), float(spec[3])


def segment_area(zs, zc, R, n=4000):
    """Area and centroid height of the part of a disc (centre height zc, radius R) below z = zs."""
    z = np.linspace(zc - R, min(zs, zc + R), n)
    w = 2.0 * np.sqrt(np.maximum(R * R - (z - zc) ** 2, 0.0))
    a = np.trapezoid(w, z)
    return a, (np.trapezoid(w * z, z) / a if a > 0 else zc - R)


def rest_area(zmean, zc, R):
    """The segment area whose centroid height is zmean (bisection on the surface height)."""
    lo, hi = zc - R, zc + R
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if segment_area(mid, zc, R)[1] < zmean:
            lo = mid
        else:
            hi = mid
    return segment_area(0.5 * (lo + hi), zc, R)[0]


def level_ratio(fill, npoints, dx, origin, ppc, cyl, length):
    """The segment below the level at rest times the jar's length, over the points' own volume
    (one point spacing everywhere: npoints (dx / ppc)^3); fill: node_fill of the points. The level
    is where the fill, averaged over the
    node columns across the middle 0.6 R of the jar (2 dx off the end caps), falls through 1/2:
    the expected fill of points of any arrangement is the B-spline's convolution of the water's
    indicator, which is 1/2 on a plane surface, so the mean over many columns finds the surface
    without a lattice. (The highest point of each column plus half a spacing, exact for a lattice,
    lies low for disordered points: points placed at random in the jar's segment below a plane
    read 0.908 by it against 0.994, the profile 0.974; in the water-only jar after 25 turns it read
    0.98-1.01 where the profile reads 1.066 and the points missing within one cell of the mantle
    are 7 % of the water.) cyl: cylinder() of --rest; the jar's axis is horizontal, z up: C1 and
    C2 are the centre's coordinates across it in the order x, y, z."""
    ax, other, c1, c2, R = cyl
    centre = dict(zip(other, (c1, c2)))
    horiz = next(d for d in centre if d != 2)  # the horizontal coordinate across the axis
    cols, layer = set(), {}
    for idx, f in fill.items():
        x_h, x_a = origin[horiz] + idx[horiz] * dx, origin[ax] + idx[ax] * dx
        if abs(x_h - centre[horiz]) > 0.6 * R or not (2 * dx < x_a - origin[ax] < length - 2 * dx):
            continue
        cols.add((idx[horiz], idx[ax]))
        layer[idx[2]] = layer.get(idx[2], 0.0) + f
    ks = sorted(layer)
    mean = {k: layer[k] / len(cols) for k in ks}
    level = None
    for k in range(ks[-1], ks[0], -1):  # from the top down: the first fall through 1/2
        hi, lo = mean.get(k, 0.0), mean.get(k - 1, 0.0)
        if hi < 0.5 <= lo:
            level = origin[2] + (k - 1 + (lo - 0.5) / (lo - hi)) * dx
            break
    if level is None:
        return float("nan")
    return segment_area(level, centre[2], R)[0] * length / (npoints * (dx / ppc) ** 3)


def wall_shell_share(xyz, dx, ppc, cyl):
    """Points within one cell of the mantle of a horizontal cylinder (axis AXIS through C1 C2, as
    --rest: C2 the centre's height, radius R) below its centre height, over the number an even fill of the half shell holds,
    pi (R^2 - (R - dx)^2) / 2 * length / (dx / ppc)^3 per unit length (the length: the points'
    extent along the axis): 1 for water filled up to the mantle, lower where the points left a
    layer along it. cyl: cylinder() of --rest."""
    ax, other, c1, c2, R = cyl
    r = np.hypot(xyz[:, other[0]] - c1, xyz[:, other[1]] - c2)
    below = xyz[:, 2] < c2
    n = int(np.sum((r > R - dx) & below))
    length = float(np.ptp(xyz[:, ax])) + dx / ppc
    even = 0.5 * np.pi * (R * R - (R - dx) ** 2) * length / (dx / ppc) ** 3
    return n / even


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rundir")
    ap.add_argument("--prefix", default="jar")
    ap.add_argument("--dx", type=float, required=True)
    ap.add_argument("--ppc", type=int, default=1)
    ap.add_argument("--origin", type=float, nargs=3, default=[0.0, 0.0, 0.0])
    ap.add_argument("--cylinder", nargs=4, default=None, metavar=("AXIS", "C1", "C2", "R"))
    ap.add_argument("--box", type=float, nargs=6, default=None)
    ap.add_argument("--deep", type=float, default=0.9)
    ap.add_argument("--rest", nargs=4, default=None, metavar=("AXIS", "C1", "C2", "R"))
    ap.add_argument("--length", type=float, default=None,
                    help="with --rest: the jar's length along its axis; adds the level at rest over the points' volume")
    ap.add_argument("--csv", default=None)
    a = ap.parse_args()
    origin = np.array(a.origin)
    dx = a.dx
    keep_cyl = cylinder(a.cylinder) if a.cylinder else None
    rest = cylinder(a.rest) if a.rest else None

    def keep(x):
        if keep_cyl:
            _, other, c1, c2, R = keep_cyl
            if np.hypot(x[other[0]] - c1, x[other[1]] - c2) > R - 2.0 * dx:
                return False
        if a.box:
            for d in range(3):
                if x[d] < a.box[2 * d] + 2.0 * dx or x[d] > a.box[2 * d + 1] - 2.0 * dx:
                    return False
        return True

    rows = []
    first = None
    first_area = None
    for t, path in h5_series(a.rundir, a.prefix):
        xyz, _, _ = read_points(path)
        fill = node_fill(xyz, dx, origin, a.ppc)
        mean, count = deep_fill(fill, dx, origin, a.deep, keep)
        occ = len({tuple(q) for q in np.floor((xyz - origin) / dx).astype(int)})
        if first is None:
            first = mean
        row = {"t": t, "points": len(xyz), "deep_nodes": count, "deep_fill": mean,
               "volume_ratio": first / mean, "occupied_cells": occ, "z_max": float(xyz[:, 2].max())}
        extra = ""
        if rest:
            area = rest_area(float(xyz[:, 2].mean()), rest[3], rest[4])
            if first_area is None:
                first_area = area
            row["rest_volume_ratio"] = area / first_area
            extra = f"  at rest: volume / first {area / first_area:.5f}"
            if a.length:
                lev = level_ratio(fill, len(xyz), dx, origin, a.ppc, rest, a.length)
                row["level_over_points"] = lev
                shell = wall_shell_share(xyz, dx, a.ppc, rest)
                row["wall_shell"] = shell
                extra += f"  level / points' volume {lev:.5f}  wall shell {shell:.3f}"
        rows.append(row)
        print(f"t {t:8.4f}  deep nodes {count:5d}  fill {mean:.5f}  volume / first {first / mean:.5f}  "
              f"occupied cells {occ}  highest point {row['z_max']:.5f} m" + extra, flush=True)
    if a.csv:
        write_rows(a.csv, rows)


if __name__ == "__main__":
    main()
