#!/usr/bin/env python3
"""Pictures of any liggghts_mpm run: material points and grains at chosen times, side projection.

  tools/python tools/render_run.py RUN_DIR [--times T1 T2 ...] [--out FILE.png] [--axis x|y|z]
        [--field p|v] [--prefix PREFIX] [--dump NAME] [--vmax V] [--dpi 150]
        [--slab LO HI] [--zoom H0 H1 V0 V1] [--title TEXT] [--labels L1 L2 ...]

RUN_DIR is the folder a run wrote its outputs to. The points come from the HDF5 series of fix
mpm/fluid (`output N PREFIX points ...`: PREFIX.xmf and PREFIX_<step>.h5; with several series,
--prefix chooses one), the grains from the one-frame-per-file LIGGGHTS dumps in the same folder
(`dump ID group custom N NAME_*.dump id x y z radius ...`; all such series, or --dump NAME). Nothing
else is needed: no info file, no knowledge of the input.

For every requested time (simulated seconds, the 'time' attribute of the HDF5 files) the nearest
written frame is drawn; its own time and step are in the panel title. The grains drawn are those of
the dump with the same step (or the nearest step, named in the title). Default times: up to four
frames spread over the series.

The picture is a projection along --axis (default y: x to the right, z up; x: y to the right, z up;
z: x to the right, y up); what is nearer to the viewer (smaller coordinate along the axis) is drawn
on top. Points are coloured by the pressure (--field p, kPa; the point field 'p' must be in the
output) or the speed |v| (--field v, m/s; field 'v'), grains are dark blue discs to scale (radius
column, else --grain-diameter). --slab LO HI draws only the points and grains whose coordinate along
the axis lies in [LO, HI] (a cut through a 3-D scene, so that beads in front do not hide the water).
The axes span the points and grains drawn (over all panels, after the slab) with a margin of 3 %;
--zoom H0 H1 V0 V1 sets them instead (picture coordinates: horizontal, then vertical, in m). The
LIGGGHTS box of the dumps is outlined where it falls inside the axes. --title TEXT heads the figure
(above the line that counts what is drawn; default: the folder's name); --labels gives one text per
--times entry, put before that panel's time (e.g. "before release").
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mpm_io import BEADS, dump_series, h5_series, read_dump_frames, read_points, xmf_series  # noqa: E402

# axis of projection -> (horizontal, vertical) coordinate indices
VIEWS = {"x": (1, 2), "y": (0, 2), "z": (0, 1)}
NAMES = "xyz"


def point_frames(rundir, prefix):
    """(prefix, [(step, time, path)]) of the run's HDF5 series."""
    series = xmf_series(rundir)
    if not series:  # no index (e.g. deleted): the files themselves, step from their attributes
        import glob
        import re
        found = {}
        for p in glob.glob(os.path.join(rundir, "*_*.h5")):
            m = re.match(r"(.+)_(\d+)\.h5$", os.path.basename(p))
            if m:
                found.setdefault(m.group(1), None)
        for pre in found:
            rows = []
            for t, p in h5_series(rundir, pre):
                rows.append((int(read_points(p)[2].get("step", -1)), t, p))
            series[pre] = rows
    if prefix:
        if prefix not in series:
            sys.exit("render_run: no HDF5 series '%s' in %s (found: %s)" % (prefix, rundir, ", ".join(series) or "none"))
        return prefix, series[prefix]
    series = {k: v for k, v in series.items() if v}
    if not series:
        sys.exit("render_run: no HDF5 output of fix mpm/fluid in %s (keyword 'output N prefix points ...')" % rundir)
    if len(series) > 1:
        print("render_run: several HDF5 series (%s); drawing '%s' (choose with --prefix)"
              % (", ".join(sorted(series)), sorted(series)[0]), file=sys.stderr)
    pre = sorted(series)[0]
    return pre, series[pre]


def nearest_spacing(xyz, sample=2000):
    """Median distance from a point to its nearest neighbour (a sample of at most 'sample' points)."""
    if len(xyz) < 2:
        return 0.0
    idx = np.linspace(0, len(xyz) - 1, min(sample, len(xyz))).astype(int)
    d = []
    for i in idx:
        r2 = ((xyz - xyz[i]) ** 2).sum(axis=1)
        r2[i] = np.inf
        d.append(r2.min())
    return float(np.sqrt(np.median(d)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rundir")
    ap.add_argument("--times", type=float, nargs="+", default=None, help="simulated times (s)")
    ap.add_argument("--out", default=None, help="PNG file (default RUN_DIR/<folder name>.png)")
    ap.add_argument("--axis", choices=["x", "y", "z"], default="y", help="projection axis (default y)")
    ap.add_argument("--field", choices=["p", "v"], default="p", help="colour: pressure p or speed |v|")
    ap.add_argument("--prefix", default=None, help="HDF5 series to draw (default: the only or first one)")
    ap.add_argument("--dump", default=None, help="grain dump series NAME (NAME_<step>.dump; default: all)")
    ap.add_argument("--grain-diameter", type=float, default=None, help="grain size when dumps have no radius")
    ap.add_argument("--vmax", type=float, default=None, help="top of the colour scale (kPa or m/s)")
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--slab", type=float, nargs=2, metavar=("LO", "HI"), default=None,
                    help="draw only what lies in [LO, HI] along the axis (m)")
    ap.add_argument("--zoom", type=float, nargs=4, metavar=("H0", "H1", "V0", "V1"), default=None,
                    help="axes limits: horizontal H0..H1, vertical V0..V1 (m)")
    ap.add_argument("--title", default=None, help="figure title (default: the run folder's name)")
    ap.add_argument("--labels", nargs="+", default=None, help="one text per --times entry, in the panel titles")
    a = ap.parse_args()
    if a.labels and (not a.times or len(a.labels) != len(a.times)):
        sys.exit("render_run: --labels expects one text per --times entry (%d times, %d labels)"
                 % (len(a.times or []), len(a.labels)))
    if a.slab and not a.slab[0] < a.slab[1]:
        sys.exit("render_run: --slab expects LO < HI (m), got %g %g" % tuple(a.slab))
    if a.zoom and not (a.zoom[0] < a.zoom[1] and a.zoom[2] < a.zoom[3]):
        sys.exit("render_run: --zoom expects H0 < H1 and V0 < V1 (m), got %g %g %g %g" % tuple(a.zoom))
    if not os.path.isdir(a.rundir):
        sys.exit("render_run: %s is not a folder" % a.rundir)

    prefix, frames = point_frames(a.rundir, a.prefix)
    if not frames:
        sys.exit("render_run: the HDF5 series '%s' in %s has no frame" % (prefix, a.rundir))
    times = np.array([f[1] for f in frames])
    labels = {}
    if a.times:
        pick = []
        for k, t in enumerate(a.times):
            i = int(np.argmin(np.abs(times - t)))
            if i not in pick:
                pick.append(i)
                if a.labels:
                    labels[i] = a.labels[k]
    else:
        pick = sorted({int(round(k)) for k in np.linspace(0, len(frames) - 1, min(4, len(frames)))})

    dumps = dump_series(a.rundir, a.dump)
    if a.dump and not dumps:
        sys.exit("render_run: no dump series %s_<step>.dump in %s" % (a.dump, a.rundir))

    h, v = VIEWS[a.axis]
    depth = [i for i in range(3) if i not in (h, v)][0]

    def in_slab(q):
        return np.ones(len(q), bool) if not a.slab else (q[:, depth] >= a.slab[0]) & (q[:, depth] <= a.slab[1])

    snaps, box = [], None
    for i in pick:
        step, t, path = frames[i]
        field = "p" if a.field == "p" else "v"
        try:
            xyz, vals, _ = read_points(path, [field])
        except KeyError:
            sys.exit("render_run: %s has no point field '%s' (add it to the fix's output list, or use --field %s)"
                     % (path, field, "v" if field == "p" else "p"))
        val = vals[field] / 1e3 if field == "p" else np.linalg.norm(vals[field], axis=1)
        keep = in_slab(xyz)
        xyz, val = xyz[keep], val[keep]
        grains, notes = [], []
        for name, by_step in sorted(dumps.items()):
            steps = np.array(sorted(by_step))
            s = int(steps[np.argmin(np.abs(steps - step))])
            fr = read_dump_frames(by_step[s], box=True)
            if not fr:
                continue
            _, cols, bounds = fr[0]
            if not all(c in cols for c in ("x", "y", "z")):
                continue
            if bounds and box is None:
                box = np.array(bounds)
            g = np.column_stack((cols["x"], cols["y"], cols["z"])) if len(cols["x"]) else np.zeros((0, 3))
            if "radius" in cols:
                rad = cols["radius"]
            elif a.grain_diameter:
                rad = np.full(len(g), 0.5 * a.grain_diameter)
            else:
                sys.exit("render_run: %s has no radius column: give --grain-diameter" % by_step[s])
            keep = in_slab(g)
            grains.append((g[keep], rad[keep]))
            if s != step:
                notes.append("%s at step %d" % (name, s))
        snaps.append((t, step, xyz, val, grains, notes, labels.get(i)))

    # the axes: what is drawn (points and grains of every panel, grains with their radius), or --zoom
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for _, _, xyz, _, grains, _, _ in snaps:
        if len(xyz):
            lo, hi = np.minimum(lo, xyz.min(axis=0)), np.maximum(hi, xyz.max(axis=0))
        for g, rad in grains:
            if len(g):
                lo = np.minimum(lo, (g - rad[:, None]).min(axis=0))
                hi = np.maximum(hi, (g + rad[:, None]).max(axis=0))
    if not np.all(np.isfinite(lo)):
        if box is None:
            sys.exit("render_run: nothing to draw (no point or grain%s)" % (" in the slab" if a.slab else ""))
        lo, hi = box[:, 0].copy(), box[:, 1].copy()
    pad = 0.03 * (hi - lo)[[h, v]].max() + 1e-12
    view = np.column_stack((lo - pad, hi + pad))
    if a.zoom:
        view[h], view[v] = a.zoom[0:2], a.zoom[2:4]
    spacing = nearest_spacing(snaps[0][2]) if len(snaps[0][2]) > 1 else 1e-3 * (view[h, 1] - view[h, 0])

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if a.field == "p":
        cmap, label = "viridis", "pressure (kPa)"
        vmin = min(0.0, min((np.percentile(s[3], 0.5) for s in snaps if len(s[3])), default=0.0))
    else:
        cmap, label, vmin = "turbo", "|v| (m/s)", 0.0
    vmax = a.vmax or max(max((np.percentile(s[3], 99.5) for s in snaps if len(s[3])), default=1.0), vmin + 1e-9)

    wx, wy = view[h, 1] - view[h, 0], view[v, 1] - view[v, 0]
    n = len(snaps)
    ncol = 1 if n == 1 else 2
    nrow = (n + ncol - 1) // ncol
    panel_w = 6.0
    fig, axes = plt.subplots(nrow, ncol, figsize=(panel_w * ncol + 1.2, nrow * (panel_w * wy / wx + 0.7) + 0.5),
                             squeeze=False, layout="constrained")
    sc = None
    for k, (t, step, xyz, val, grains, notes, plabel) in enumerate(snaps):
        ax = axes[k // ncol][k % ncol]
        ax.set_xlim(view[h, 0], view[h, 1])
        ax.set_ylim(view[v, 0], view[v, 1])
        ax.set_aspect("equal")
        fig.canvas.draw()
        pt_per_m = ax.get_window_extent().width / wx * 72.0 / fig.dpi
        # the farthest along the axis first: nearer points and grains on top
        o = np.argsort(-xyz[:, depth]) if a.axis != "z" else np.argsort(xyz[:, depth])
        sc = ax.scatter(xyz[o, h], xyz[o, v], c=val[o], s=(0.9 * spacing * pt_per_m) ** 2, marker="o",
                        linewidths=0, cmap=cmap, vmin=vmin, vmax=vmax, alpha=0.8, zorder=1, rasterized=True)
        for g, rad in grains:
            og = np.argsort(-g[:, depth]) if a.axis != "z" else np.argsort(g[:, depth])
            ax.scatter(g[og, h], g[og, v], s=(2.0 * rad[og] * pt_per_m) ** 2, c=BEADS, marker="o",
                       linewidths=0, zorder=2, rasterized=True)
        if box is not None:
            ax.plot([box[h, 0], box[h, 1], box[h, 1], box[h, 0], box[h, 0]],
                    [box[v, 0], box[v, 0], box[v, 1], box[v, 1], box[v, 0]], color="k", lw=0.8, zorder=3)
        title = ("%s: " % plabel if plabel else "") + "t = %.4g s (step %d)" % (t, step)
        if notes:
            title += "; " + ", ".join(notes)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("%s (m)" % NAMES[h], fontsize=8)
        ax.set_ylabel("%s (m)" % NAMES[v], fontsize=8)
        ax.tick_params(labelsize=7)
    for k in range(n, nrow * ncol):
        axes[k // ncol][k % ncol].axis("off")
    cb = fig.colorbar(sc, ax=axes.ravel().tolist(), shrink=0.6)
    cb.set_label(label, fontsize=9)
    name = os.path.basename(os.path.normpath(os.path.abspath(a.rundir)))
    ngr = sum(len(g) for g, _ in snaps[-1][4])
    fig.suptitle("%s%s%d material points%s, seen along %s%s" % (
        a.title or name, "\n" if a.title else ": ", len(snaps[-1][2]), (", %d grains" % ngr) if snaps[-1][4] else "", a.axis,
        (", %s in [%g, %g]" % (a.axis, a.slab[0], a.slab[1])) if a.slab else ""), fontsize=11)
    out = a.out or os.path.join(a.rundir, name + ".png")
    fig.savefig(out, dpi=a.dpi)
    print("wrote %s (%s: %d points, %d grains at the last time drawn; t = %s s; axes %s [%.6g, %.6g] %s [%.6g, %.6g])" % (
        out, prefix, len(snaps[-1][2]), ngr, ", ".join("%.4g" % s[0] for s in snaps), NAMES[h], view[h, 0],
        view[h, 1], NAMES[v], view[v, 0], view[v, 1]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
