#!/usr/bin/env python3
"""Snapshots of the C3 tank run (inputs/tank/in.tank): glass beads and water after the gate rises.

  tools/python tools/render_tank.py RUNDIR [--times 0.05 0.10 0.15 0.20] [--out tank.png]
        [--view side|top] [--slab YLO YHI] [--dpi 150]

RUNDIR is the work folder of one run of in.tank. It holds tank_run.txt (time step, step of the
gate start, geometry; written by the input), the HDF5 point output <prefix>_<step, 9 digits>.h5
and the LIGGGHTS bead dumps beads_<step>.dump, written every 'tsnap' of simulated time. Times are
seconds after the start of the lift; for every requested time the nearest written frame is drawn
(its own time is in the panel title).

Side view (default): x along the tank, z up, every point and bead projected along y (or only those
in the slab YLO < y < YHI); water points light blue, beads dark blue drawn to scale (diameter d)
on top, like Figures 9.3 and 10.5 of the dissertation. The tank outline is black, the gate
(grey) is drawn at its height at that time. Top view: x along the tank, y across.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mpm_io import BEADS, WATER, paired_frames, read_dump, read_key_values, read_points  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rundir")
    ap.add_argument("--times", type=float, nargs="+", default=[0.05, 0.10, 0.15, 0.20])
    ap.add_argument("--out", default=None, help="PNG file (default RUNDIR/tank_snapshots.png)")
    ap.add_argument("--view", choices=["side", "top"], default="side")
    ap.add_argument("--slab", type=float, nargs=2, default=None, metavar=("YLO", "YHI"),
                    help="side view: only points and beads with YLO < y < YHI")
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--title", default=None)
    a = ap.parse_args()

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    info = read_key_values(os.path.join(a.rundir, "tank_run.txt"), numbers=True, missing_ok=True)
    if not info:
        sys.exit(f"render_tank: no tank_run.txt in {a.rundir} (not a run of inputs/tank/in.tank?)")
    dt, n0 = info["dt"], int(info["gate_start_step"])
    prefix = str(info.get("prefix", "tank"))
    L, W, H = info.get("L", 0.2), info.get("W", 0.1), info.get("H", 0.15)
    xg, vg, d = info.get("xg", 0.05), info.get("vgate", 0.68), info.get("d", 0.0027)
    fr = paired_frames(a.rundir, prefix)
    if not fr:
        sys.exit("no frame with both %s_*.h5 and beads_*.dump in %s" % (prefix, a.rundir))
    steps = np.array(sorted(fr))

    n = len(a.times)
    ncol = 2 if n > 1 else 1
    nrow = (n + ncol - 1) // ncol
    ext_y = H if a.view == "side" else W
    fig_w = 6.0 * ncol
    fig_h = nrow * (6.0 * (ext_y + 0.02) / (L + 0.02) + 0.45) + 0.5
    fig, axes = plt.subplots(nrow, ncol, figsize=(fig_w, fig_h), squeeze=False)
    for k, t in enumerate(a.times):
        ax = axes[k // ncol][k % ncol]
        want = n0 + t / dt
        s = int(steps[np.argmin(np.abs(steps - want))])
        ts = (s - n0) * dt
        h5, dump = fr[s]
        xyz = read_points(h5)[0]
        b = read_dump(dump)
        bx, by, bz = b["x"], b["y"], b["z"]
        if a.view == "side":
            px, py = xyz[:, 0], xyz[:, 2]
            qx, qy = bx, bz
            if a.slab:
                mp = (xyz[:, 1] > a.slab[0]) & (xyz[:, 1] < a.slab[1])
                mb = (by > a.slab[0]) & (by < a.slab[1])
                px, py, qx, qy = px[mp], py[mp], qx[mb], qy[mb]
                order_p, order_b = None, None
            else:
                # draw the farthest first (view from y < 0): nearer points and beads on top
                order_p = np.argsort(-xyz[:, 1])
                order_b = np.argsort(-by)
                px, py = px[order_p], py[order_p]
                qx, qy = qx[order_b], qy[order_b]
            ylim = (-0.005, H + 0.005)
        else:
            px, py = xyz[:, 0], xyz[:, 1]
            oz = np.argsort(xyz[:, 2])
            px, py = px[oz], py[oz]
            ob = np.argsort(bz)
            qx, qy = bx[ob], by[ob]
            ylim = (-0.005, W + 0.005)
        ax.set_xlim(-0.005, L + 0.005)
        ax.set_ylim(*ylim)
        ax.set_aspect("equal")
        fig.canvas.draw()
        # marker sizes in points^2 from data units
        bbox = ax.get_window_extent()
        pt_per_m = bbox.width / (L + 0.01) * 72.0 / fig.dpi
        dx = info.get("dx", 0.005)
        npc = max(info.get("pnx", 2), info.get("pnz", 2))
        sp = dx / npc
        ax.scatter(px, py, s=(0.9 * sp * pt_per_m) ** 2, c=WATER, marker="o", linewidths=0,
                   alpha=0.6 if a.view == "side" else 0.5, zorder=1)
        ax.scatter(qx, qy, s=(d * pt_per_m) ** 2, c=BEADS, marker="o", linewidths=0, zorder=2)
        # tank and gate
        top = H if a.view == "side" else W
        ax.plot([0, 0, L, L], [top, 0, 0, top], color="k", lw=1.2, zorder=3)
        if a.view == "side":
            gz = max(0.0, vg * ts)
            ax.plot([xg, xg], [gz, H + 0.005], color="0.45", lw=2.5, zorder=3)
        else:
            ax.plot([0, L], [W, W], color="k", lw=1.2, zorder=3)
        ax.set_title("t = %.3f s" % ts, fontsize=10)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("z (m)" if a.view == "side" else "y (m)")
        ax.tick_params(labelsize=8)
    for k in range(n, nrow * ncol):
        axes[k // ncol][k % ncol].axis("off")
    title = a.title or ("C3 tank, Grid%d, %dx%dx%d points per cell, %d beads" % (
        int(info.get("cells", 0)), int(info.get("pnx", 0)), int(info.get("pny", 0)),
        int(info.get("pnz", 0)), int(info.get("nbeads", 0))))
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    out = a.out or os.path.join(a.rundir, "tank_snapshots.png")
    fig.savefig(out, dpi=a.dpi)
    print("wrote", out)


if __name__ == "__main__":
    main()
