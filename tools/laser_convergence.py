#!/usr/bin/env python3
"""Error against run time for laser_drill (Table 5.1 case, 7.5e10 W/m2, 700 us,
rising-fall xi_p = 1): the default automatic step over a ladder of --tol, ladders of
fixed time steps and of grid spacings, errors of the centre depth and the removed
volume against a converged reference run of the same melt layer.

  tools/python tools/laser_convergence.py --out conv/ [--melt-energy advected|text]
      [--exe build/laser_drill] [--repeat 3]

Writes conv/convergence.csv, conv/convergence.md and conv/convergence.png
(log-log error against CPU time). Every run includes laser_drill's step-doubling
companion run (the price of the error estimate). Times are the minimum over --repeat
runs: wall as measured by laser_drill itself (summary.json: wall_time_s), CPU
(user + system) of the process, which depends much less on the load of the machine.
The auto ladder also lists laser_drill's own error estimate next to the measured error.
"""
import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from laser_common import find_exe, run_case  # noqa: E402

REFERENCE = {"dt": 2.5e-8, "dxi": 0.003125}
TOL_LADDER = [1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4]
DT_LADDER = [1e-5, 8e-6, 4e-6, 2e-6, 1e-6, 5e-7, 2.5e-7, 1e-7, 5e-8]
DXI_LADDER = [0.1, 0.05, 0.025, 0.0125, 0.00625]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="laser_convergence")
    ap.add_argument("--exe")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--melt-energy", choices=("advected", "text"), default="advected",
                    help="melt layer of every run, reference included (laser_drill default: advected)")
    a = ap.parse_args()
    exe = find_exe(a.exe)
    os.makedirs(a.out, exist_ok=True)

    def run(dt, dxi, repeat, tol=None):
        """dt None: automatic step with --tol tol. Minimum wall and CPU time over repeat runs."""
        best = None
        args = ["--dxi", dxi, "--melt-energy", a.melt_energy]
        args += ["--tol", tol] if dt is None else ["--dt", dt]
        name = ("tol%g" % tol if dt is None else "dt%g" % dt) + "_dxi%g" % dxi
        for k in range(repeat):
            code, s, err = run_case(exe, os.path.join(a.out, name), args)
            if s is None:
                return None, err.splitlines()[-1] if err else "exit %d" % code
            if best is None:
                best = s
            best["wall_time_s"] = min(best["wall_time_s"], s["wall_time_s"])
            best["cpu_time_s"] = min(best["cpu_time_s"], s["cpu_time_s"])
        return best, ""

    print("reference run dt = %g s, dxi = %g ..." % (REFERENCE["dt"], REFERENCE["dxi"]), file=sys.stderr)
    ref, err = run(REFERENCE["dt"], REFERENCE["dxi"], 1)
    if ref is None:
        sys.exit("reference run failed: " + err)
    rows = []
    ladder = ([("tol", None, 0.0125, tol) for tol in TOL_LADDER] + [("dt", dt, 0.0125, None) for dt in DT_LADDER]
              + [("dxi", 2.5e-7, dx, None) for dx in DXI_LADDER])
    for kind, dt, dxi, tol in ladder:
        s, err = run(dt, dxi, a.repeat, tol)
        row = {"ladder": kind, "tol": "" if tol is None else tol, "dt_s": dt, "dxi": dxi}
        if s is None:
            row.update(status="rejected", note=err)
        else:
            ts = s["time_step"]
            row.update(status=s["status"], dt_s=ts["dt_s"], depth_center_m=s["depth_center_m"],
                       volume_removed_m3=s["volume_removed_m3"],
                       err_depth=abs(s["depth_center_m"] / ref["depth_center_m"] - 1.0),
                       err_volume=abs(s["volume_removed_m3"] / ref["volume_removed_m3"] - 1.0),
                       est_depth=ts["depth_error_estimate"], est_volume=ts["volume_error_estimate"],
                       wall_time_s=s["wall_time_s"], cpu_time_s=s["cpu_time_s"], steps=s["steps"],
                       steps_total=ts["steps_total"], nodes=s["nodes"], note=s["message"])
        rows.append(row)
        print(row, file=sys.stderr)
    keys = ["ladder", "tol", "dt_s", "dxi", "status", "steps", "steps_total", "nodes", "wall_time_s", "cpu_time_s",
            "depth_center_m", "err_depth", "est_depth", "volume_removed_m3", "err_volume", "est_volume", "note"]
    with open(os.path.join(a.out, "convergence.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    with open(os.path.join(a.out, "convergence.md"), "w") as f:
        ts = ref["time_step"]
        f.write("Melt layer %s. Reference: dt = %g s, dxi = %g: depth %.7e m, volume %.7e m3 (own estimate "
                "%.1e / %.1e), wall %.2f s, CPU %.2f s\n\n"
                % (a.melt_energy, REFERENCE["dt"], REFERENCE["dxi"], ref["depth_center_m"], ref["volume_removed_m3"],
                   ts["depth_error_estimate"], ts["volume_error_estimate"], ref["wall_time_s"], ref["cpu_time_s"]))
        f.write("| ladder | --tol | dt [s] | dxi | status | steps (all runs) | nodes | wall [s] | CPU [s] "
                "| error depth (estimate) | error volume (estimate) |\n")
        f.write("|---|---|---|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            if r["status"] == "rejected":
                f.write("| %s | %s | %g | %g | rejected: %s | | | | | | |\n"
                        % (r["ladder"], r["tol"], r["dt_s"], r["dxi"], r["note"][:90]))
            else:
                f.write("| %s | %s | %.3g | %g | %s | %d (%d) | %d | %.3f | %.3f | %.2e (%.1e) | %.2e (%.1e) |\n"
                        % (r["ladder"], r["tol"], r["dt_s"], r["dxi"], r["status"], r["steps"], r["steps_total"],
                           r["nodes"], r["wall_time_s"], r["cpu_time_s"], r["err_depth"], r["est_depth"],
                           r["err_volume"], r["est_volume"]))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for kind, mk in (("tol", "^"), ("dt", "o"), ("dxi", "s")):
        sel = [r for r in rows if r["ladder"] == kind and r["status"] != "rejected"]
        for key, ls in (("err_depth", "-"), ("err_volume", "--")):
            pts = [(r["cpu_time_s"], max(r[key], 1e-12)) for r in sel]
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], ls, marker=mk,
                      label="%s ladder, %s" % ("automatic step, --tol" if kind == "tol" else kind,
                                               "centre depth" if key == "err_depth" else "removed volume"))
    ax.axhline(1e-3, color="gray", lw=0.8)
    ax.set_xlabel("CPU time [s] (incl. the step-doubling companion run)")
    ax.set_ylabel("relative error vs reference")
    ax.set_title("laser_drill, Table 5.1, 7.5e10 W/m2, rising-fall xi_p = 1,\n%s melt layer" % a.melt_energy,
                 fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "convergence.png"), dpi=120)
    print("wrote %s/convergence.{csv,md,png}" % a.out)


if __name__ == "__main__":
    main()
