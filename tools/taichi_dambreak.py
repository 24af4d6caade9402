#!/usr/bin/env python3
"""Taichi reference for the 3-D dam-break benchmark (docs/validation/performance.md).

  tools/python-bench tools/taichi_dambreak.py [--cells 23] [--threads 1] [--warm 10] [--nsteps 300]

The case of inputs/bench/in.dambreak3d: a cube of water a x a x a (a = 1 m) in the corner x < a,
y < a of a tank 3a x 2a x (a + 2 dx), no-slip walls on every face, released at step 0 from a
hydrostatic state; cell dx = a / cells, 2 x 2 x 2 points per cell (8 cells^3 points: 97,336 at
cells 23), rho0 1000, linear equation of state p = K (1 - J) with K = 2e7 Pa, viscosity 0.001 Pa s,
g = 9.81, time step 0.25 dx / (c + 2 sqrt(g a)) as in the input.

The scheme is the usual compact CPU MLS-MPM of Taichi's examples: quadratic B-splines, APIC
velocity field (the MLS-MPM form: the affine matrix C carries the stress force into the same P2G
scatter), one P2G with atomic adds, one grid pass (momentum -> velocity, gravity, no-slip walls),
one G2P that moves the points and updates J. Float64 throughout (our solver runs in double), the
CPU backend with cpu_max_num_threads = --threads. The grid covers the tank plus one ghost layer of
nodes (the stencils of points within dx/2 of a wall), dense, cleared every step, as in Taichi's
examples.

Prints, after 'warm' steps (JIT compilation included) and 'nsteps' timed steps (front_x as fix
mpm/fluid's f_ID[4]: the largest x of a point plus half the point spacing):
  taichi_dambreak: points N steps S threads T loop_s L point_steps_per_s R front_x F mass M
"""
import argparse
import math
import sys
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=int, default=23, help="cells across the column edge")
    ap.add_argument("--threads", type=int, default=1, help="Taichi cpu_max_num_threads")
    ap.add_argument("--warm", type=int, default=10, help="untimed steps (JIT compilation happens here)")
    ap.add_argument("--nsteps", type=int, default=300, help="timed steps")
    a = ap.parse_args()
    for name in ("cells", "threads", "nsteps"):
        if getattr(a, name) < 1:
            sys.exit("taichi_dambreak.py: --%s must be >= 1 (given %d)" % (name, getattr(a, name)))
    if a.warm < 1:
        sys.exit("taichi_dambreak.py: --warm must be >= 1 to keep the JIT out of the timing (given %d)" % a.warm)

    import taichi as ti
    ti.init(arch=ti.cpu, default_fp=ti.f64, default_ip=ti.i32, cpu_max_num_threads=a.threads,
            log_level=ti.WARN, offline_cache=True)

    A, RHO, K, MU, G, PPC = 1.0, 1000.0, 2.0e7, 0.001, 9.81, 2
    n = a.cells
    dx = A / n
    inv_dx = 1.0 / dx
    ncell = (3 * n, 2 * n, n + 2)           # tank 3a x 2a x (a + 2 dx)
    c = math.sqrt(K / RHO)
    dt = 0.25 * dx / (c + 2.0 * math.sqrt(G * A))
    npc = n * PPC                            # points per column edge
    npts = npc ** 3
    vol0 = (dx / PPC) ** 3
    m_p = RHO * vol0

    x = ti.Vector.field(3, ti.f64, shape=npts)
    v = ti.Vector.field(3, ti.f64, shape=npts)
    C = ti.Matrix.field(3, 3, ti.f64, shape=npts)
    J = ti.field(ti.f64, shape=npts)
    # nodes -1 .. ncell + 1 on each axis: the walls are the node planes 0 and ncell
    gshape = tuple(k + 3 for k in ncell)
    grid_v = ti.Vector.field(3, ti.f64, shape=gshape, offset=(-1, -1, -1))
    grid_m = ti.field(ti.f64, shape=gshape, offset=(-1, -1, -1))
    nx, ny, nz = ncell

    @ti.kernel
    def init():
        for i, j, k in ti.ndrange(npc, npc, npc):
            p = (i * npc + j) * npc + k
            x[p] = ti.Vector([i + 0.5, j + 0.5, k + 0.5]) * (dx / PPC)
            v[p] = ti.Vector.zero(ti.f64, 3)
            C[p] = ti.Matrix.zero(ti.f64, 3, 3)
            # hydrostatic start: p = rho0 g (a - z) = K (1 - J)
            J[p] = 1.0 - RHO * G * ti.max(0.0, A - x[p][2]) / K

    @ti.kernel
    def clear():
        for I in ti.grouped(grid_m):
            grid_v[I] = ti.Vector.zero(ti.f64, 3)
            grid_m[I] = 0.0

    @ti.kernel
    def p2g():
        for p in x:
            Xp = x[p] * inv_dx
            base = ti.floor(Xp - 0.5, ti.i32)
            fx = Xp - base
            w = [0.5 * (1.5 - fx) ** 2, 0.75 - (fx - 1.0) ** 2, 0.5 * (fx - 0.5) ** 2]
            pres = K * (1.0 - J[p])
            D = 0.5 * (C[p] + C[p].transpose())
            sigma = 2.0 * MU * (D - D.trace() / 3.0 * ti.Matrix.identity(ti.f64, 3)) \
                - pres * ti.Matrix.identity(ti.f64, 3)
            # the force -V sigma grad(w) written with the quadratic B-spline's D^-1 = 4 / dx^2
            affine = -dt * vol0 * J[p] * 4.0 * inv_dx * inv_dx * sigma + m_p * C[p]
            for o in ti.static(ti.grouped(ti.ndrange(3, 3, 3))):
                dpos = (o - fx) * dx
                weight = w[o[0]][0] * w[o[1]][1] * w[o[2]][2]
                grid_v[base + o] += weight * (m_p * v[p] + affine @ dpos)
                grid_m[base + o] += weight * m_p

    @ti.kernel
    def update_grid():
        for i, j, k in grid_m:
            if grid_m[i, j, k] > 0:
                vel = grid_v[i, j, k] / grid_m[i, j, k]
                vel[2] -= dt * G
                if i <= 0 or i >= nx or j <= 0 or j >= ny or k <= 0 or k >= nz:
                    vel = ti.Vector.zero(ti.f64, 3)   # no-slip walls (and the ghost nodes behind them)
                grid_v[i, j, k] = vel

    @ti.kernel
    def g2p():
        for p in x:
            Xp = x[p] * inv_dx
            base = ti.floor(Xp - 0.5, ti.i32)
            fx = Xp - base
            w = [0.5 * (1.5 - fx) ** 2, 0.75 - (fx - 1.0) ** 2, 0.5 * (fx - 0.5) ** 2]
            new_v = ti.Vector.zero(ti.f64, 3)
            new_C = ti.Matrix.zero(ti.f64, 3, 3)
            for o in ti.static(ti.grouped(ti.ndrange(3, 3, 3))):
                dpos = (o - fx) * dx
                weight = w[o[0]][0] * w[o[1]][1] * w[o[2]][2]
                gv = grid_v[base + o]
                new_v += weight * gv
                new_C += 4.0 * inv_dx * inv_dx * weight * gv.outer_product(dpos)
            v[p] = new_v
            C[p] = new_C
            J[p] *= 1.0 + dt * new_C.trace()
            x[p] += dt * new_v

    def step():
        clear()
        p2g()
        update_grid()
        g2p()

    init()
    for _ in range(a.warm):
        step()
    ti.sync()
    t0 = time.perf_counter()
    for _ in range(a.nsteps):
        step()
    ti.sync()
    loop = time.perf_counter() - t0

    xs = x.to_numpy()
    js = J.to_numpy()
    if not (abs(xs).max() < 10.0 * A and (js > 0).all()):
        sys.exit("taichi_dambreak.py: the run blew up (max |x| %g, min J %g)" % (abs(xs).max(), js.min()))
    print("taichi_dambreak: points %d steps %d threads %d loop_s %.6f point_steps_per_s %.6g front_x %.6f "
          "mass %.6f taichi %s" % (npts, a.nsteps, a.threads, loop, npts * a.nsteps / loop, xs[:, 0].max() + 0.5 * dx / PPC,
                                   m_p * npts, ti.__version__ if isinstance(ti.__version__, str)
                                   else ".".join(map(str, ti.__version__))), flush=True)


if __name__ == "__main__":
    main()
