#!/usr/bin/env python3
"""Inviscid early-time kinetic energy of a water column released at one face (docs/theory/projection.md,
"The released column"): the reference of inputs/tank/in.column, computed from the inputs alone by
two independent methods.

At t = 0+ the fluid starts from rest, so rho a = -grad p - rho g e_z with div a = 0: p is harmonic,
p = 0 on the free top and the open face x = a, dp/dn = -rho g n_z on the floor and the back wall.
The kinetic energy is KE(t) = t^2 / 2 * rho int |a|^2 dV (leading order while t sqrt(g/h) << 1).

1. Fourier series: p = rho g (h - z) + q, q = sum A_n cosh(k_n x) cos(k_n z), k_n = (2n+1) pi / (2h),
   q(a, z) = -rho g (h - z) gives A_n cosh(k_n a) = c_n = -2 rho g / (h k_n^2), and
   int |grad q|^2 dV = W int_0^h q dq/dx |_{x=a} dz = W (h/2) sum c_n^2 k_n tanh(k_n a).
2. Second-order finite differences on a cell-centred grid (ghost values for the boundary conditions),
   solved densely, energy from the face accelerations; three grids.

Usage: tools/python tools/column_inviscid.py [--width 0.05 --height 0.1 --depth 0.1]
"""
import argparse
import math

import numpy as np


def series(a, h, W, rho=1000.0, g=9.81, terms=200000):
    n = np.arange(terms)
    k = (2 * n + 1) * math.pi / (2 * h)
    c = -2 * rho * g / (h * k ** 2)
    return 0.5 / rho * W * np.sum(c ** 2 * k * np.tanh(k * a)) * h / 2


def finite_differences(a, h, W, nx, rho=1000.0, g=9.81):
    dx = a / nx
    nz = int(round(h / dx))
    N = nx * nz
    A = np.zeros((N, N))
    b = np.zeros(N)
    idx = lambda i, k: i * nz + k  # noqa: E731
    for i in range(nx):
        for k in range(nz):
            r = idx(i, k)
            for di, dk in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                ii, kk = i + di, k + dk
                if 0 <= ii < nx and 0 <= kk < nz:
                    A[r, r] -= 1
                    A[r, idx(ii, kk)] += 1
                elif ii == nx or kk == nz:  # p = 0 on the face: ghost = -p
                    A[r, r] -= 2
                elif kk < 0:  # floor: dp/dz = -rho g
                    b[r] -= rho * g * dx
                # back wall: dp/dx = 0, nothing to add
    p = np.linalg.solve(A, b).reshape(nx, nz)
    pe = np.zeros((nx + 2, nz + 2))
    pe[1:-1, 1:-1] = p
    pe[0, 1:-1] = p[0]
    pe[-1, 1:-1] = -p[-1]
    pe[1:-1, -1] = -p[:, -1]
    pe[1:-1, 0] = p[:, 0] + rho * g * dx
    ax = -(pe[1:, 1:-1] - pe[:-1, 1:-1]) / dx / rho
    az = -(pe[1:-1, 1:] - pe[1:-1, :-1]) / dx / rho - g
    wx = np.ones_like(ax)
    wx[0] = wx[-1] = 0.5
    wz = np.ones_like(az)
    wz[:, 0] = wz[:, -1] = 0.5
    return 0.5 * rho * (np.sum(wx * ax ** 2) + np.sum(wz * az ** 2)) * dx * dx * W


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=float, default=0.05)
    ap.add_argument("--height", type=float, default=0.1)
    ap.add_argument("--depth", type=float, default=0.1)
    a = ap.parse_args()
    s = series(a.width, a.height, a.depth)
    print(f"series: KE / t^2 = {s:.5f} J/s^2; KE(0.01 s) = {s * 1e-4:.4e} J, KE(0.02 s) = {s * 4e-4:.4e} J")
    for nx in (20, 40, 60):
        f = finite_differences(a.width, a.height, a.depth, nx)
        print(f"finite differences, {nx} cells across: KE / t^2 = {f:.5f} J/s^2 ({f / s - 1:+.2e} against the series)")


if __name__ == "__main__":
    main()
