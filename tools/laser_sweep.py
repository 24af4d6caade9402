#!/usr/bin/env python3
"""Sweep of laser_drill over centre intensities and melt-flow models, or over any options.

  tools/python tools/laser_sweep.py --out sweep/ [--full] [--melt-energy advected|text] [--exe build/laser_drill]
  tools/python tools/laser_sweep.py --out sweep/ --vary pulse=100e-6,300e-6,700e-6 --vary pr=0.142,142 [-- --dxi 0.025]

--vary OPTION=V1,V2,... (any laser_drill option without its dashes, repeatable) runs the
Cartesian product of the values instead of the intensity x model table; every option
given and the run's case (summary.json "case") are columns of sweep.csv. Without --exe the
newest build*/laser_drill of this repository is used (then PATH).

Writes one run directory per case under --out and the table sweep.csv
(intensity, model, parameter, melt layer, status, removal rate, depth, T_peak,
p_peak, flow share, wall and CPU time). --full adds every m and xi_p of chapter 5.
--melt-energy text uses the dissertation's linear melt layer (chapter 5's numbers);
the default is laser_drill's energy-consistent advected layer.
"""
import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mpm_io  # noqa: E402
from laser_common import find_exe, run_case  # noqa: E402

INTENSITIES = [2.5e10, 5.0e10, 7.5e10, 10.0e10, 12.5e10, 14.3e10, 16.0e10]


def cases(full):
    yield "conduction", None, []
    for m in ([1.5, 2, 3, 4, 5] if full else [2]):
        yield "rising", m, ["--m", m]
    for xp in ([0.2, 0.4, 0.6, 0.8, 1.0, 1.5] if full else [0.6, 1.0]):
        yield "risingfall", xp, ["--xi-p", xp]


def summary_row(s):
    share = s["melt_balance"]["expelled_over_rim_m3"] / s["volume_removed_m3"] if s.get("volume_removed_m3") else None
    row = dict(status=s["status"], causes="; ".join(s.get("causes", [])),
               removal_rate_m3_per_s=s["removal_rate_m3_per_s"], volume_removed_m3=s["volume_removed_m3"],
               depth_center_m=s["depth_center_m"], T_peak_K=s["T_peak_K"], p_peak_Pa=s["p_peak_Pa"],
               flow_share=share, melt_balance=s["melt_balance"]["relative_residual"],
               depth_error_estimate=s["time_step"]["depth_error_estimate"] if s["status"] != "diverged" else None,
               volume_error_estimate=s["time_step"]["volume_error_estimate"] if s["status"] != "diverged" else None,
               dt_s=s["dt_s"], wall_time_s=s["wall_time_s"], cpu_time_s=s["cpu_time_s"], message=s["message"])
    for k, v in s["case"].items():
        row["case." + k] = v
    return row


def vary_sweep(a):
    import itertools
    axes = []
    for v in a.vary:
        if "=" not in v:
            sys.exit("--vary: expected OPTION=V1,V2,..., got %r" % v)
        opt, vals = v.split("=", 1)
        opt = opt.lstrip("-")
        values = [x for x in vals.split(",") if x]
        if not opt or not values:
            sys.exit("--vary: expected OPTION=V1,V2,..., got %r" % v)
        axes.append((opt, values))
    exe = find_exe(a.exe)
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for combo in itertools.product(*[vals for _, vals in axes]):
        opts = list(zip([o for o, _ in axes], combo))
        name = "_".join("%s%s" % (o, v) for o, v in opts).replace("/", "_")
        args = [x for o, v in opts for x in ("--" + o, v)] + a.extra
        code, s, err = run_case(exe, os.path.join(a.out, name), args)
        row = {"option." + o: v for o, v in opts}
        row.update(extra=" ".join(a.extra), dir=name, exit_code=code)
        if s:
            row.update(summary_row(s))
        else:
            # exit 2: refused; before computing, or (explicit update) by the run-time check of (4-14)
            after = "(4-14) unstable at" in err
            row.update(status=("refused after running" if after else "refused") if code == 2 else "error",
                       message=err.splitlines()[-1] if err else "")
        rows.append(row)
        print("%-40s %-12s %s" % (name, row["status"], row.get("message", "")), file=sys.stderr)
    mpm_io.write_rows(os.path.join(a.out, "sweep.csv"), rows)
    print("wrote %s" % os.path.join(a.out, "sweep.csv"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="laser_sweep")
    ap.add_argument("--exe")
    ap.add_argument("--full", action="store_true")
    ap.add_argument("--melt-energy", choices=("advected", "text"), default="advected")
    ap.add_argument("--intensities", type=float, nargs="*", default=INTENSITIES)
    ap.add_argument("--vary", action="append", default=[], metavar="OPTION=V1,V2,...",
                    help="sweep this laser_drill option over the values (repeatable: Cartesian product)")
    ap.add_argument("extra", nargs="*", help="extra laser_drill options after --")
    a = ap.parse_args()
    if a.vary:
        return vary_sweep(a)
    exe = find_exe(a.exe)
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for I in a.intensities:
        for model, par, args in cases(a.full):
            name = "I%.3g_%s%s" % (I, model, "" if par is None else "_%g" % par)
            d = os.path.join(a.out, name)
            code, s, err = run_case(exe, d, ["--intensity", I, "--model", model,
                                                "--melt-energy", a.melt_energy] + args + a.extra)
            row = {"intensity_W_per_m2": I, "model": model, "parameter": "" if par is None else par, "dir": name,
                   "melt_energy": a.melt_energy, "exit_code": code}
            if s:
                row.update(status=s["status"], removal_rate_m3_per_s=s["removal_rate_m3_per_s"],
                           volume_removed_m3=s["volume_removed_m3"], depth_center_m=s["depth_center_m"],
                           T_peak_K=s["T_peak_K"], p_peak_Pa=s["p_peak_Pa"],
                           flow_share=(s["volume_removed_by_flow_m3"] / s["volume_removed_m3"]
                                       if s["volume_removed_m3"] else 0.0),
                           wall_time_s=s["wall_time_s"], cpu_time_s=s["cpu_time_s"], message=s["message"])
            else:
                row.update(status="error", message=err.splitlines()[-1] if err else "")
            rows.append(row)
            print("%-32s %-20s %s" % (name, row["status"], row.get("message", "")), file=sys.stderr)
    keys = ["intensity_W_per_m2", "model", "parameter", "melt_energy", "status", "removal_rate_m3_per_s", "volume_removed_m3",
            "depth_center_m", "T_peak_K", "p_peak_Pa", "flow_share", "wall_time_s", "cpu_time_s", "exit_code", "dir", "message"]
    with open(os.path.join(a.out, "sweep.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    print("wrote %s" % os.path.join(a.out, "sweep.csv"))


if __name__ == "__main__":
    main()
