#!/usr/bin/env python3
"""Frequency and growth rate of the standing wave of inputs/sloshing/in.wave against linear theory.

The water's centre of mass moves as x_c - L/2 = -2 A sin(w t) / (k^2 h L) for a surface
eta = A cos(k x) sin(w t), k = pi / L, w^2 = g k tanh(k h) (first order in A). The run's x_c(t) is
fitted by least squares with c + B exp(-r t) sin(w t + phi); printed: w / w_exact, r (1/s, positive:
decay), the amplitude ratio exp(-r t_end) over the run and B over the theory's 2 A / (k^2 h L).

The water's volume of inputs/sloshing/in.slosh (--volume dump.points): per frame, the cells of
the grid (x-z plane, one cell in y) counted as filled by min(1, n / ppc^2) of their area with n the
points in them (a regular fill has ppc^2 points per cell), summed; printed: the last frame's over the
first's (an irregular fill of the same volume reads low: a cell of 3 and one of 5 points count 1.75),
the largest number of points in a cell, and the mean number in the cells whose eight neighbours hold
points (ppc^2 for the held volume; more: the points compacted).

Usage: tools/python tools/sloshing.py wave.csv [--L 1 --h 0.25 --amp 0.005 --g 9.81]
       tools/python tools/sloshing.py --volume dump.points [--L 1 --cells 20 --ppc 2]
"""
import argparse
import csv
import math


def _solve3(a, b):
    """Solves the 3 x 3 system a x = b (Cramer)."""
    def det(m):
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    d = det(a)
    out = []
    for c in range(3):
        m = [row[:] for row in a]
        for r in range(3):
            m[r][c] = b[r]
        out.append(det(m) / d)
    return out


def _cost(t, x, w, r):
    """Least-squares fit of c + exp(-r t) (al sin w t + be cos w t) for fixed w, r: (cost, c, al, be)."""
    cols = [[1.0] * len(t), [math.exp(-r * s) * math.sin(w * s) for s in t], [math.exp(-r * s) * math.cos(w * s) for s in t]]
    a = [[sum(p * q for p, q in zip(cols[i], cols[j])) for j in range(3)] for i in range(3)]
    b = [sum(p * q for p, q in zip(cols[i], x)) for i in range(3)]
    c = _solve3(a, b)
    e = sum((c[0] * u + c[1] * v + c[2] * z - xx) ** 2 for u, v, z, xx in zip(cols[0], cols[1], cols[2], x))
    return e, c


def fit(path, L=1.0, h=0.25, amp=0.005, g=9.81):
    with open(path) as f:
        rows = [r for r in csv.DictReader(f)]
    t = [float(r["t"]) for r in rows]
    x = [float(r["xc"]) for r in rows]
    k = math.pi / L
    w0 = math.sqrt(g * k * math.tanh(k * h))
    b0 = 2 * amp / (k * k * h * L)
    # w on a grid from 0.5 to 1.5 w0, then w and r refined by shrinking coordinate steps
    w = min((_cost(t, x, w0 * (0.5 + 0.01 * i), 0.0)[0], w0 * (0.5 + 0.01 * i)) for i in range(101))[1]
    r, dw, dr = 0.0, 0.005 * w0, 0.05
    best = _cost(t, x, w, r)[0]
    while dw > 1e-6 * w0 or dr > 1e-6:
        moved = False
        for cw, cr in ((w + dw, r), (w - dw, r), (w, r + dr), (w, r - dr)):
            e = _cost(t, x, cw, cr)[0]
            if e < best:
                best, w, r, moved = e, cw, cr, True
        if not moved:
            dw *= 0.5
            dr *= 0.5
    e, c = _cost(t, x, w, r)
    b = math.hypot(c[1], c[2])
    rms = math.sqrt(e / len(t))
    return {"w_ratio": w / w0, "rate": r, "amp_ratio_end": math.exp(-r * (t[-1] - t[0])),
            "b_ratio": b / b0, "rms_over_b": rms / b, "w_exact": w0, "t_end": t[-1]}


def frames(path):
    """[(step, [(x, z), ...]), ...] of a dump 'id x z'."""
    out = []
    with open(path) as f:
        lines = f.read().split("\n")
    i = 0
    while i < len(lines):
        if lines[i].startswith("ITEM: TIMESTEP"):
            step = int(lines[i + 1])
            n = int(lines[i + 3])
            j = i + 9
            out.append((step, [(float(r.split()[1]), float(r.split()[2])) for r in lines[j:j + n]]))
            i = j + n
        else:
            i += 1
    return out


def filled_volume(points, dx, ppc):
    """(area filled per unit thickness, largest count of points in a cell) of one frame."""
    count = {}
    for x, z in points:
        c = (math.floor(x / dx), math.floor(z / dx))
        count[c] = count.get(c, 0) + 1
    full = ppc * ppc
    return sum(min(1.0, n / full) for n in count.values()) * dx * dx, max(count.values())


def interior_count(points, dx):
    """Mean number of points in the cells whose eight neighbours all hold points."""
    count = {}
    for x, z in points:
        c = (math.floor(x / dx), math.floor(z / dx))
        count[c] = count.get(c, 0) + 1
    inner = [n for (i, k), n in count.items()
             if all((i + a, k + b) in count for a in (-1, 0, 1) for b in (-1, 0, 1))]
    return sum(inner) / len(inner) if inner else float("nan")


def volume(path, L=1.0, cells=20, ppc=2):
    f = frames(path)
    dx = L / cells
    v0, n0 = filled_volume(f[0][1], dx, ppc)
    v1, n1 = filled_volume(f[-1][1], dx, ppc)
    return {"ratio": v1 / v0, "max_first": n0, "max_last": n1,
            "interior_first": interior_count(f[0][1], dx), "interior_last": interior_count(f[-1][1], dx)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv", nargs="?")
    ap.add_argument("--volume")
    ap.add_argument("--cells", type=int, default=20)
    ap.add_argument("--ppc", type=int, default=2)
    ap.add_argument("--L", type=float, default=1.0)
    ap.add_argument("--h", type=float, default=0.25)
    ap.add_argument("--amp", type=float, default=0.005)
    ap.add_argument("--g", type=float, default=9.81)
    a = ap.parse_args()
    if a.volume:
        v = volume(a.volume, a.L, a.cells, a.ppc)
        print("volume last / first %.4f  largest points per cell %d (first frame %d)  points per interior cell "
              "%.3f (first frame %.3f)" % (v["ratio"], v["max_last"], v["max_first"], v["interior_last"],
                                           v["interior_first"]))
        return
    r = fit(a.csv, a.L, a.h, a.amp, a.g)
    print("w / w_exact %.4f  decay rate %.4f 1/s  amplitude after %.2f s %.4f  amplitude / theory %.4f  "
          "fit rms / amplitude %.3f" % (r["w_ratio"], r["rate"], r["t_end"], r["amp_ratio_end"], r["b_ratio"],
                                        r["rms_over_b"]))


if __name__ == "__main__":
    main()
