#!/usr/bin/env python3
"""Snapshots of a dam-break run (HDF5 point output of inputs/dambreak/in.dambreak).

  tools/python tools/render_dambreak.py RUNDIR [--times 0 0.5 1 1.5 2 2.5 3]
        [--field v|p] [--front RUNDIR/front.csv] [--out dambreak.png]

RUNDIR holds dambreak_<step>.h5 (run with -var h5every N > 0). Times are in
units of T = t sqrt(g/a) after gate removal; the HDF5 'time' attribute
includes the settling time (--tsettle, default 0.3 s). For every requested T
the nearest written frame is drawn (its own T is in the panel title). Points
are coloured by the velocity magnitude (--field v) or the pressure (--field p).
The dashed line in each panel marks the Martin & Moyce (1952) front at that T.
With --front front.csv the figure gets a second column: Z = x_front/a and
H = h_wall/a against T with the measured points.
Geometry (width a, height, length, g, ppc) is read from RUNDIR/in.dambreak if
present (override with --width/--length/--g).
"""
import argparse
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import dambreak_error  # noqa: E402
from mpm_io import h5_series, read_csv, read_points  # noqa: E402


def load(path, field):
    xyz, vals, _ = read_points(path, ["p"] if field == "p" else ["v"])
    val = vals["p"] if field == "p" else np.linalg.norm(vals["v"], axis=1)
    return xyz[:, 0], xyz[:, 2], val


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rundir", help="folder with dambreak_*.h5 (and in.dambreak)")
    ap.add_argument("--times", type=float, nargs="+", default=None,
                    help="T = t sqrt(g/a) after gate removal (default: up to 7 frames spread over the run)")
    ap.add_argument("--tsettle", type=float, default=0.3, help="settling time before gate removal (s)")
    ap.add_argument("--field", choices=["v", "p"], default="v")
    ap.add_argument("--front", default=None, help="front.csv of the run: add Z(T), H(T) vs Martin & Moyce")
    ap.add_argument("--out", default="dambreak.png")
    ap.add_argument("--prefix", default="dambreak")
    ap.add_argument("--width", type=float, default=None, help="column width a (m)")
    ap.add_argument("--length", type=float, default=None, help="channel length (m)")
    ap.add_argument("--g", type=float, default=None)
    ap.add_argument("--vmax", type=float, default=None, help="top of the colour scale")
    ap.add_argument("--title", default=None)
    ap.add_argument("--dpi", type=int, default=140)
    a = ap.parse_args()

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.gridspec import GridSpec

    d = dambreak_error.input_defaults(os.path.join(a.rundir, "in.dambreak"))
    width = a.width or float(d.get("width", 4.0))
    height = float(d.get("height", width))
    length = a.length or float(d.get("length", 6 * width))
    g = a.g or float(d.get("g", 9.81))
    tscale = math.sqrt(g / width)

    fr = h5_series(a.rundir, a.prefix)
    if not fr:
        sys.exit("no %s_*.h5 in %s (run with -var h5every N)" % (a.prefix, a.rundir))
    Tf = np.array([(t - a.tsettle) * tscale for t, _ in fr])
    if a.times:
        idx = []
        for T in a.times:
            i = int(np.argmin(np.abs(Tf - T)))
            if i not in idx:
                idx.append(i)
    else:
        cand = [i for i in range(len(fr)) if Tf[i] > -0.05] or list(range(len(fr)))
        idx = sorted({cand[int(round(k))] for k in np.linspace(0, len(cand) - 1, min(7, len(cand)))})
    snaps = []
    for i in idx:
        x, z, val = load(fr[i][1], a.field)
        snaps.append((Tf[i], fr[i][0], x, z, val))
    n0 = len(snaps[0][2])
    spacing = math.sqrt(width * height / n0)  # initial point spacing (2-D column)

    if a.field == "p":
        scale, unit, cmap, label = 1e-3, "kPa", "viridis", "pressure (kPa)"
        vmin = 0.0
        vmax = a.vmax or max(np.percentile(s[4], 99.5) for s in snaps) * scale
    else:
        scale, unit, cmap, label = 1.0, "m/s", "turbo", "|v| (m/s)"
        vmin = 0.0
        vmax = a.vmax or max(max(np.percentile(s[4], 99.5) for s in snaps), 1e-6)

    front, href = dambreak_error.load_reference()
    Tref = np.concatenate(([0.0], front["T"]))
    Zref = np.concatenate(([1.0], front["Z"]))

    nrow = len(snaps)
    zmax = 1.15 * height
    strip_w = 9.0
    strip_h = strip_w * zmax / length
    row_h = strip_h + 0.42
    with_front = a.front is not None
    figw = strip_w + 1.6 + (4.6 if with_front else 0.0)
    figh = max(nrow * row_h + 1.0, 5.0 if with_front else 0.0)
    fig = plt.figure(figsize=(figw, figh))
    left_in, right_in = 0.55, 1.2 + (4.6 if with_front else 0.0)
    gs = GridSpec(nrow, 1, figure=fig, left=left_in / figw, right=1 - right_in / figw,
                  top=1 - 0.55 / figh, bottom=0.5 / figh, hspace=0.42 / strip_h)
    axes = [fig.add_subplot(gs[k, 0]) for k in range(nrow)]
    pts_per_m = strip_w * 72.0 / length
    msize = (1.5 * spacing * pts_per_m) ** 2
    sc = None
    for k, (ax, (T, t, x, z, val)) in enumerate(zip(axes, snaps)):
        order = np.argsort(val)
        sc = ax.scatter(x[order] / width, z[order] / width, c=val[order] * scale, s=msize, marker="s",
                        linewidths=0, cmap=cmap, vmin=vmin, vmax=vmax, rasterized=True)
        ax.set_xlim(0, length / width)
        ax.set_ylim(0, zmax / width)
        ax.set_aspect("equal")
        ax.plot([0, 0], [0, zmax / width], color="0.2", lw=3, solid_capstyle="butt", clip_on=False)
        ax.axhline(0, color="0.2", lw=1.5)
        if 0.0 <= T <= Tref[-1]:
            zf = float(np.interp(T, Tref, Zref))
            ax.axvline(zf, color="k", ls="--", lw=0.9,
                       label="Martin & Moyce (1952) front" if k == 0 else None)
        tag = "T = %.2f" % T
        if T < -1e-3:
            tag += "  (gate closed)"
        ax.set_title(tag + "   (t = %.3f s)" % (t - a.tsettle), loc="left", fontsize=9, pad=3)
        ax.tick_params(labelsize=8)
        ax.set_yticks([0, 0.5, 1.0])
        if k < nrow - 1:
            ax.set_xticklabels([])
        ax.set_ylabel("z/a", fontsize=8, labelpad=1)
    axes[-1].set_xlabel("x/a", fontsize=9)
    if any(ax.get_legend_handles_labels()[0] for ax in axes):
        axes[0].legend(loc="upper right", fontsize=7, frameon=False)
    cax = fig.add_axes([1 - (right_in - 0.25) / figw, 0.5 / figh + 0.1 * (1 - 1.05 / figh),
                        0.14 / figw, 0.8 * (1 - 1.05 / figh)])
    cb = fig.colorbar(sc, cax=cax)
    cb.set_label(label, fontsize=9)
    cb.ax.tick_params(labelsize=8)

    if with_front:
        sim = read_csv(a.front)
        T = sim["t"] * tscale
        x0 = 1 - 4.15 / figw
        w = 3.75 / figw
        top = 1 - 0.55 / figh
        bot = 0.5 / figh
        hgt = (top - bot - 0.75 / figh) / 2
        axz = fig.add_axes([x0, bot + hgt + 0.75 / figh, w, hgt])
        axh = fig.add_axes([x0, bot, w, hgt])
        tmax = max(T.max(), 0.5) * 1.03
        kf, kh = front["T"] <= tmax * 1.02, href["T"] <= tmax * 1.02
        axz.plot(T, sim["x_front"] / width, "-", color="C0", lw=1.8, label="MPM")
        axz.plot(front["T"][kf], front["Z"][kf], "ks", mfc="none", ms=5, label="Martin & Moyce (1952)")
        axh.plot(T, sim["h_wall"] / width, "-", color="C0", lw=1.8, label="MPM")
        axh.plot(href["T"][kh], href["H"][kh], "ks", mfc="none", ms=5, label="Martin & Moyce (1952)")
        for s in snaps:
            for ax in (axz, axh):
                ax.axvline(s[0], color="0.75", lw=0.7, zorder=0)
        ef, eh, n = dambreak_error.errors(a.front, width, g)
        axz.set_title("surge front, RMS error %.3f a" % ef, fontsize=9)
        axh.set_title("height at the wall, RMS error %.3f a" % eh, fontsize=9)
        axz.set_ylabel(r"$Z = x_{front}/a$", fontsize=9)
        axh.set_ylabel(r"$H = h_{wall}/a$", fontsize=9)
        axh.set_xlabel(r"$T = t\,\sqrt{g/a}$", fontsize=9)
        for ax in (axz, axh):
            ax.set_xlim(-0.02 * tmax, tmax)
            ax.grid(True, alpha=0.3)
            ax.tick_params(labelsize=8)
            ax.legend(fontsize=7, loc="best")
        axh.set_ylim(0, 1.1)
    title = a.title or "Dam break, square column a = %g m%s" % (
        width, (", %d points" % n0))
    fig.suptitle(title, x=left_in / figw, y=1 - 0.12 / figh, ha="left", va="top", fontsize=11)
    fig.savefig(a.out, dpi=a.dpi)
    print("wrote %s (%d snapshots: T = %s)" % (a.out, len(snaps), ", ".join("%.2f" % s[0] for s in snaps)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
