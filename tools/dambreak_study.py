#!/usr/bin/env python3
"""Dam-break study: error against wall time for MPM16/24/32 and two bulk moduli.

Runs inputs/dambreak/in.dambreak (square water column, Martin & Moyce 1952) for
every (bulk modulus, cells) pair, each in its own work directory
<out>/<case>/, times each run (time.perf_counter around the subprocess), and
computes the RMS front and wall-height errors (units of the column width a)
with tools/dambreak_error.errors().

  tools/python tools/dambreak_study.py [--out dambreak-study] [--cells 16 24 32]
        [--bulk 2e7 2.2e9] [--projection] [--floor noslip] [--transfer apic] [--tend 3]
        [--np N] [--jobs J] [--skip-existing] [--quick]

Time step: automatic (the input's dtfactor*dx/(c + 2 sqrt(g h))) for the weakly
compressible bulk moduli, an explicit --dt-stiff (default 1e-5 s, as in the
dissertation) for bulk moduli >= --stiff-bulk (default 1e9 Pa, i.e. real
water, 2.2e9 Pa); --dt forces one explicit step for every case.

--projection adds the incompressible model (`-var pressure projection`, no bulk modulus; listed
with bulk 0 in results.csv and as "projection" in the tables and plots).

Writes <out>/results.csv, results.md, error_vs_walltime.png and fronts.png and
prints the table. --quick: cells 8 12 16, tend 1.0, weak bulk only.
Real water at MPM32 takes 10+ minutes on one core; progress is printed as each
case finishes.
"""
import argparse
import concurrent.futures as cf
import csv
import hashlib
import json
import math
import os
import re
import shutil
import subprocess
import sys
import threading
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.normpath(os.path.join(HERE, ".."))
sys.path.insert(0, HERE)
import dambreak_error  # noqa: E402
from mpm_io import read_csv  # noqa: E402

INPUT = os.path.join(TOP, "inputs", "dambreak", "in.dambreak")
EXE = os.path.join(TOP, "build", "liggghts_mpm")
COLUMNS = ["case", "cells", "bulk", "floor", "transfer", "dt", "points", "steps_if_known", "wall_s",
           "front_rms_a", "height_rms_a", "status", "message"]
_print_lock = threading.Lock()


def say(*args):
    with _print_lock:
        print(*args, flush=True)


def bulk_label(k):
    if k == 0:
        return "projection"
    s = "%.3g" % k
    return s.replace("e+0", "e").replace("e+", "e")


def model_label(k):
    return "projection" if k == 0 else "K = %s Pa" % bulk_label(k)


def case_name(c):
    model = "projection" if c["bulk"] == 0 else "K" + bulk_label(c["bulk"])
    name = "MPM%d_%s_%s" % (c["cells"], model, c["floor"])
    if c["pass_transfer"]:
        name += "_" + re.sub(r"[^A-Za-z0-9.]+", "", c["transfer"].replace(" ", "-"))
    return name


def parse_log(path):
    """(points, steps, dt, error line) from a LIGGGHTS log (None where unknown)."""
    points = steps = dt = None
    err = ""
    if not os.path.exists(path):
        return points, steps, dt, err
    nsteps = 0
    found_loop = False
    in_thermo = False
    with open(path, errors="replace") as f:
        for ln in f:
            m = re.search(r"created (\d+) material points", ln)
            if m:
                points = int(m.group(1))
            m = re.search(r"Loop time of \S+ on \d+ procs for (\d+) steps", ln)
            if m:
                nsteps += int(m.group(1))
                found_loop = True
                in_thermo = False
                continue
            if ln.lstrip().startswith("ERROR") and not err:
                err = ln.strip()
            if ln.split()[:2] == ["Step", "Time"]:
                in_thermo = True
                continue
            if in_thermo and dt is None:
                w = ln.split()
                try:
                    s, t = int(w[0]), float(w[1])
                    if s > 0 and t > 0:
                        dt = t / s
                except (ValueError, IndexError):
                    pass
    return points, (nsteps if found_loop else None), dt, err


def front_ok(csvpath, tend_s):
    """'' if front.csv is complete and finite, else a short reason."""
    if not os.path.exists(csvpath):
        return "no front.csv"
    try:
        d = read_csv(csvpath)
    except Exception as e:  # noqa: BLE001
        return "unreadable front.csv (%s)" % e
    if len(d["t"]) < 2:
        return "front.csv has no data"
    for k in ("t", "x_front", "h_wall"):
        if not np.all(np.isfinite(d[k])):
            i = int(np.argmax(~np.isfinite(d[k])))
            return "NaN in front.csv (%s at t = %.3g s)" % (k, d["t"][i])
    if d["t"][-1] < tend_s - 1e-6:
        return "front.csv ends at t = %.3g s < %.3g s" % (d["t"][-1], tend_s)
    return ""


def run_case(c, a, defaults):
    d = c["dir"]
    os.makedirs(d, exist_ok=True)
    meta_path = os.path.join(d, "run.json")
    key = {k: c[k] for k in ("cells", "bulk", "floor", "transfer", "dt_in", "tend", "np")}
    with open(a.input, "rb") as f:
        key["input_sha1"] = hashlib.sha1(f.read()).hexdigest()
    if a.skip_existing and os.path.exists(meta_path):
        try:
            with open(meta_path) as f:
                meta = json.load(f)
            if meta.get("key") == key and meta.get("status") == "ok" and \
                    os.path.exists(os.path.join(d, "front.csv")):
                meta["reused"] = True
                return meta
        except (OSError, ValueError):
            pass
    for fn in ("front.csv", "log.liggghts"):
        if os.path.exists(os.path.join(d, fn)):
            os.remove(os.path.join(d, fn))
    shutil.copy(a.input, os.path.join(d, "in.dambreak"))
    cmd = []
    if a.np > 1:
        cmd += ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(a.np)]
    cmd += [os.path.abspath(a.exe), "-in", "in.dambreak", "-echo", "none", "-screen", "none",
            "-var", "cells", str(c["cells"]),
            "-var", "floor", c["floor"], "-var", "tend", repr(c["tend"]), "-var", "h5every", "0"]
    cmd += ["-var", "pressure", "projection"] if c["bulk"] == 0 else ["-var", "pressure", "eos", "-var", "bulk", repr(c["bulk"])]
    if c["dt_in"] > 0:
        cmd += ["-var", "dt", repr(c["dt_in"])]
    if c["pass_transfer"]:
        cmd += ["-var", "extra", "transfer " + c["transfer"]]
    t0 = time.perf_counter()
    with open(os.path.join(d, "stdout.txt"), "w") as fo, open(os.path.join(d, "stderr.txt"), "w") as fe:
        rc = subprocess.run(cmd, cwd=d, stdout=fo, stderr=fe).returncode
    wall = time.perf_counter() - t0
    points, steps, dt, err = parse_log(os.path.join(d, "log.liggghts"))
    if not err:
        for fn in ("stdout.txt", "stderr.txt"):
            with open(os.path.join(d, fn), errors="replace") as f:
                for ln in f:
                    if "ERROR" in ln:
                        err = ln.strip()
                        break
            if err:
                break
    width, g = float(defaults.get("width", 4.0)), float(defaults.get("g", 9.81))
    outdt = float(defaults.get("outdt", 0.05))
    tend_s = c["tend"] * math.sqrt(width / g)
    why = front_ok(os.path.join(d, "front.csv"), tend_s - outdt)
    if rc != 0:
        status = "failed (exit %d)" % rc
    elif why.startswith("NaN"):
        status = "nan"
    elif why:
        status = "incomplete"
    else:
        status = "ok"
    msg = "; ".join(s for s in (err, why) if s)
    meta = {"key": key, "cmd": cmd, "returncode": rc, "wall_s": wall, "points": points, "steps": steps,
            "dt": dt if dt is not None else (c["dt_in"] or None), "status": status, "message": msg,
            "finished": time.strftime("%Y-%m-%dT%H:%M:%S"), "np": a.np, "jobs": a.jobs}
    with open(meta_path, "w") as f:
        json.dump(meta, f, indent=1)
    return meta


def fmt(v, spec):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return ""
    return spec % v


def write_outputs(rows, cases, a, width, g):
    with open(os.path.join(a.out, "results.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else r[k]) for k in COLUMNS})
    head = ["case", "cells", "bulk (Pa) or model", "floor", "transfer", "dt (s)", "points", "steps", "wall (s)",
            "front RMS / a", "height RMS / a", "status"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        vals = [r["case"], str(r["cells"]), bulk_label(r["bulk"]), r["floor"], r["transfer"],
                fmt(r["dt"], "%.3g"), fmt(r["points"], "%d"), fmt(r["steps_if_known"], "%d"),
                fmt(r["wall_s"], "%.1f"), fmt(r["front_rms_a"], "%.4f"), fmt(r["height_rms_a"], "%.4f"),
                r["status"] + ((": " + r["message"]) if r["message"] else "")]
        lines.append("| " + " | ".join(v.replace("|", "/") for v in vals) + " |")
    table = "\n".join(lines)
    with open(os.path.join(a.out, "results.md"), "w") as f:
        f.write("# Dam break (square column), error against wall time\n\n")
        f.write("Errors: RMS over the Martin & Moyce (1952) times inside the simulated range "
                "(tend = %g, T = t sqrt(g/a)), in units of the column width a = %g m.\n" % (a.tend, width))
        f.write("Wall time: whole LIGGGHTS run including %s s settling, %s.\n\n"
                % (dambreak_error.input_defaults(a.input).get("tsettle", "0.3"),
                   "one run at a time" if a.jobs == 1 else
                   "%d runs at a time (wall times are not comparable)" % a.jobs)
                + ("MPI: %d ranks.\n\n" % a.np if a.np > 1 else "\n"))
        f.write(table + "\n")
    plots(rows, cases, a, width, g)
    return table


def plots(rows, cases, a, width, g):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker  # noqa: F401

    front, height = dambreak_error.load_reference()
    groups = {}
    for r in rows:
        groups.setdefault((r["bulk"], r["floor"], r["transfer"]), []).append(r)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]

    # error against wall time
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    for gi, (key, rs) in enumerate(sorted(groups.items(), key=lambda kv: kv[0][0])):
        bulk, floor, transfer = key
        ok = sorted([r for r in rs if r["status"] == "ok" and r["front_rms_a"] is not None
                     and math.isfinite(r["front_rms_a"])], key=lambda r: r["cells"])
        if not ok:
            continue
        lab = model_label(bulk) + ("" if len(groups) == 1 else ", %s%s" % (
            floor, (", " + transfer) if transfer else ""))
        for ax, col in zip(axes, ("front_rms_a", "height_rms_a")):
            x = [r["wall_s"] for r in ok]
            y = [r[col] for r in ok]
            ax.plot(x, y, "o-", color=colors[gi % len(colors)], label=lab)
            for r, xi, yi in zip(ok, x, y):
                ax.annotate("MPM%d" % r["cells"], (xi, yi), textcoords="offset points", xytext=(5, 5),
                            fontsize=8, color=colors[gi % len(colors)])
    fmt_g = matplotlib.ticker.FuncFormatter(lambda v, _: "%g" % v)
    for ax, t in zip(axes, ("surge front", "water height at the wall")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.margins(0.15)
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_formatter(fmt_g)
            axis.set_minor_formatter(fmt_g)
        ax.tick_params(which="minor", labelsize=7)
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("RMS error / a")
        ax.set_title("%s vs Martin & Moyce (1952)" % t)
        ax.grid(True, which="both", alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "error_vs_walltime.png"), dpi=130)
    plt.close(fig)

    # fronts and heights
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    styles = ["-", "--", ":", "-."]
    cell_list = sorted({r["cells"] for r in rows})
    for gi, (key, rs) in enumerate(sorted(groups.items(), key=lambda kv: kv[0][0])):
        bulk, floor, transfer = key
        for r in sorted(rs, key=lambda r: r["cells"]):
            p = os.path.join(r["_dir"], "front.csv")
            if not os.path.exists(p):
                continue
            try:
                d = read_csv(p)
            except Exception:  # noqa: BLE001
                continue
            T = d["t"] * math.sqrt(g / width)
            lab = "MPM%d, %s" % (r["cells"], model_label(bulk))
            if len(groups) > len({k[0] for k in groups}):
                lab += ", %s%s" % (floor, (", " + transfer) if transfer else "")
            if r["status"] != "ok":
                lab += " (%s)" % r["status"]
            ci = cell_list.index(r["cells"])
            axes[0].plot(T, d["x_front"] / width, styles[gi % len(styles)], color=colors[ci % len(colors)],
                         label=lab, lw=1.4)
            axes[1].plot(T, d["h_wall"] / width, styles[gi % len(styles)], color=colors[ci % len(colors)],
                         lw=1.4)
    tmax = a.tend * 1.05
    kf, kh = front["T"] <= tmax, height["T"] <= tmax
    axes[0].plot(front["T"][kf], front["Z"][kf], "ks", mfc="none", label="Martin & Moyce (1952)")
    axes[1].plot(height["T"][kh], height["H"][kh], "ks", mfc="none", label="Martin & Moyce (1952)")
    axes[0].set_xlim(-0.02 * tmax, tmax)
    axes[1].set_xlim(-0.02 * tmax, tmax)
    axes[0].set_xlabel(r"$T = t\,\sqrt{g/a}$")
    axes[1].set_xlabel(r"$T = t\,\sqrt{g/a}$")
    axes[0].set_ylabel(r"$Z = x_{front}/a$")
    axes[1].set_ylabel(r"$H = h_{wall}/a$")
    axes[0].set_title("surge front")
    axes[1].set_title("water height at the wall")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7)
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "fronts.png"), dpi=130)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="dambreak-study", help="output folder (default ./dambreak-study)")
    ap.add_argument("--cells", type=int, nargs="+", default=[16, 24, 32])
    ap.add_argument("--bulk", type=float, nargs="+", default=[2.0e7, 2.2e9], help="bulk moduli (Pa)")
    ap.add_argument("--projection", action="store_true", help="also run 'pressure projection' (incompressible)")
    ap.add_argument("--floor", choices=["noslip", "freeslip"], default="noslip")
    ap.add_argument("--transfer", nargs="+", default=None,
                    help="passed as -var extra 'transfer X' (e.g. apic, pic, flip 0.99); default: the fix's")
    ap.add_argument("--tend", type=float, default=3.0, help="end time in units of sqrt(a/g)")
    ap.add_argument("--dt", type=float, default=0.0, help="explicit time step (s) for every case (0 = rule below)")
    ap.add_argument("--dt-stiff", type=float, default=1e-5, help="time step (s) for bulk >= --stiff-bulk")
    ap.add_argument("--stiff-bulk", type=float, default=1e9)
    ap.add_argument("--np", type=int, default=1, help="MPI ranks per run (mpirun)")
    ap.add_argument("--jobs", type=int, default=1, help="cases run at the same time (quick tests only)")
    ap.add_argument("--skip-existing", action="store_true", help="reuse finished cases (front.csv + run.json)")
    ap.add_argument("--quick", action="store_true", help="cells 8 12 16, tend 1.0, weak bulk only")
    ap.add_argument("--exe", default=EXE)
    ap.add_argument("--input", default=INPUT)
    a = ap.parse_args()
    if a.quick:
        a.cells = [8, 12, 16]
        a.tend = 1.0
        a.bulk = [2.0e7]
    if not os.path.exists(a.exe):
        sys.exit("no executable %s (build: cmake -S . -B build -G Ninja && cmake --build build)" % a.exe)
    if a.np > 1 and shutil.which("mpirun") is None:
        sys.exit("--np %d needs mpirun" % a.np)
    defaults = dambreak_error.input_defaults(a.input)
    width, g = float(defaults.get("width", 4.0)), float(defaults.get("g", 9.81))
    os.makedirs(a.out, exist_ok=True)
    transfer = " ".join(a.transfer) if a.transfer else defaults.get("transfer", "flip")
    pass_transfer = bool(a.transfer)

    cases = []
    for bulk in a.bulk + ([0.0] if a.projection else []):
        if bulk < 0 or (bulk == 0 and not a.projection):
            sys.exit("--bulk %g: a bulk modulus > 0 (Pa) is needed; for the incompressible model use --projection" % bulk)
        dt_in = a.dt if a.dt > 0 else (a.dt_stiff if bulk >= a.stiff_bulk else 0.0)
        for cells in a.cells:
            c = {"cells": cells, "bulk": bulk, "floor": a.floor, "transfer": transfer, "dt_in": dt_in,
                 "tend": a.tend, "np": a.np, "pass_transfer": pass_transfer}
            c["case"] = case_name(c)
            c["dir"] = os.path.join(a.out, c["case"])
            cases.append(c)

    say("dambreak study: %d cases, tend = %g, out = %s, %d rank(s) per run, %d job(s)"
        % (len(cases), a.tend, a.out, a.np, a.jobs))
    results = {}
    t_start = time.perf_counter()

    def finish(c, meta):
        try:
            ef, eh, n = dambreak_error.errors(os.path.join(c["dir"], "front.csv"), width, g) \
                if os.path.exists(os.path.join(c["dir"], "front.csv")) else (float("nan"),) * 3
        except Exception as e:  # noqa: BLE001
            ef = eh = float("nan")
            meta["message"] = (meta.get("message", "") + "; error evaluation failed: %s" % e).strip("; ")
        if meta["status"] not in ("ok", "incomplete"):
            ef = eh = float("nan")
        row = {"case": c["case"], "cells": c["cells"], "bulk": c["bulk"], "floor": c["floor"],
               "transfer": c["transfer"], "dt": meta.get("dt"), "points": meta.get("points"),
               "steps_if_known": meta.get("steps"), "wall_s": round(meta["wall_s"], 3),
               "front_rms_a": None if not math.isfinite(ef) else round(ef, 6),
               "height_rms_a": None if not math.isfinite(eh) else round(eh, 6),
               "status": meta["status"], "message": meta.get("message", ""), "_dir": c["dir"]}
        results[c["case"]] = row
        say("[%d/%d] %-28s %-10s wall %8.1f s  steps %7s  front RMS/a %s  height RMS/a %s%s%s"
            % (len(results), len(cases), c["case"], meta["status"], meta["wall_s"],
               meta.get("steps") or "?", fmt(row["front_rms_a"], "%.4f") or "-",
               fmt(row["height_rms_a"], "%.4f") or "-", "  (reused)" if meta.get("reused") else "",
               ("  " + row["message"]) if row["message"] else ""))

    def safe_run(c):
        try:
            return run_case(c, a, defaults)
        except Exception as e:  # noqa: BLE001
            return {"wall_s": float("nan"), "status": "failed", "message": "%s: %s" % (type(e).__name__, e)}

    if a.jobs <= 1:
        for c in cases:
            say("  running %s ..." % c["case"])
            finish(c, safe_run(c))
    else:
        with cf.ThreadPoolExecutor(max_workers=a.jobs) as ex:
            futs = {ex.submit(safe_run, c): c for c in cases}
            for fu in cf.as_completed(futs):
                finish(futs[fu], fu.result())
    rows = [results[c["case"]] for c in cases]
    table = write_outputs(rows, cases, a, width, g)
    print()
    print(table)
    print("\nwrote %s/{results.csv,results.md,error_vs_walltime.png,fronts.png} (total %.0f s)"
          % (a.out, time.perf_counter() - t_start))
    return 0 if all(r["status"] == "ok" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
