#!/usr/bin/env python3
"""Snapshots of the C4 rotating-jar run (inputs/jar/in.jar): beads and water seen along the axis.

  tools/python tools/render_jar.py RUNDIR [--turns 1 5 10 25] [--out jar.png] [--slab YLO YHI]
        [--altitude MM] [--dpi 150]

RUNDIR is the work folder of one run of in.jar: jar_run.txt (time step, step of the start of the
rotation, period, geometry), the HDF5 point output jar_<step, 9 digits>.h5 and the bead dumps
beads_<step>.dump, written every 'tsnap'. For every requested turn the nearest written frame is
drawn (its own turn is in the panel title): x across, z up, every point and bead projected along
the jar axis y (or only those in the slab YLO < y < YHI), water points light blue, beads dark blue
to scale, the jar wall black. The jar turns counter-clockwise in this view (positive rotation
about +y seen from y < 0), so the bed climbs the left wall. Dashed: the experiment's bed altitude
62.18 mm; dotted: --altitude (e.g. the run's mean from tools/jar_altitude.py).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from jar_altitude import EXPERIMENT_MM, read_info  # noqa: E402
from mpm_io import BEADS, WATER, paired_frames, read_dump, read_points  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rundir")
    ap.add_argument("--turns", type=float, nargs="+", default=[1.0, 5.0, 10.0, 25.0])
    ap.add_argument("--out", default=None, help="PNG file (default RUNDIR/jar_snapshots.png)")
    ap.add_argument("--slab", type=float, nargs=2, default=None, metavar=("YLO", "YHI"))
    ap.add_argument("--altitude", type=float, default=None, help="a bed altitude (mm) to mark")
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--title", default=None)
    a = ap.parse_args()

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not os.path.exists(os.path.join(a.rundir, "jar_run.txt")):
        sys.exit(f"render_jar: no jar_run.txt in {a.rundir} (not a run of inputs/jar/in.jar?)")
    info = read_info(a.rundir)
    dt, n0, period = float(info["dt"]), int(float(info["rot_start_step"])), float(info["period"])
    D, d = float(info.get("D", 0.1)), float(info.get("d", 0.0027))
    dx = float(info.get("dx", D / 18))
    fr = paired_frames(a.rundir, "jar")
    if not fr:
        sys.exit("render_jar: no frame with both jar_*.h5 and beads_*.dump in %s" % a.rundir)
    steps = np.array(sorted(fr))

    n = len(a.turns)
    ncol = min(n, 4)
    nrow = (n + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.6 * ncol, 3.8 * nrow + 0.4), squeeze=False)
    R = 0.5 * D
    phi = np.linspace(0.0, 2.0 * np.pi, 361)
    for k, turn in enumerate(a.turns):
        ax = axes[k // ncol][k % ncol]
        s = int(steps[np.argmin(np.abs(steps - (n0 + turn * period / dt)))])
        ts = (s - n0) * dt
        h5, dump = fr[s]
        xyz = read_points(h5)[0]
        b = read_dump(dump)
        if a.slab:
            xyz = xyz[(xyz[:, 1] > a.slab[0]) & (xyz[:, 1] < a.slab[1])]
            keep = (b["y"] > a.slab[0]) & (b["y"] < a.slab[1])
            b = {c: v[keep] for c, v in b.items()}
        # view from y < 0: the farthest first, nearer points and beads on top
        op, ob = np.argsort(-xyz[:, 1]), np.argsort(-b["y"])
        ax.set_xlim(-0.004, D + 0.004)
        ax.set_ylim(-0.004, D + 0.004)
        ax.set_aspect("equal")
        fig.canvas.draw()
        pt_per_m = ax.get_window_extent().width / (D + 0.008) * 72.0 / fig.dpi
        ax.scatter(xyz[op, 0], xyz[op, 2], s=(0.9 * dx * pt_per_m) ** 2, c=WATER, marker="o",
                   linewidths=0, alpha=0.5, zorder=1)
        ax.scatter(b["x"][ob], b["z"][ob], s=(d * pt_per_m) ** 2, c=BEADS, marker="o", linewidths=0, zorder=2)
        ax.plot(R + R * np.cos(phi), R + R * np.sin(phi), color="k", lw=1.2, zorder=3)
        ax.axhline(EXPERIMENT_MM / 1e3, color="0.3", lw=0.9, ls="--", zorder=4)
        if a.altitude is not None:
            ax.axhline(a.altitude / 1e3, color="tab:red", lw=0.9, ls=":", zorder=4)
        ax.set_title("turn %.2f (t = %.2f s)" % (ts / period, ts), fontsize=9)
        ax.set_xlabel("x (m)", fontsize=8)
        ax.set_ylabel("z (m)", fontsize=8)
        ax.tick_params(labelsize=7)
    for k in range(n, nrow * ncol):
        axes[k // ncol][k % ncol].axis("off")
    title = a.title or "C4 jar, wall %s, cells %s, %s beads (dashed: experiment %.2f mm)" % (
        info.get("wall", "?"), info.get("cells", "?"), info.get("nbeads", "?"), EXPERIMENT_MM)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    out = a.out or os.path.join(a.rundir, "jar_snapshots.png")
    fig.savefig(out, dpi=a.dpi)
    print("wrote", out)


if __name__ == "__main__":
    main()
