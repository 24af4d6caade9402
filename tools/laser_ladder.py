#!/usr/bin/env python3
"""Refinement ladders of laser_drill: a d(xi) ladder at a fixed step and a dt ladder at a fixed grid.

  tools/python tools/laser_ladder.py --out ladder/ [--dxi 0.05,0.025,0.0125,0.00625] [--dxi-dt 2.5e-7]
      [--dt 1e-6,5e-7,2.5e-7,1.25e-7] [--dt-dxi 0.0125] [--exe build/laser_drill] -- --pr 142 --pulse 200e-6

Everything after -- is passed to every run. For each run: status, causes, centre depth, removed
volume, flow share (volume expelled over the rim / removed volume), worst column demand over
its absorbed energy, b2 limiter hits, curvature clamps, CPU time. Observed orders from three
successive runs of a ladder with ratio 2: p = log2(|D1 - D2| / |D2 - D3|) (none where a difference
is zero or changes sign, i.e. not monotone). Writes ladder.csv and prints Markdown tables.
"""
import argparse
import csv
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from laser_common import find_exe, run_case  # noqa: E402

KEYS = ("depth_um", "volume_1e11", "flow_share")


def row_of(s, code, err):
    if s is None:
        return dict(status="exit %d" % code, causes=err.splitlines()[-1][:120] if err else "")
    share = s["melt_balance"]["expelled_over_rim_m3"] / s["volume_removed_m3"] if s["volume_removed_m3"] else 0.0
    return dict(status=s["status"], causes="; ".join(s.get("causes", [])),
                depth_um=s["depth_center_m"] * 1e6, volume_1e11=s["volume_removed_m3"] * 1e11, flow_share=share,
                column=s["energy_check"]["worst_node_demand_over_absorbed"],
                limiter=s["b2_limiter_hits"], clamps=s["curvature_clamps"], A_last=s.get("A_last"),
                cpu_s=s["cpu_time_s"])


def orders(rows, key):
    out = []
    for k in range(len(rows) - 2):
        try:
            d1 = rows[k][key] - rows[k + 1][key]
            d2 = rows[k + 1][key] - rows[k + 2][key]
        except (KeyError, TypeError):
            out.append(None)
            continue
        out.append(math.log2(abs(d1 / d2)) if d1 * d2 > 0 else None)
    return out


def fmt(v, f="%.5g"):
    return "-" if v is None else (f % v if isinstance(v, float) else str(v))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--exe")
    ap.add_argument("--dxi", default="0.05,0.025,0.0125,0.00625")
    ap.add_argument("--dxi-dt", default="2.5e-7", help="step of the d(xi) ladder [s]")
    ap.add_argument("--dt", default="1e-6,5e-7,2.5e-7,1.25e-7")
    ap.add_argument("--dt-dxi", default="0.0125", help="grid of the dt ladder")
    ap.add_argument("rest", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    rest = [x for x in a.rest if x != "--"]
    exe = find_exe(a.exe)
    os.makedirs(a.out, exist_ok=True)
    ladders = {"dxi": [("dxi", v, ["--dxi", v, "--dt", a.dxi_dt]) for v in a.dxi.split(",") if v],
               "dt": [("dt", v, ["--dt", v, "--dxi", a.dt_dxi]) for v in a.dt.split(",") if v]}
    table = []
    for name, runs in ladders.items():
        rows = []
        for _, v, args in runs:
            code, s, err = run_case(exe, os.path.join(a.out, "%s_%s" % (name, v)), args + rest)
            r = dict(ladder=name, value=v, **row_of(s, code, err))
            rows.append(r)
            table.append(r)
            print(r, file=sys.stderr, flush=True)
        print("\n%s ladder (%s): %s\n" % (name, " ".join(rest), ", ".join(v for _, v, _ in runs)))
        print("| %s | status | depth [um] | volume [1e-11 m3] | flow share | column | limiter | clamps | A | CPU [s] |" % name)
        print("|---|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            print("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                r["value"], r["status"], fmt(r.get("depth_um"), "%.3f"), fmt(r.get("volume_1e11"), "%.4f"),
                fmt(r.get("flow_share"), "%.4f"), fmt(r.get("column"), "%.3f"), fmt(r.get("limiter")),
                fmt(r.get("clamps")), fmt(r.get("A_last"), "%.1f"), fmt(r.get("cpu_s"), "%.2f")))
        for key in KEYS:
            print("observed order, %s: %s" % (key, " / ".join(fmt(p, "%.2f") for p in orders(rows, key))))
    with open(os.path.join(a.out, "ladder.csv"), "w", newline="") as f:
        keys = sorted({k for r in table for k in r})
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(table)


if __name__ == "__main__":
    main()
