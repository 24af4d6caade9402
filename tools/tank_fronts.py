#!/usr/bin/env python3
"""Fronts of the C3 tank runs (inputs/tank/in.tank) and their convergence against wall time.

  tools/python tools/tank_fronts.py RUNDIR [RUNDIR ...] [--ref RUNDIR] [--labels L1 L2 ...] [--cpu]
        [--times 0.05 0.10 0.15 0.20] [--out PREFIX]

Every RUNDIR is the work folder of one run of in.tank; it holds fronts.csv (t, x_water, x_beads,
...; t = 0 at the start of the lift; lines starting with '#' are skipped), tank_run.txt (grid and
points per cell) and, for the wall time, time.txt written by /usr/bin/time (plain or -v format);
without time.txt the sum of the LIGGGHTS "Loop time of ..." lines of log.liggghts (or out.txt) is
used.

Prints, per run: the water and bead fronts at --times (linear interpolation), the wall time and,
against the reference run (--ref, default: the run with the most cells, then the most points per
cell), the RMS and the largest difference of x_water and x_beads over the common time range
(the reference's output times up to the shorter of the two runs). Writes
  PREFIX_fronts.png       x_water (solid) and x_beads (dashed) against t for every run
  PREFIX_convergence.png  difference from the reference against wall time (log-log), water and beads
  PREFIX_convergence.csv  the table
(PREFIX defaults to 'tank' in the current folder). With a single RUNDIR only the fronts are drawn.

The largest bead x is sensitive to single beads thrown ahead of the bed. So, where the run folder
holds the bead dumps (beads_<step>.dump) and HDF5 point files, a second table gives at the snapshot
nearest to each --times value the 99th percentile of the bead x and of the point x (--pct).
"""
import argparse
import math
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mpm_io import paired_frames, read_csv, read_dump, read_key_values, read_points  # noqa: E402


def wall_time(rundir, cpu=False):
    """Seconds: /usr/bin/time output (time.txt), else the sum of LIGGGHTS loop times. cpu: the
    user + system time of time.txt instead of the elapsed time (runs that shared the cores)."""
    p = os.path.join(rundir, "time.txt")
    if os.path.exists(p):
        txt = open(p).read()
        if cpu:
            u = re.search(r"User time \(seconds\):\s*([\d.]+)", txt)
            k = re.search(r"System time \(seconds\):\s*([\d.]+)", txt)
            if u and k:
                return float(u.group(1)) + float(k.group(1)), "cpu"
        m = re.search(r"Elapsed \(wall clock\) time[^:]*:\s*([\d:.]+)", txt)
        if not m:
            m = re.search(r"([\d:.]+)elapsed", txt)
        if m:
            parts = [float(x) for x in m.group(1).split(":")]
            s = 0.0
            for x in parts:
                s = 60.0 * s + x
            return s, "time"
    for name in ("log.liggghts", "out.txt"):
        p = os.path.join(rundir, name)
        if os.path.exists(p):
            loops = re.findall(r"Loop time of ([\d.eE+-]+) on", open(p).read())
            if loops:
                return sum(float(x) for x in loops), "loops"
    return float("nan"), "none"


def label_of(info, rundir):
    if "cells" in info:
        npc = int(info.get("pnx", 1) * info.get("pny", 1) * info.get("pnz", 1))
        lab = "Grid%d_%dp" % (int(info["cells"]), npc)
        if str(info.get("transfer", "apic")) != "apic":
            lab += "_" + str(info["transfer"]).replace(" ", "")
        if int(info.get("nbeads", 7762)) != 7762:
            lab += "_%db" % int(info.get("nbeads", 0))
        return lab
    return os.path.basename(os.path.normpath(rundir))


def at(t, x, tq):
    if tq < t[0] - 1e-12 or tq > t[-1] + 1e-12:
        return float("nan")
    return float(np.interp(tq, t, x))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rundirs", nargs="+")
    ap.add_argument("--ref", default=None, help="reference run folder (default: the finest)")
    ap.add_argument("--labels", nargs="+", default=None)
    ap.add_argument("--times", type=float, nargs="+", default=[0.05, 0.10, 0.15, 0.20])
    ap.add_argument("--out", default="tank", help="output prefix")
    ap.add_argument("--cpu", action="store_true",
                    help="cost = user + system time of time.txt (/usr/bin/time -v) instead of the wall "
                         "time: for runs that shared the cores")
    ap.add_argument("--pct", type=float, default=99.0, help="percentile of the snapshot table")
    a = ap.parse_args()

    runs = []
    for k, d in enumerate(a.rundirs):
        p = os.path.join(d, "fronts.csv")
        if not os.path.exists(p):
            print("skip %s: no fronts.csv" % d, file=sys.stderr)
            continue
        info = read_key_values(os.path.join(d, "tank_run.txt"), numbers=True, missing_ok=True)
        c = read_csv(p, keep_last_of="t")
        wt, src = wall_time(d, a.cpu)
        lab = a.labels[k] if a.labels and k < len(a.labels) else label_of(info, d)
        npc = info.get("pnx", 1) * info.get("pny", 1) * info.get("pnz", 1)
        runs.append(dict(dir=d, info=info, c=c, wall=wt, wsrc=src, label=lab,
                         cells=info.get("cells", 0), npc=npc))
    if not runs:
        sys.exit("no run with fronts.csv")

    if a.ref:
        ref = next((r for r in runs if os.path.normpath(r["dir"]) == os.path.normpath(a.ref)), None)
        if ref is None:
            sys.exit("--ref %s is not among the runs" % a.ref)
    else:
        ref = max(runs, key=lambda r: (r["cells"], r["npc"]))

    # fronts at the requested times
    hdr = "%-20s %9s" % ("run", "wall[s]")
    for tq in a.times:
        hdr += "  xw(%.2f) xb(%.2f)" % (tq, tq)
    print(hdr)
    for r in runs:
        t, xw, xb = r["c"]["t"], r["c"]["x_water"], r["c"]["x_beads"]
        line = "%-20s %9.1f" % (r["label"], r["wall"])
        for tq in a.times:
            line += "  %8.4f %8.4f" % (at(t, xw, tq), at(t, xb, tq))
        print(line)

    # percentile fronts from the snapshots
    try:
        head = False
        for r in runs:
            info = r["info"]
            if "gate_start_step" not in info:
                continue
            fr = paired_frames(r["dir"], str(info.get("prefix", "tank")))
            if not fr:
                continue
            if not head:
                print("\n%g-th percentile of x in the snapshots (water points, beads):" % a.pct)
                head = True
            steps = np.array(sorted(fr))
            n0, dt = int(info["gate_start_step"]), info["dt"]
            line = "%-20s" % r["label"]
            for tq in a.times:
                s_ = int(steps[np.argmin(np.abs(steps - (n0 + tq / dt)))])
                if abs((s_ - n0) * dt - tq) > 0.5 * info.get("tsnap", 0.05) + 1e-9:
                    line += "  t=%.3f %7s %7s" % (tq, "-", "-")
                    continue
                h5, dump = fr[s_]
                xw = read_points(h5)[0][:, 0]
                xb = read_dump(dump)["x"]
                line += "  t=%.3f %7.4f %7.4f" % ((s_ - n0) * dt, np.percentile(xw, a.pct),
                                                   np.percentile(xb, a.pct) if len(xb) else float("nan"))
            print(line)
    except ImportError as exc:  # h5py missing
        print("(no snapshot table: %s)" % exc)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for k, r in enumerate(sorted(runs, key=lambda r: (r["cells"], r["npc"]))):
        col = "C%d" % (k % 10)
        t = r["c"]["t"]
        ax.plot(t, r["c"]["x_water"], "-", color=col, label=r["label"] + " water")
        ax.plot(t, r["c"]["x_beads"], "--", color=col, label=r["label"] + " beads")
    L = ref["info"].get("L", 0.2)
    ax.axhline(L, color="0.6", lw=0.8)
    ax.set_xlabel("t after the start of the lift (s)")
    ax.set_ylabel("front position x (m)")
    ax.set_title("C3 tank: water front (solid) and bead front (dashed)")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(a.out + "_fronts.png", dpi=150)
    print("wrote", a.out + "_fronts.png")

    if len(runs) < 2:
        return

    # differences from the reference over the reference's times common to both runs
    tr = ref["c"]["t"]
    rows = []
    print("\nreference: %s (%s)" % (ref["label"], ref["dir"]))
    print("%-20s %6s %4s %9s %11s %11s %11s %11s" % ("run", "cells", "ppc", "wall[s]", "rms_water", "max_water",
                                                   "rms_beads", "max_beads"))
    for r in runs:
        t = r["c"]["t"]
        tmax = min(t[-1], tr[-1])
        m = tr <= tmax + 1e-12
        tt = tr[m]
        dw = np.interp(tt, t, r["c"]["x_water"]) - ref["c"]["x_water"][m]
        db = np.interp(tt, t, r["c"]["x_beads"]) - ref["c"]["x_beads"][m]
        row = dict(run=r["label"], dir=r["dir"], cells=int(r["cells"]), ppc=int(r["npc"]), wall=r["wall"],
                   tmax=tmax, rms_water=float(np.sqrt(np.mean(dw ** 2))), max_water=float(np.max(np.abs(dw))),
                   rms_beads=float(np.sqrt(np.mean(db ** 2))), max_beads=float(np.max(np.abs(db))))
        rows.append(row)
        print("%-20s %6d %4d %9.1f %11.5f %11.5f %11.5f %11.5f" % (row["run"], row["cells"], row["ppc"], row["wall"],
                                                                 row["rms_water"], row["max_water"],
                                                                 row["rms_beads"], row["max_beads"]))
    with open(a.out + "_convergence.csv", "w") as f:
        keys = ["run", "cells", "ppc", "wall", "tmax", "rms_water", "max_water", "rms_beads", "max_beads", "dir"]
        f.write(",".join(keys) + "\n")
        for row in rows:
            f.write(",".join(str(row[k]) for k in keys) + "\n")
    print("wrote", a.out + "_convergence.csv")

    fig, ax = plt.subplots(figsize=(6, 4.5))
    others = [rw for rw in rows if rw["dir"] != ref["dir"] and math.isfinite(rw["wall"])]
    # one line per series: the grid series (points per cell of the reference) and the
    # points-per-cell series (cells of the reference); any other run as single markers
    series = [("grid series, %d points/cell" % int(ref["npc"]), [rw for rw in others if rw["ppc"] == int(ref["npc"])]),
              ("points/cell series, Grid%d" % int(ref["cells"]), [rw for rw in others if rw["cells"] == int(ref["cells"])
                                                                 and rw["ppc"] != int(ref["npc"])])]
    rest = [rw for rw in others if all(rw not in grp for _, grp in series)]
    if rest:
        series.append(("other runs", rest))
    for k, (name, grp) in enumerate(series):
        if not grp:
            continue
        grp = sorted(grp, key=lambda rw: (rw["cells"], rw["ppc"]))  # in order of resolution
        w = [rw["wall"] for rw in grp]
        ls = "" if name == "other runs" else "-"
        ax.loglog(w, [max(rw["rms_water"], 1e-6) for rw in grp], "o" + ls, color="C%d" % k,
                  label=name + ": water")
        ax.loglog(w, [max(rw["rms_beads"], 1e-6) for rw in grp], "s" + (ls and "-") + "-", color="C%d" % k,
                  mfc="none", label=name + ": beads")
        for rw in grp:
            ax.annotate(rw["run"], (rw["wall"], max(rw["rms_water"], 1e-6)), fontsize=7,
                        textcoords="offset points", xytext=(4, 4))
    ax.set_xlabel("CPU time, user + system (s)" if a.cpu else "wall time (s)")
    ax.set_ylabel("RMS difference from %s (m)" % ref["label"])
    ax.set_title("C3 tank: convergence against cost")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(a.out + "_convergence.png", dpi=150)
    print("wrote", a.out + "_convergence.png")


if __name__ == "__main__":
    main()
