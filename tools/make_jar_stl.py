#!/usr/bin/env python3
"""Writes the STL mesh of a closed cylindrical jar (CASES.md C4, dissertation 10.3).

The jar is a cylinder of inner diameter D and depth L, axis along x, y or z,
centred at a given point; the mantle has N segments (2 triangles each) and each
end cap is a fan of N triangles around its centre, so the mesh has 4 N
triangles (N = 360: the 1440 triangles of the text). Normals point out of the
jar (the fluid is inside: use `mesh_wall ... side auto` or `side opposite`).
The polygon's flat segments are inside the circle of diameter D; the radius is
scaled by 1/cos(pi/N) so that they touch it at their midpoints when --inscribe
is not given.

  tools/python tools/make_jar_stl.py jar.stl [--diameter 0.1] [--depth 0.1]
        [--segments 360] [--axis y] [--centre 0 0 0] [--inscribe]
Standard library only.
"""
import argparse
import math
import sys


def jar_triangles(diameter, depth, segments, axis, centre, inscribe=False, caps="strip"):
    """List of (normal, (v1, v2, v3)) with outward normals, in the axis frame mapped to xyz."""
    r = 0.5 * diameter / (1.0 if inscribe else math.cos(math.pi / segments))
    h = 0.5 * depth
    # local frame: a = axial coordinate, (b, c) = cross-section
    order = {"x": (0, 1, 2), "y": (1, 2, 0), "z": (2, 0, 1)}[axis]

    def xyz(a, b, c):
        p = [0.0, 0.0, 0.0]
        p[order[0]], p[order[1]], p[order[2]] = a, b, c
        return tuple(p[k] + centre[k] for k in range(3))

    def vec(a, b, c):
        p = [0.0, 0.0, 0.0]
        p[order[0]], p[order[1]], p[order[2]] = a, b, c
        return tuple(p)

    tris = []
    ring = [(r * math.cos(2 * math.pi * k / segments), r * math.sin(2 * math.pi * k / segments))
            for k in range(segments)]
    for k in range(segments):
        (b0, c0), (b1, c1) = ring[k], ring[(k + 1) % segments]
        mid = math.pi * (2 * k + 1) / segments
        n = vec(0.0, math.cos(mid), math.sin(mid))
        p00, p01 = xyz(-h, b0, c0), xyz(-h, b1, c1)
        p10, p11 = xyz(h, b0, c0), xyz(h, b1, c1)
        tris.append((n, (p00, p01, p11)))
        tris.append((n, (p00, p11, p10)))
        if caps == "fan":
            # end caps: fans; winding so that the right-hand normal points outward
            tris.append((vec(-1.0, 0.0, 0.0), (xyz(-h, 0.0, 0.0), p01, p00)))
            tris.append((vec(1.0, 0.0, 0.0), (xyz(h, 0.0, 0.0), p10, p11)))
    if caps == "strip":
        # end caps: zig-zag strips of chords 0, 1, N-1, 2, N-2, ... (N - 2 triangles each, no
        # vertex shared by all of them, so a grid node near a cap is near few triangles)
        order_k = [0]
        lo, hi = 1, segments - 1
        while lo <= hi:
            order_k.append(lo)
            lo += 1
            if lo <= hi:
                order_k.append(hi)
                hi -= 1
        for a in (-h, h):
            for i in range(len(order_k) - 2):
                q = [ring[order_k[i + j]] for j in range(3)]
                # orient: normal along +a on the far cap, -a on the near one
                cross = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0])
                if (cross > 0) != (a > 0):
                    q[1], q[2] = q[2], q[1]
                tris.append((vec(1.0 if a > 0 else -1.0, 0.0, 0.0), tuple(xyz(a, b, c) for b, c in q)))
    return tris


def write_stl(path, tris, name="jar"):
    with open(path, "w") as f:
        f.write(f"solid {name}\n")
        for n, vs in tris:
            f.write(f" facet normal {n[0]:.9g} {n[1]:.9g} {n[2]:.9g}\n  outer loop\n")
            for v in vs:
                f.write(f"   vertex {v[0]:.9g} {v[1]:.9g} {v[2]:.9g}\n")
            f.write("  endloop\n endfacet\n")
        f.write(f"endsolid {name}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--diameter", type=float, default=0.1, help="inner diameter (m), default 0.1")
    ap.add_argument("--depth", type=float, default=0.1, help="inner depth (m), default 0.1")
    ap.add_argument("--segments", type=int, default=361,
                    help="segments around, default 361 (strip caps: 4 N - 4 = 1440 triangles; fan caps: 4 N)")
    ap.add_argument("--caps", choices=("strip", "fan"), default="strip",
                    help="end caps as zig-zag strips (default) or as fans around the centre")
    ap.add_argument("--axis", choices=("x", "y", "z"), default="y", help="jar axis, default y (horizontal)")
    ap.add_argument("--centre", type=float, nargs=3, default=(0.0, 0.0, 0.0))
    ap.add_argument("--inscribe", action="store_true", help="polygon corners on the circle (flats inside)")
    a = ap.parse_args()
    if a.diameter <= 0 or a.depth <= 0 or a.segments < 3:
        ap.error("--diameter and --depth must be > 0 and --segments >= 3")
    tris = jar_triangles(a.diameter, a.depth, a.segments, a.axis, a.centre, a.inscribe, a.caps)
    write_stl(a.out, tris)
    print(f"wrote {a.out}: {len(tris)} triangles, diameter {a.diameter} m, depth {a.depth} m, axis {a.axis}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
