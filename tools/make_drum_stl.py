#!/usr/bin/env python3
"""Writes the STL mesh of a closed drum with lifter bars (inputs/drum, docs/drum.md).

The drum is the closed cylinder of tools/make_jar_stl.py (axis along y, mantle of N flat segments,
end caps as zig-zag strips, outward normals), with --lifters rectangular bars along the whole
length on the inside of the mantle. Lifter k stands at the angle phi_k = phase + k 360/n degrees in
the x-z plane, measured from +x towards +z about the drum axis: its top face is the plane at
distance R - height from the axis, its two sides the planes at +-width/2 from the radial line
through phi_k; the sides run from the top face to the mantle polygon. The lifter faces' normals
point into the bar (out of the drum's inside, like the mantle's and the caps'), so the one mesh is
a fluid wall with `mesh_wall ID ... side opposite` and a wall for the beads (fix wall/gran).
The bar's end faces lie in the caps' planes and are covered by them; the mantle runs on under the
bars (neither beads nor fluid reach it there).

  tools/python tools/make_drum_stl.py drum.stl [--diameter 0.16] [--length 0.04] [--segments 72]
        [--lifters 6] [--height 0.008] [--width 0.008] [--phase 90] [--centre 0.08 0.02 0.08]
Standard library only.
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_jar_stl import jar_triangles, write_stl  # noqa: E402


def lifter_triangles(diameter, length, segments, n, height, width, phase_deg, centre):
    """Faces (2 triangles each: top and two sides) of n lifter bars, normals into the bars."""
    r = 0.5 * diameter
    rpoly = r / math.cos(math.pi / segments)  # corners of the circumscribed mantle polygon
    s_top = r - height
    s_out = rpoly  # the sides reach (just beyond) the mantle polygon
    cx, cy, cz = centre
    y0, y1 = cy - 0.5 * length, cy + 0.5 * length
    tris = []

    def rect(p, q, nrm):
        """Two triangles of the rectangle with edge p-q (in x-z) extruded from y0 to y1, wound so
        that the right-hand normal is nrm (x, z)."""
        a, b = (p[0], y0, p[1]), (q[0], y0, q[1])
        c, d = (q[0], y1, q[1]), (p[0], y1, p[1])
        # right-hand normal of (a, b, c): (b - a) x (c - b)
        e1 = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
        e2 = (c[0] - b[0], c[1] - b[1], c[2] - b[2])
        cr = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        nv = (nrm[0], 0.0, nrm[1])
        if cr[0] * nv[0] + cr[2] * nv[2] < 0:
            a, b, c, d = b, a, d, c
        tris.append((nv, (a, b, c)))
        tris.append((nv, (a, c, d)))

    for k in range(n):
        phi = math.radians(phase_deg + 360.0 * k / n)
        e = (math.cos(phi), math.sin(phi))   # radial direction in (x, z)
        t = (-math.sin(phi), math.cos(phi))  # tangential direction in (x, z)

        def pt(s, l):
            return (cx + s * e[0] + l * t[0], cz + s * e[1] + l * t[1])

        h = 0.5 * width
        rect(pt(s_top, -h), pt(s_top, h), e)                 # top face, normal outwards (into the bar)
        rect(pt(s_top, h), pt(s_out, h), (-t[0], -t[1]))     # side at +w/2, normal towards the bar's middle
        rect(pt(s_top, -h), pt(s_out, -h), t)                # side at -w/2
    return tris


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--diameter", type=float, default=0.16, help="inner diameter of the mantle (m), default 0.16")
    ap.add_argument("--length", type=float, default=0.04, help="inner length between the end caps (m), default 0.04")
    ap.add_argument("--segments", type=int, default=72,
                    help="flat segments of the mantle, default 72 (5 degrees; the flats touch the circle, the corners lie 0.08 mm outside it)")
    ap.add_argument("--lifters", type=int, default=6, help="number of lifter bars, default 6 (0: none)")
    ap.add_argument("--height", type=float, default=0.008, help="lifter height from the mantle (m), default 0.008")
    ap.add_argument("--width", type=float, default=0.008, help="lifter width (m), default 0.008")
    ap.add_argument("--phase", type=float, default=90.0,
                    help="angle of the first lifter in the x-z plane from +x towards +z (degrees), default 90")
    ap.add_argument("--centre", type=float, nargs=3, default=None,
                    help="centre of the drum, default (D/2, L/2, D/2)")
    a = ap.parse_args()
    if a.diameter <= 0 or a.length <= 0 or a.segments < 8:
        ap.error(f"--diameter and --length must be > 0 and --segments >= 8 (given {a.diameter}, {a.length}, {a.segments})")
    if a.lifters < 0 or (a.lifters > 0 and not (0 < a.height < 0.5 * a.diameter and 0 < a.width < a.diameter)):
        ap.error(f"--lifters >= 0, with 0 < --height < D/2 and 0 < --width < D "
                 f"(given {a.lifters}, {a.height}, {a.width})")
    if a.lifters > 0:
        # neighbouring bars must not overlap at their tops
        gap = 2 * (0.5 * a.diameter - a.height) * math.sin(math.pi / a.lifters) - a.width
        if gap <= 0:
            ap.error(f"--lifters {a.lifters} bars of width {a.width} m overlap at radius {0.5 * a.diameter - a.height} m")
    centre = a.centre if a.centre is not None else (0.5 * a.diameter, 0.5 * a.length, 0.5 * a.diameter)
    tris = jar_triangles(a.diameter, a.length, a.segments, "y", centre)
    tris += lifter_triangles(a.diameter, a.length, a.segments, a.lifters, a.height, a.width, a.phase, centre)
    write_stl(a.out, tris, name="drum")
    print(f"wrote {a.out}: {len(tris)} triangles, diameter {a.diameter} m, length {a.length} m, "
          f"{a.lifters} lifters {a.height} x {a.width} m, axis y through ({centre[0]}, {centre[2]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
