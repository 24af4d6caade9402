#!/usr/bin/env python3
"""Writes the STL mesh of a closed drum with lifter bars (inputs/drum, docs/validation/drum.md).

The drum's axis is along y. Its cross-section (x-z plane) is the polygon of N flat segments
circumscribing the circle of the inner diameter (as tools/make_jar_stl.py's jar), with --lifters
rectangular notches: lifter k stands at the angle phi_k = phase + k 360/n degrees, measured from +x
towards +z about the axis; its top face is the line at distance R - height from the axis, its two
sides the lines at +-width/2 from the radial line through phi_k, down to the mantle polygon. The
outline is extruded over the length (mantle and bar faces, 2 triangles per edge) and triangulated
for the two end caps (ear clipping, the fattest ear first). The mesh is closed (every edge shared
by two triangles) with normals out of the drum's inside: a fluid wall with `mesh_wall ID ...
side opposite` and a wall for the beads (fix wall/gran).

  tools/python tools/make_drum_stl.py drum.stl [--diameter 0.16] [--length 0.04] [--segments 72]
        [--lifters 6] [--height 0.008] [--width 0.008] [--phase 90] [--centre 0.08 0.02 0.08]
Standard library only.
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_jar_stl import write_stl  # noqa: E402


def outline(diameter, segments, n, height, width, phase_deg):
    """The drum's cross-section in the x-z plane, relative to its axis: the circumscribed polygon
    of the mantle (corners at angles 2 pi j / segments) with n rectangular notches (the bars), as a
    list of (x, z) vertices counter-clockwise (angle from +x towards +z increasing)."""
    r = 0.5 * diameter
    rpoly = r / math.cos(math.pi / segments)
    ring = [(rpoly * math.cos(2 * math.pi * j / segments), rpoly * math.sin(2 * math.pi * j / segments))
            for j in range(segments)]

    def ang(p):
        return math.atan2(p[1], p[0]) % (2 * math.pi)

    def on_mantle(e, t, l):
        """Point of the mantle polygon on the line l = const (lateral offset) of a bar, s > 0."""
        for j in range(segments):
            a, b = ring[j], ring[(j + 1) % segments]
            la, lb = a[0] * t[0] + a[1] * t[1], b[0] * t[0] + b[1] * t[1]
            if (la - l) * (lb - l) <= 0 and la != lb:
                u = (l - la) / (lb - la)
                p = (a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1]))
                if p[0] * e[0] + p[1] * e[1] > 0:
                    return p
        raise ValueError("bar side does not meet the mantle")

    bars = []
    for k in range(n):
        phi = math.radians(phase_deg + 360.0 * k / n)
        e, t = (math.cos(phi), math.sin(phi)), (-math.sin(phi), math.cos(phi))
        h, st = 0.5 * width, r - height
        m0, m1 = on_mantle(e, t, -h), on_mantle(e, t, h)
        corner = [m0, (st * e[0] - h * t[0], st * e[1] - h * t[1]),
                  (st * e[0] + h * t[0], st * e[1] + h * t[1]), m1]
        bars.append((ang(m0), ang(m1), corner))
    pts = []
    for j, p in enumerate(ring):
        a = ang(p)
        inside = any((a0 <= a <= a1) if a0 <= a1 else (a >= a0 or a <= a1) for a0, a1, _ in bars)
        if not inside:
            pts.append((a, 0, p))
    for a0, _, corner in bars:
        for i, p in enumerate(corner):
            pts.append((a0, 1 + i, p))  # the bar's four vertices in order, at the angle of its first
    pts.sort(key=lambda q: (q[0], q[1]))
    return [p for _, _, p in pts]


def ear_clip(poly):
    """Triangles (index triples, counter-clockwise) of a simple counter-clockwise polygon; the ear
    taken at each step is the one with the largest smallest angle (no long fans)."""
    idx = list(range(len(poly)))

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def inside(p, a, b, c):
        return cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0

    def min_angle(a, b, c):
        def angle(o, p, q):
            v, w = (p[0] - o[0], p[1] - o[1]), (q[0] - o[0], q[1] - o[1])
            return math.acos(max(-1.0, min(1.0, (v[0] * w[0] + v[1] * w[1]) / math.hypot(*v) / math.hypot(*w))))
        return min(angle(a, b, c), angle(b, c, a), angle(c, a, b))

    tris = []
    while len(idx) > 3:
        best = None
        m = len(idx)
        for i in range(m):
            ia, ib, ic = idx[i - 1], idx[i], idx[(i + 1) % m]
            a, b, c = poly[ia], poly[ib], poly[ic]
            if cross(a, b, c) <= 1e-15:
                continue
            if any(inside(poly[j], a, b, c) for j in idx if j not in (ia, ib, ic)):
                continue
            q = min_angle(a, b, c)
            if best is None or q > best[0]:
                best = (q, i, (ia, ib, ic))
        if best is None:
            raise ValueError("ear clipping failed (polygon not simple)")
        tris.append(best[2])
        del idx[best[1]]
    tris.append(tuple(idx))
    return tris


def drum_triangles(diameter, length, segments, n, height, width, phase_deg, centre):
    """A closed drum with n bars: the outline extruded along y (mantle and bar faces) and the two
    end caps (the outline triangulated); normals out of the drum's inside."""
    poly = outline(diameter, segments, n, height, width, phase_deg)
    cx, cy, cz = centre
    y0, y1 = cy - 0.5 * length, cy + 0.5 * length
    tris = []
    m = len(poly)
    for j in range(m):
        (ax, az), (bx, bz) = poly[j], poly[(j + 1) % m]
        # counter-clockwise in (x, z): the outward normal of edge a -> b is (dz, -dx)
        dx_, dz_ = bx - ax, bz - az
        ln = math.hypot(dx_, dz_)
        nv = (dz_ / ln, 0.0, -dx_ / ln)
        p00, p01 = (cx + ax, y0, cz + az), (cx + bx, y0, cz + bz)
        p10, p11 = (cx + ax, y1, cz + az), (cx + bx, y1, cz + bz)
        for tri in ((p00, p01, p11), (p00, p11, p10)):
            tris.append((nv, oriented(tri, nv)))
    for ia, ib, ic in ear_clip(poly):
        for y, ny in ((y0, -1.0), (y1, 1.0)):
            tri = tuple((cx + poly[i][0], y, cz + poly[i][1]) for i in (ia, ib, ic))
            tris.append(((0.0, ny, 0.0), oriented(tri, (0.0, ny, 0.0))))
    return tris


def oriented(tri, nv):
    """tri wound so that its right-hand normal points along nv."""
    a, b, c = tri
    e1 = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    e2 = (c[0] - a[0], c[1] - a[1], c[2] - a[2])
    cr = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
    return (a, b, c) if cr[0] * nv[0] + cr[1] * nv[1] + cr[2] * nv[2] > 0 else (a, c, b)


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
    tris = drum_triangles(a.diameter, a.length, a.segments, a.lifters, a.height, a.width, a.phase, centre)
    write_stl(a.out, tris, name="drum")
    print(f"wrote {a.out}: {len(tris)} triangles, diameter {a.diameter} m, length {a.length} m, "
          f"{a.lifters} lifters {a.height} x {a.width} m, axis y through ({centre[0]}, {centre[2]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
