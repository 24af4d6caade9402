#!/usr/bin/env python3
"""Error against run time for the verification and validation cases of the fluid and the coupling:
each case at several resolutions with both pressure models, its error against the case's
reference (CASES.md) and the run's wall time, as a table, a CSV and a log-log plot per case.

    tools/python tools/error_vs_time.py [CASE ...] [--exe build/liggghts_mpm] [--work /tmp/error_vs_time]
                                        [--models projection eos] [--out docs/img]

CASE (default: all): f1 f3 f4 c1 c5 c6 c8. The runs are those of tools/model_table.py (the same inputs,
analyses and references), at these resolutions:

  f1  hydrostatic column (inputs/hydrostatic), 8 / 16 / 32 cells: L2 pressure error over all points
      against rho g (h - z)
  f3  released column (inputs/tank/in.column), Grid20 / 40 / 80: |E_kin / E_inviscid - 1| at 0.02 s
      (eos at Grid80 with the step 8e-6 s, under its acoustic limit)
  f4  standing wave (inputs/sloshing/in.wave), 20 / 40 / 80 cells along the tank: |omega / omega_exact - 1|
      and |amplitude after three periods - 1|
  c1  one sphere settling (inputs/settling), cells 6 / 3 / 1.5 mm in a box of fixed size: the grain's
      velocity at the end (0.1 s) against the Schiller-Naumann relaxation curve at the same time (at
      0.1 s the curve is still 4e-4 below the terminal velocity)
  c5  random held bed (inputs/archimedes/in.bed), cells of 3 / 2 / 1.5 grain diameters (the bed's
      height kept): |fluid force / Archimedes - 1|, mid-depth and on the floor
  c6  hindered settling at solid fraction 0.2 (inputs/suspension), cells of 3 / 2 / 1.5 grain
      diameters (box about 8 x 8 x 24 mm): |settling velocity / reference - 1|
  c8  fluidized bed (inputs/fluidized_bed), cells of 3 / 2 / 1.5 bead diameters (box about
      18 x 18 x 86 mm), stages 0.01 0.02 0.025 0.04 0.045 m/s of 0.6 s, the projection only (the
      input's fluid step is above the stable step of pressure eos): |dP / (W/A) - 1| of the
      fluidized stages (the buoyant weight per area) and |U_mf / U_mf(Wen-Yu) - 1|

The other cases have their own error-against-run-time tools: F2 tools/dambreak_study.py, C3
tools/tank_fronts.py, the laser tools/laser_convergence.py; C2 (Ergun) is exact at any resolution.

Writes OUT/error_vs_walltime_cases.csv and OUT/error_vs_walltime_cases.png. Wall times are those of
one run each on the machine it ran on: compare within one run of this tool only. `--from-csv FILE`
draws the plot again from a CSV this tool wrote, without running anything.
"""
import argparse
import csv
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import model_table as mt  # noqa: E402


def emitted(row, *args, **kwargs):
    """The records that one call of a model_table row emits."""
    n0 = len(mt.OUT)
    row(*args, **kwargs)
    return mt.OUT[n0:]


def run_f1(r, models):
    for c in (8, 16, 32):
        for rec in emitted(mt.row_f1, r, models, cells=c, undamped=False):
            yield rec, f"{c} cells", c, {"L2 pressure error": rec["figures"]["L2_all"]}


def run_f3(r, models):
    for c in (20, 40, 80):
        for rec in emitted(mt.row_f3, r, models, cells=(c,), dt={"eos": 8e-6} if c == 80 else None):
            yield rec, f"Grid{c}", c, {"|KE/KE_inviscid - 1| at 0.02 s": abs(rec["figures"]["ke_ratio_0.02s"] - 1.0)}


def run_f4(r, models):
    for c in (20, 40, 80):
        for rec in emitted(mt.row_f4, r, models, cells=(c,)):
            f = rec["figures"]
            yield rec, f"{c} cells", c, {"|omega/omega_exact - 1|": abs(f["w_ratio"] - 1.0),
                                         "|amplitude after 3 periods - 1|": abs(f["amp_end_ratio"] - 1.0)}


def run_c1(r, models):
    # the box 24 x 24 x 36 mm at every cell size (the input's 8 x 8 x 12 cells of 3 mm)
    for cell_mm in (6.0, 3.0, 1.5):
        for rec in emitted(mt.row_c1, r, models, cell=cell_mm * 1e-3, nxy=round(24 / cell_mm), nz=round(36 / cell_mm)):
            yield rec, f"cell {cell_mm:g} mm", 1.0 / cell_mm, {"|v / v_SN(t) - 1| at the end": abs(rec["figures"]["end_over_curve"] - 1.0)}


def run_c5(r, models):
    # 150 grains at cell 1.5 d (model_table's C5); the box is 8 cells wide, so the grains grow with
    # the cell's area to keep the bed's height
    for cellf in (3.0, 2.0, 1.5):
        for rec in emitted(mt.row_c5, r, models, cellf=cellf, nbeads=round(150 * (cellf / 1.5) ** 2)):
            where = "mid-depth" if rec["settings"].startswith("mid-depth") else "floor"
            yield rec, f"cell {cellf:g} d", 1.0 / cellf, {f"|F / Archimedes - 1|, {where}": abs(rec["figures"]["archimedes_ratio"] - 1.0)}


def run_c6(r, models):
    # model_table's reduced C6 is 4 x 4 x 12 cells of 2 d: the same box (8 x 8 x 24 mm) at each cell
    for cellf in (3.0, 2.0, 1.5):
        for rec in emitted(mt.row_c6, r, models, phis=(0.2,), cellf=cellf, nxy=round(8 / cellf), nsus=round(24 / cellf)):
            yield rec, f"cell {cellf:g} d", 1.0 / cellf, {"|v / v_ref - 1|, solid fraction 0.2": abs(rec["figures"]["v_ratio"] - 1.0)}


def run_c8(r, models):
    # the fluidized bed's input is written for the default model (its fluid step, every 10 DEM
    # steps, is above the stable step of pressure eos, which refuses it): the projection only.
    # Stages 0.01, 0.02, 0.025 (fixed bed) and 0.04, 0.045 m/s (fluidized), 0.6 s each; the box
    # about 18 x 18 x 86 mm
    import time
    import fluidized_bed as fb
    if "projection" not in models:
        return
    for cellf in (3.0, 2.0, 1.5):
        work = os.path.join(r.work, "c8", f"cell{cellf:g}")
        v = [("Ulist", "0.01 0.02 0.025 0.04 0.045"), ("thold", 0.6), ("cellf", cellf),
             ("nxy", round(6 / cellf)), ("nz", round(28.5 / cellf))]
        t0 = time.time()
        fb.run(r.exe, work, v)
        wall = time.time() - t0
        with open(os.devnull, "w") as devnull:
            res = fb.analyse(work, out=devnull)
        mt.emit("C8", "projection", f"cell {cellf:g} d, stages 0.01-0.045 m/s of 0.6 s",
                {"plateau_over_W": res.get("plateau", float("nan")), "umf_m_s": res.get("umf", float("nan"))}, wall)
        yield mt.OUT[-1], f"cell {cellf:g} d", 1.0 / cellf, {
            "|dP / (W/A) - 1|, fluidized": res.get("plateau_dev", float("nan")),
            "|U_mf / U_mf(Wen-Yu) - 1|": abs(res["umf"] / res["umf_wy"] - 1.0) if "umf" in res else float("nan")}


CASES = {"f1": ("F1 hydrostatic column", run_f1), "f3": ("F3 released column", run_f3),
         "f4": ("F4 standing wave", run_f4), "c1": ("C1 settling sphere", run_c1),
         "c5": ("C5 Archimedes, held bed", run_c5), "c6": ("C6 hindered settling", run_c6),
         "c8": ("C8 fluidized bed (projection)", run_c8)}


def minor_label(v, _):
    m = v / 10 ** math.floor(math.log10(v) + 1e-9)
    return "%g" % v if any(abs(m - k) < 1e-6 for k in (2, 3, 5)) else ""


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    titles = []
    for r in rows:
        if r["case"] not in titles:
            titles.append(r["case"])
    ncol = 3
    nrow = (len(titles) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.0 * ncol, 4.0 * nrow), squeeze=False)
    marker = {"projection": "o", "eos": "s"}
    for ax, title in zip(axes.flat, titles):
        sel = [r for r in rows if r["case"] == title]
        for model in ("projection", "eos"):
            for metric in dict.fromkeys(r["metric"] for r in sel):
                pts = sorted((r for r in sel if r["model"] == model and r["metric"] == metric), key=lambda r: r["order"])
                pts = [p for p in pts if p["error"] > 0 and math.isfinite(p["error"])]
                if not pts:
                    continue
                ax.loglog([p["wall_s"] for p in pts], [p["error"] for p in pts], marker=marker[model],
                          ls="-" if model == "projection" else "--", label=f"{model}: {metric}")
                for p in pts:
                    ax.annotate(p["resolution"], (p["wall_s"], p["error"]), fontsize=7,
                                textcoords="offset points", xytext=(4, 3))
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("wall time of the run (s)")
        ax.set_ylabel("error against the reference")
        for axis in (ax.xaxis, ax.yaxis):  # minor ticks labelled at 2, 3 and 5 of each decade only
            axis.set_minor_formatter(matplotlib.ticker.FuncFormatter(minor_label))
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    for ax in list(axes.flat)[len(titles):]:
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cases", nargs="*", default=[], help="cases (default: all): " + " ".join(CASES))
    ap.add_argument("--exe", default=os.path.join(mt.TOP, "build", "liggghts_mpm"))
    ap.add_argument("--work", default="/tmp/error_vs_time")
    ap.add_argument("--models", nargs="+", default=["projection", "eos"], choices=["projection", "eos"])
    ap.add_argument("--out", default=".", help="folder of the CSV and the plot")
    ap.add_argument("--from-csv", default=None, help="only draw the plot from this CSV (written by this tool)")
    a = ap.parse_args()
    if a.from_csv:
        with open(a.from_csv) as f:
            rows = [dict(r, order=float(r["order"]), error=float(r["error"]), wall_s=float(r["wall_s"]))
                    for r in csv.DictReader(f)]
        os.makedirs(a.out, exist_ok=True)
        plot(rows, os.path.join(a.out, "error_vs_walltime_cases.png"))
        return
    names = a.cases or list(CASES)
    for n in names:
        if n not in CASES:
            sys.exit(f"error_vs_time.py: unknown case '{n}'; one of {' '.join(CASES)}")
    a.exe, a.work = os.path.abspath(a.exe), os.path.abspath(a.work)
    os.makedirs(a.out, exist_ok=True)
    r = mt.runner(a)
    rows = []
    for n in names:
        title, fn = CASES[n]
        for rec, res, order, errors in fn(r, a.models):
            for metric, err in errors.items():
                rows.append({"case": title, "model": rec["model"], "resolution": res, "order": order,
                             "metric": metric, "error": err, "wall_s": rec["wall_s"]})
    print("\ncase | model | resolution | error | wall time (s)")
    for x in rows:
        print(f"{x['case']} | {x['model']} | {x['resolution']} | {x['metric']} {x['error']:.3g} | {x['wall_s']:.1f}")
    path = os.path.join(a.out, "error_vs_walltime_cases.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["case", "model", "resolution", "order", "metric", "error", "wall_s"],
                           extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    plot(rows, os.path.join(a.out, "error_vs_walltime_cases.png"))
    print(f"wrote {path} and error_vs_walltime_cases.png")


if __name__ == "__main__":
    main()
