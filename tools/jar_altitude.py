#!/usr/bin/env python3
"""Maximum altitude of the bead bed in the rotating jar (CASES.md C4, dissertation 10.3).

Reads the bead dumps (beads_<step>.dump) and jar_run.txt of one or more run folders of
inputs/jar/in.jar. For every dump after the start of the rotation:
  * bed beads = beads with at least --contacts neighbours whose centres are closer than
    --gap x d (beads flying above the bed or sliding alone along the wall do not count);
  * altitude = largest (z + d/2) of a bed bead, measured from the jar bottom (z = 0);
  * zmax = largest z + d/2 of any bead.
The steady-state altitude is the mean (and standard deviation) over the dumps from --from-turn
turns on; the experiment (Sun et al. 2013): 62.18 mm, standard deviation 1.71 mm.

  tools/python tools/jar_altitude.py RUNDIR [RUNDIR ...] [--from-turn 1] [--out jar_altitude]
Writes OUT.csv (run,t,turn,altitude_mm,zmax_mm,nbed) and OUT.png.
It also checks each run's jar.csv (rows of a resumed run replace the rows after its restart
step): the fluid mass (largest relative deviation from the first row), non-finite values, and the
largest point pressure (median / 95th percentile / largest from --from-turn on).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mpm_io import dump_series, read_csv, read_dump, read_key_values  # noqa: E402

EXPERIMENT_MM, EXPERIMENT_STD_MM = 62.18, 1.71


def read_info(d):
    """jar_run.txt of a run folder (written by in.jar) as {key: string}."""
    return read_key_values(os.path.join(d, "jar_run.txt"))


def bed_altitude(x, rad, contacts=3, gap=1.2):
    """(altitude, zmax, number of bed beads): see the module text."""
    if len(x) == 0:
        return float("nan"), float("nan"), 0
    d = 2.0 * rad.max()
    cut = gap * d
    # neighbour counts: beads sorted by z, each block of 256 against the beads within cut in z
    order = np.argsort(x[:, 2], kind="stable")
    xs = x[order]
    z = xs[:, 2]
    nnb_sorted = np.zeros(len(x), dtype=int)
    for a in range(0, len(x), 256):
        b = min(a + 256, len(x))
        lo, hi = np.searchsorted(z, z[a] - cut, "left"), np.searchsorted(z, z[b - 1] + cut, "right")
        dd = ((xs[a:b, None, :] - xs[None, lo:hi, :]) ** 2).sum(axis=2)
        nnb_sorted[a:b] = (dd < cut * cut).sum(axis=1) - 1
    nnb = np.empty_like(nnb_sorted)
    nnb[order] = nnb_sorted
    top = x[:, 2] + rad
    bed = nnb >= contacts
    alt = top[bed].max() if bed.any() else float("nan")
    return alt, top.max(), int(bed.sum())


def analyse(d, contacts, gap):
    info = read_info(d)
    dt, n0, period = float(info["dt"]), int(float(info["rot_start_step"])), float(info["period"])
    rows = []
    for step, path in dump_series(d, "beads").get("beads", {}).items():
        if step < n0:
            continue
        t = (step - n0) * dt
        b = read_dump(path)
        x = np.column_stack((b["x"], b["y"], b["z"])) if len(b["x"]) else np.zeros((0, 3))
        alt, zmax, nbed = bed_altitude(x, b["radius"], contacts=contacts, gap=gap)
        rows.append((t, t / period, 1e3 * alt, 1e3 * zmax, nbed))
    rows.sort()
    return info, rows


def read_jar_csv(d):
    """jar.csv as {column: array}, one row per time (the last row of a time that a resumed run
    wrote again), or None."""
    path = os.path.join(d, "jar.csv")
    return read_csv(path, keep_last_of="t") if os.path.exists(path) else None


def csv_summary(c, from_turn):
    """One line on the fluid mass, the finiteness and the largest pressure of a jar.csv."""
    if c is None or len(c["t"]) == 0:
        return "no jar.csv rows"
    finite = all(np.isfinite(v).all() for v in c.values())
    m = c["mass"]
    dev = np.abs(m - m[0]).max() / m[0]
    p = c["pmax"][c["turn"] >= from_turn]
    ptxt = (f"largest pressure median {np.median(p) / 1e3:.1f} / 95 % {np.percentile(p, 95) / 1e3:.1f} / "
            f"max {p.max() / 1e3:.1f} kPa" if len(p) else "no pressure rows yet")
    return (f"jar.csv: {len(m)} rows to turn {c['turn'][-1]:.2f}, {'all finite' if finite else 'NON-FINITE VALUES'}, "
            f"fluid mass {m[0]:.15g} kg (largest rel. deviation {dev:.1e}), {ptxt}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--from-turn", type=float, default=1.0, help="steady state from this turn on (default 1)")
    ap.add_argument("--contacts", type=int, default=3, help="neighbours a bed bead needs (default 3)")
    ap.add_argument("--gap", type=float, default=1.2, help="neighbour distance in diameters (default 1.2)")
    ap.add_argument("--out", default="jar_altitude")
    a = ap.parse_args()
    out_rows, series = [], []
    for d in a.runs:
        info, rows = analyse(d, a.contacts, a.gap)
        if not rows:
            print(f"{d}: no bead dump after the start of the rotation", file=sys.stderr)
            continue
        label = f"{os.path.basename(os.path.normpath(d))} ({info.get('wall', '?')}, cells {info.get('cells', '?')})"
        steady = np.array([r[2] for r in rows if r[1] >= a.from_turn])
        print(f"{label}: {len(rows)} dumps up to turn {rows[-1][1]:.2f}")
        print("  " + csv_summary(read_jar_csv(d), a.from_turn))
        if len(steady):
            print(f"  steady state (turn >= {a.from_turn}): bed altitude {steady.mean():.2f} mm "
                  f"(std {steady.std():.2f} mm, {len(steady)} dumps); experiment {EXPERIMENT_MM} mm "
                  f"(std {EXPERIMENT_STD_MM} mm); difference {steady.mean() - EXPERIMENT_MM:+.2f} mm")
        else:
            print(f"  no dump at turn >= {a.from_turn} yet")
        for r in rows:
            out_rows.append((d,) + r)
        series.append((label, rows))
    if not out_rows:
        return 1
    with open(a.out + ".csv", "w") as f:
        f.write("run,t,turn,altitude_mm,zmax_mm,nbed\n")
        for r in out_rows:
            f.write(f"{r[0]},{r[1]:.6g},{r[2]:.6g},{r[3]:.6g},{r[4]:.6g},{r[5]}\n")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for label, rows in series:
        ax.plot([r[1] for r in rows], [r[2] for r in rows], marker="o", ms=3, label=label)
    ax.axhspan(EXPERIMENT_MM - EXPERIMENT_STD_MM, EXPERIMENT_MM + EXPERIMENT_STD_MM, color="0.85",
               label="experiment 62.18 ± 1.71 mm")
    ax.set_xlabel("turns")
    ax.set_ylabel("bed altitude (mm)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.out + ".png", dpi=120)
    print(f"wrote {a.out}.csv, {a.out}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
