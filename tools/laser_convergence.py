#!/usr/bin/env python3
"""Error against run time for laser_drill (Table 5.1 case, 7.5e10 W/m2, 700 us,
rising-fall xi_p = 1): ladders of time steps and grid spacings, errors of the
centre depth and the removed volume against a converged reference run.

  tools/python tools/laser_convergence.py --out conv/ [--exe build/laser_drill] [--repeat 3]

Writes conv/convergence.csv, conv/convergence.md and conv/convergence.png
(log-log error against wall time). Wall time is the minimum over --repeat runs
as measured by laser_drill itself (summary.json: wall_time_s).
"""
import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from laser_common import find_exe, run_case  # noqa: E402

REFERENCE = {"dt": 2.5e-8, "dxi": 0.003125}
DT_LADDER = [1e-5, 8e-6, 4e-6, 2e-6, 1e-6, 5e-7, 2.5e-7, 1e-7, 5e-8]
DXI_LADDER = [0.1, 0.05, 0.025, 0.0125, 0.00625]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="laser_convergence")
    ap.add_argument("--exe")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    exe = find_exe(a.exe)
    os.makedirs(a.out, exist_ok=True)

    def run(dt, dxi, repeat):
        best = None
        for k in range(repeat):
            d = os.path.join(a.out, "dt%g_dxi%g" % (dt, dxi))
            code, s, err = run_case(exe, d, ["--dt", dt, "--dxi", dxi])
            if s is None:
                return None, err.splitlines()[-1] if err else "exit %d" % code
            if best is None or s["wall_time_s"] < best["wall_time_s"]:
                best = s
        return best, ""

    print("reference run dt = %g s, dxi = %g ..." % (REFERENCE["dt"], REFERENCE["dxi"]), file=sys.stderr)
    ref, err = run(REFERENCE["dt"], REFERENCE["dxi"], 1)
    if ref is None:
        sys.exit("reference run failed: " + err)
    rows = []
    ladder = [("dt", dt, 0.0125) for dt in DT_LADDER] + [("dxi", 2.5e-7, dx) for dx in DXI_LADDER]
    for kind, dt, dxi in ladder:
        s, err = run(dt, dxi, a.repeat)
        row = {"ladder": kind, "dt_s": dt, "dxi": dxi}
        if s is None:
            row.update(status="rejected", note=err)
        else:
            row.update(status=s["status"], depth_center_m=s["depth_center_m"], volume_removed_m3=s["volume_removed_m3"],
                       err_depth=abs(s["depth_center_m"] / ref["depth_center_m"] - 1.0),
                       err_volume=abs(s["volume_removed_m3"] / ref["volume_removed_m3"] - 1.0),
                       wall_time_s=s["wall_time_s"], steps=s["steps"], nodes=s["nodes"], note=s["message"])
        rows.append(row)
        print(row, file=sys.stderr)
    keys = ["ladder", "dt_s", "dxi", "status", "steps", "nodes", "wall_time_s", "depth_center_m", "err_depth",
            "volume_removed_m3", "err_volume", "note"]
    with open(os.path.join(a.out, "convergence.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    with open(os.path.join(a.out, "convergence.md"), "w") as f:
        f.write("Reference: dt = %g s, dxi = %g: depth %.7e m, volume %.7e m3, wall %.2f s\n\n"
                % (REFERENCE["dt"], REFERENCE["dxi"], ref["depth_center_m"], ref["volume_removed_m3"],
                   ref["wall_time_s"]))
        f.write("| ladder | dt [s] | dxi | steps | nodes | wall [s] | rel. error depth | rel. error volume |\n")
        f.write("|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            if r["status"] == "rejected":
                f.write("| %s | %g | %g | - | - | - | rejected: %s | |\n" % (r["ladder"], r["dt_s"], r["dxi"], r["note"][:90]))
            else:
                f.write("| %s | %g | %g | %d | %d | %.3f | %.2e | %.2e |\n"
                        % (r["ladder"], r["dt_s"], r["dxi"], r["steps"], r["nodes"], r["wall_time_s"],
                           r["err_depth"], r["err_volume"]))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for kind, mk in (("dt", "o"), ("dxi", "s")):
        sel = [r for r in rows if r["ladder"] == kind and r["status"] != "rejected"]
        for key, ls in (("err_depth", "-"), ("err_volume", "--")):
            pts = [(r["wall_time_s"], max(r[key], 1e-12)) for r in sel]
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], ls, marker=mk,
                      label="%s ladder, %s" % (kind, "centre depth" if key == "err_depth" else "removed volume"))
    ax.axhline(1e-3, color="gray", lw=0.8)
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel("relative error vs reference")
    ax.set_title("laser_drill, Table 5.1, 7.5e10 W/m2, rising-fall xi_p = 1")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "convergence.png"), dpi=120)
    print("wrote %s/convergence.{csv,md,png}" % a.out)


if __name__ == "__main__":
    main()
