#!/usr/bin/env python3
"""Benchmark harness (docs/validation/performance.md).

  tools/python tools/bench.py [--quick] [--out DIR] [--np 2] [--only SECTION ...]

Sections (all by default):
  mpm       3-D pure-fluid dam break (inputs/bench/in.dambreak3d, quadratic B-splines, double
            precision): material-point-steps per second serially and on --np ranks (uniform cuts and
            with fix balance/mpm), parallel efficiency t1 / (np t_np), memory per point (peak RSS
            minus a run with 512 points). Quick: 100k points, 300 timed steps, the serial and the
            balanced runs twice (interleaved, the faster of each counts); full: 30k, 100k, 250k.
            Then the Taichi reference (tools/taichi_dambreak.py: the same dam break at 97,336
            points, CPU MLS-MPM in float64) on 1 and 2 threads in the same run, and the ratios to
            it. Taichi runs in its own venv, .venv-bench (tools/requirements-bench.txt, created on
            first use); if it cannot be installed or imported the Taichi rows are nan with the
            reason in the note, and the rest still runs (--no-taichi skips it). Then the write
            time per HDF5 output (hdf5_write_s_per_output: --np ranks; _1rank) in runs of their own.
  coupling  C3 tank (inputs/tank/in.tank) at Grid40 x 8 (32000 points, 7762 beads), a short segment
            (dry phase 20 steps, 50 coupled settling + 50 lift steps), one rank: the fix's own
            timers (f_ID[14], f_ID[15], printed after each run) split the wall time into the
            fluid's work and the coupling (fluid fraction, pressure fit, drag and pressure
            exchange); the rest of LIGGGHTS' "Loop time" is LIGGGHTS (DEM, neighbour lists, other
            fixes) and output. coupling_overhead_fraction = coupling / fluid. Then a pure-fluid
            dam break under valgrind --tool=callgrind (collected inside Verlet::run): the coupling
            code must not run, and the hot spots. Full mode adds the wall time of the whole tank
            case (about 30 min on one core).
  laser     one Table 5.1 case (inputs/laser/table51.toml), wall time of the process; full mode:
            the sweep of tools/laser_sweep.py --full (every model x 7 intensities) on 1 and 2 cores.
  sph       2-D square-column dam break against Martin & Moyce: LIGGGHTS SPH
            (inputs/bench/in.sph_dambreak) and fix mpm/fluid (inputs/dambreak/in.dambreak, K = 2e7)
            at several resolutions, one rank each; RMS front error (units of a) and wall time;
            sph_over_mpm_walltime_same_error = SPH wall time / MPM wall time at the same error,
            interpolated log-log on each method's error-vs-wall-time front.

Writes DIR/results.csv (metric,value,unit,note), DIR/results.md, DIR/runs.csv (every run),
plots DIR/*.png, DIR/hotspots.md, and bench-results.csv (metric,value,unit) in the current
folder. Quick mode takes about 2-4 minutes on 2 quiet cores. Timings depend on the load of the
machine (the load average at the start and the end is in bench_total_s's note).
"""
import argparse
import concurrent.futures as cf
import csv
import math
import os
import platform
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.normpath(os.path.join(HERE, ".."))
sys.path.insert(0, HERE)
import dambreak_error  # noqa: E402
import laser_sweep  # noqa: E402
import mpm_io  # noqa: E402
from laser_common import run_case  # noqa: E402

# idle ranks yield the core: the machine is shared with other jobs (no effect on an idle machine)
MPIRUN = ["mpirun", "--allow-run-as-root", "--oversubscribe", "--mca", "mpi_yield_when_idle", "1"]
RESULTS = []  # (metric, value, unit, note)
RUNS = []     # dicts


def say(*a):
    print(*a, flush=True)


def add(metric, value, unit, note=""):
    RESULTS.append((metric, value, unit, note))
    say("  %-44s %12s %-22s %s" % (metric, fmt(value), unit, note))


def fmt(v):
    if isinstance(v, float):
        return "%.4g" % v
    return str(v)


def run(cmd, cwd, timeout=3600, rss=False):
    """Runs cmd in cwd; returns (wall s, stdout text, peak RSS kB or None)."""
    os.makedirs(cwd, exist_ok=True)
    if rss:
        cmd = ["/usr/bin/time", "-v", "-o", os.path.join(cwd, "time.txt")] + cmd
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       errors="replace", timeout=timeout)
    wall = time.perf_counter() - t0
    with open(os.path.join(cwd, "output.txt"), "w") as f:
        f.write(p.stdout)
    if p.returncode != 0:
        tail = "\n".join(p.stdout.splitlines()[-12:])
        raise RuntimeError("%s failed (%d) in %s:\n%s" % (" ".join(cmd[:6]), p.returncode, cwd, tail))
    peak = None
    if rss:
        with open(os.path.join(cwd, "time.txt")) as f:
            m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", f.read())
            peak = int(m.group(1)) if m else None
    return wall, p.stdout, peak


def loop_times(text):
    return [(float(m.group(1)), int(m.group(2)), int(m.group(3))) for m in
            re.finditer(r"Loop time of (\S+) on (\d+) procs for (\d+) steps", text)]


def lig(a, np_):
    return (MPIRUN + ["-np", str(np_)] if np_ > 1 else []) + [a.exe]


# ---------------------------------------------------------------- 3-D pure-fluid dam break

REBAL = 50  # fix balance/mpm ... every REBAL measured yes in the balanced runs


def mpm_run(a, cells, np_, balance, nsteps, tag, rss=False, h5every=0, pressure="eos"):
    d = os.path.join(a.out, "mpm3d", tag)
    shutil.rmtree(d, ignore_errors=True)
    cmd = lig(a, np_) + ["-in", os.path.join(TOP, "inputs", "bench", "in.dambreak3d"), "-echo", "none",
                         "-var", "cells", str(cells), "-var", "nsteps", str(nsteps), "-var", "warm", "10",
                         "-var", "balance", str(balance), "-var", "h5every", str(h5every),
                         "-var", "pressure", pressure, "-var", "measured", "yes" if balance else "no",
                         # balanced runs re-cut every REBAL steps by the work measured since the last cut, so
                         # that a cut from a disturbed warm-up does not stay for the whole timed run
                         "-var", "rebal", str(REBAL if balance else 0)]
    wall, out, peak = run(cmd, d, rss=rss)
    lt = loop_times(out)
    points = int(re.search(r"created (\d+) material points", out).group(1))
    loop = lt[1][0]  # the timed run (the first is the warm-up)
    r = dict(section="mpm3d", case=tag, cells=cells, np=np_, balance=balance, points=points, steps=nsteps,
             loop_s=loop, wall_s=wall, point_steps_per_s=points * nsteps / loop, peak_rss_kB=peak)
    ms = re.findall(r"((?:measured )?imbalance) (\S+) -> (\S+)\)", out)
    m = ms[-1] if ms else None  # the balance of the timed run (the last one)
    if m:
        r["imbalance"] = "%s %s -> %s" % m
    if h5every > 0:  # the fix's output time in the timed run (slowest rank), printed after it
        w = re.findall(r"output \S+ s \((\d+) files, (\S+) s per file\)", out)[-1]
        r["h5_files"], r["h5_s_per_file"] = int(w[0]), float(w[1])
        r["h5_file_bytes"] = max(os.path.getsize(os.path.join(d, f)) for f in os.listdir(d) if f.endswith(".h5"))
    RUNS.append(r)
    say("    %-22s %8d points, %4d steps: loop %.3f s, %.3g point-steps/s%s" %
        (tag, points, nsteps, loop, r["point_steps_per_s"], ", " + r["imbalance"] if m else ""))
    return r


def section_projection(a, c):
    """The same dam break with pressure projection (hypre PCG + PFMG, advective step 0.25 dx / vref):
    1 rank and a.np ranks with fix balance/mpm, 100 steps (quick: 2 interleaved repeats)."""
    nsteps = 100
    s1 = mpm_run(a, c, 1, 0, nsteps, "c%d_np1_projection" % c, pressure="projection")
    sb = mpm_run(a, c, a.np, 1, nsteps, "c%d_np%d_balance_projection" % (c, a.np), pressure="projection")
    note = "%d points, %d steps after 10 warm-up steps, pressure projection" % (s1["points"], nsteps)
    if a.quick:
        s1 = with_repeat(a, s1, c, 1, 0, nsteps, pressure="projection")
        sb = with_repeat(a, sb, c, a.np, 1, nsteps, pressure="projection")
        note += ", faster of 2 interleaved repeats"
    add("mpm_point_steps_per_s_per_core_projection", s1["point_steps_per_s"], "point-steps/s",
        note + ", serial (loop s %s)" % s1.get("repeats_loop_s", "%.3f" % s1["loop_s"]))
    add("mpm_parallel_efficiency_%dranks_projection" % a.np, s1["loop_s"] / (a.np * sb["loop_s"]), "0..1",
        note + ", fix balance/mpm (loop s %s)" % sb.get("repeats_loop_s", "%.3f" % sb["loop_s"]))


def with_repeat(a, r, cells, np_, balance, nsteps, **kw):
    """The faster of run r and a repeat of it (tag r's case + '_repeat')."""
    return faster(r, mpm_run(a, cells, np_, balance, nsteps, r["case"] + "_repeat", **kw))


def faster(r1, r2):
    """The faster of two repeats of the same run (the machine is shared: load only slows a run down)."""
    best = dict(r1 if r1["loop_s"] <= r2["loop_s"] else r2)
    best["repeats_loop_s"] = "%.3f %.3f" % (r1["loop_s"], r2["loop_s"])
    return best


def section_mpm(a):
    say("== mpm: 3-D dam break")
    sizes = [23] if a.quick else [16, 23, 32]
    nsteps = 300 if a.quick else 100
    base = mpm_run(a, 4, 1, 0, 10, "baseline_c4", rss=True)
    table = []
    for c in sizes:
        s1 = mpm_run(a, c, 1, 0, nsteps, "c%d_np1" % c, rss=True)
        sb = mpm_run(a, c, a.np, 1, nsteps, "c%d_np%d_balance" % (c, a.np))
        su = mpm_run(a, c, a.np, 0, nsteps, "c%d_np%d_uniform" % (c, a.np))
        note = "%d points, %d steps after 10 warm-up steps" % (s1["points"], nsteps)
        mem = (s1["peak_rss_kB"] - base["peak_rss_kB"]) * 1024.0 / (s1["points"] - base["points"])
        if a.quick:  # interleaved repeats: a burst of load on the shared machine hits one of each at most
            s1 = with_repeat(a, s1, c, 1, 0, nsteps)
            sb = with_repeat(a, sb, c, a.np, 1, nsteps)
            note += ", faster of 2 interleaved repeats"
        eff_u = s1["loop_s"] / (a.np * su["loop_s"])
        eff_b = s1["loop_s"] / (a.np * sb["loop_s"])
        table.append((c, s1, su, sb, eff_u, eff_b, mem))
        sfx = "" if c == 23 else "_%dk" % round(s1["points"] / 1000.0)
        add("mpm_point_steps_per_s_per_core" + sfx, s1["point_steps_per_s"], "point-steps/s",
            note + ", serial (loop s %s)" % s1.get("repeats_loop_s", "%.3f" % s1["loop_s"]))
        add("mpm_point_steps_per_s_%dranks%s" % (a.np, sfx), sb["point_steps_per_s"], "point-steps/s",
            note + ", %d ranks, fix balance/mpm (loop s %s)" % (a.np, sb.get("repeats_loop_s", "%.3f" % sb["loop_s"])))
        add("mpm_parallel_efficiency_%dranks%s" % (a.np, sfx), eff_b, "0..1",
            note + ", fix balance/mpm measured yes (cut at the setup of the timed run by the work measured in the warm-up "
            "and every %d steps by the work since the last cut)" % REBAL)
        add("mpm_parallel_efficiency_%dranks_uniform%s" % (a.np, sfx), eff_u, "0..1",
            "%d points, %d steps, uniform LIGGGHTS cuts (all points on one rank), one run" % (s1["points"], nsteps))
        add("mpm_memory_per_point" + sfx, mem, "bytes/point",
            "peak RSS minus the 512-point run, divided by the extra points (grid included)")
        if c == 23:
            section_projection(a, c)
            section_taichi(a, s1, sb, nsteps)
            section_hdf5(a, c)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(5.5, 4))
        pts = [t[1]["points"] for t in table]
        ax.plot(pts, [t[1]["point_steps_per_s"] / 1e6 for t in table], "o-", label="1 rank")
        ax.plot(pts, [t[2]["point_steps_per_s"] / 1e6 / a.np for t in table], "s--",
                label="%d ranks, uniform cuts (per rank)" % a.np)
        ax.plot(pts, [t[3]["point_steps_per_s"] / 1e6 / a.np for t in table], "^-",
                label="%d ranks, balance/mpm (per rank)" % a.np)
        ax.axhline(3.0, color="k", lw=0.8, ls=":", label="target 3 M/s/core")
        ax.set_xscale("log")
        ax.set_xlabel("material points")
        ax.set_ylabel("M point-steps / s / core")
        ax.set_title("3-D dam break, bspline2, double")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, "mpm_throughput.png"), dpi=120)
        plt.close(fig)
    except ImportError:
        pass


def section_hdf5(a, cells):
    """Write time per HDF5 output of the 3-D dam break (points v p rho id, grid mass v), every 10
    steps of 60 timed ones, on 1 rank and on --np ranks; separate runs, the other figures are
    timed without output."""
    lib = subprocess.run(["ldd", a.exe], stdout=subprocess.PIPE, text=True).stdout
    how = "parallel HDF5 (MPI-IO, each rank its rows)" if re.search(r"libhdf5_(openmpi|mpich)", lib) \
        else "serial HDF5 (rank 0 gathers and writes)"
    for np_, metric in ((a.np, "hdf5_write_s_per_output"), (1, "hdf5_write_s_per_output_1rank")):
        r = mpm_run(a, cells, np_, 1 if np_ > 1 else 0, 60, "c%d_np%d_hdf5" % (cells, np_), h5every=10)
        say("    %-22s %d files of %.1f MB: %.4f s per file" % ("", r["h5_files"], r["h5_file_bytes"] / 1e6,
                                                                r["h5_s_per_file"]))
        add(metric, r["h5_s_per_file"], "s",
            "%d points, %d rank(s), %s; %d files of %.1f MB in 60 steps (page cache, no fsync); wall time of "
            "the fix's output call, slowest rank" % (r["points"], np_, how, r["h5_files"], r["h5_file_bytes"] / 1e6))


# ---------------------------------------------------------------- Taichi reference

BENCH_VENV = os.path.join(TOP, ".venv-bench")
BENCH_REQ = os.path.join(HERE, "requirements-bench.txt")


def bench_python():
    """(python of .venv-bench with Taichi, None) or (None, why not). Created from tools/requirements-bench.txt
    on first use and re-installed when that file is newer, like tools/python does for .venv: Taichi pins its
    own numpy and LLVM runtime, so it stays out of the tools' venv."""
    py = os.path.join(BENCH_VENV, "bin", "python")
    stamp = os.path.join(BENCH_VENV, ".requirements-installed")

    def step(cmd, what):
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, errors="replace")
        if p.returncode != 0:
            last = [ln for ln in p.stdout.splitlines() if ln.strip()][-1:] or ["exit %d" % p.returncode]
            raise RuntimeError("%s failed: %s" % (what, last[0].strip()))

    try:
        if not os.path.exists(stamp) or os.path.getmtime(BENCH_REQ) > os.path.getmtime(stamp):
            say("    installing tools/requirements-bench.txt into %s" % BENCH_VENV)
            step(["python3", "-m", "venv", BENCH_VENV], "python3 -m venv .venv-bench")
            step([py, "-m", "pip", "install", "-q", "--disable-pip-version-check", "-r", BENCH_REQ],
                 "pip install -r tools/requirements-bench.txt")
            open(stamp, "w").close()
        step([py, "-c", "import taichi"], "import taichi in .venv-bench")
    except (RuntimeError, OSError) as e:
        return None, str(e)
    return py, None


def taichi_run(a, py, threads, nsteps, tag):
    d = os.path.join(a.out, "taichi", tag)
    shutil.rmtree(d, ignore_errors=True)
    wall, out, _ = run([py, os.path.join(HERE, "taichi_dambreak.py"), "--cells", "23", "--threads", str(threads),
                        "--warm", "10", "--nsteps", str(nsteps)], d)
    m = re.search(r"taichi_dambreak: points (\d+) steps (\d+) threads (\d+) loop_s (\S+) point_steps_per_s (\S+) "
                  r"front_x (\S+) mass (\S+) taichi (\S+)", out)
    if not m:
        raise RuntimeError("no result line from taichi_dambreak.py in %s" % d)
    r = dict(section="taichi", case=tag, cells=23, np=threads, points=int(m.group(1)), steps=int(m.group(2)),
             loop_s=float(m.group(4)), wall_s=wall, point_steps_per_s=float(m.group(5)), front_x=float(m.group(6)),
             version=m.group(8))
    RUNS.append(r)
    say("    %-22s %8d points, %4d steps: loop %.3f s, %.3g point-steps/s (Taichi %s, %d thread%s)" %
        (tag, r["points"], r["steps"], r["loop_s"], r["point_steps_per_s"], r["version"], threads,
         "s" if threads > 1 else ""))
    return r


def section_taichi(a, s1, sb, nsteps):
    """Taichi's CPU MLS-MPM on the same dam break, 1 and a.np threads; the MPM figures as ratios to it."""
    say("== taichi: the same 3-D dam break, CPU MLS-MPM (tools/taichi_dambreak.py)")
    many = "%dthreads" % a.np
    metrics = [("taichi_point_steps_per_s_1thread", "point-steps/s"),
               ("taichi_point_steps_per_s_" + many, "point-steps/s"),
               ("taichi_parallel_efficiency_" + many, "0..1"),
               ("mpm_over_taichi_1core", "ratio"), ("mpm_over_taichi_%dcores" % a.np, "ratio"),
               ("mpm_over_taichi_parallel_efficiency", "ratio")]
    why = "skipped (--no-taichi)" if a.no_taichi else None
    py = None
    if why is None:
        py, why = bench_python()
    if why is None:
        try:
            t1 = taichi_run(a, py, 1, nsteps, "threads1")
            tn = taichi_run(a, py, a.np, nsteps, "threads%d" % a.np)
            if a.quick:
                t1 = faster(t1, taichi_run(a, py, 1, nsteps, "threads1_repeat"))
                tn = faster(tn, taichi_run(a, py, a.np, nsteps, "threads%d_repeat" % a.np))
        except (RuntimeError, subprocess.TimeoutExpired, OSError) as e:
            why = "taichi_dambreak.py failed: %s" % str(e).splitlines()[-1]
    if why is not None:
        say("!! Taichi reference absent: " + why)
        for m, u in metrics:
            add(m, float("nan"), u, "absent: " + why)
        return
    note = "Taichi %s, %d points, %d steps after 10 warm-up steps (JIT), float64, cpu_max_num_threads %%d%s" % (
        t1["version"], t1["points"], nsteps, ", faster of 2 interleaved repeats" if a.quick else "")
    eff_t = tn["point_steps_per_s"] / (a.np * t1["point_steps_per_s"])
    eff_m = sb["point_steps_per_s"] / (a.np * s1["point_steps_per_s"])
    add(metrics[0][0], t1["point_steps_per_s"], "point-steps/s",
        note % 1 + " (loop s %s)" % t1.get("repeats_loop_s", "%.3f" % t1["loop_s"]))
    add(metrics[1][0], tn["point_steps_per_s"], "point-steps/s",
        note % a.np + " (loop s %s)" % tn.get("repeats_loop_s", "%.3f" % tn["loop_s"]))
    add(metrics[2][0], eff_t, "0..1", "Taichi's rate on %d threads / (%d x its rate on 1)" % (a.np, a.np))
    add(metrics[3][0], s1["point_steps_per_s"] / t1["point_steps_per_s"], "ratio",
        "mpm_point_steps_per_s_per_core / taichi_point_steps_per_s_1thread (%d / %d points)" %
        (s1["points"], t1["points"]))
    add(metrics[4][0], sb["point_steps_per_s"] / tn["point_steps_per_s"], "ratio",
        "mpm_point_steps_per_s_%dranks (fix balance/mpm) / taichi_point_steps_per_s_%s" % (a.np, many))
    add(metrics[5][0], eff_m / eff_t, "ratio", "mpm_parallel_efficiency_%dranks / taichi_parallel_efficiency_%s"
        % (a.np, many))


# ---------------------------------------------------------------- coupling (callgrind)

def callgrind_costs(path):
    """({function: inclusive Ir}, {function: self Ir}, total Ir) from callgrind_annotate."""
    line = re.compile(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(.*?)(?:\s+\[[^\]]*\])?\s*$")

    def table(extra):
        p = subprocess.run(["callgrind_annotate", "--threshold=100"] + extra + [path], stdout=subprocess.PIPE,
                           text=True, errors="replace")
        out, total = {}, 0
        for ln in p.stdout.splitlines():
            m = line.match(ln)
            if not m:
                continue
            ir, name = int(m.group(1).replace(",", "")), m.group(2)
            if name == "PROGRAM TOTALS":
                total = ir
                continue
            i = name.find(":")
            if 0 <= i < len(name) - 1 and name[i + 1] != ":":
                name = name[i + 1:]  # drop the "file:" / "???:" prefix
            out[name] = out.get(name, 0) + ir
        return out, total

    incl, total = table(["--inclusive=yes"])
    self_, _ = table([])
    return incl, self_, total


def find_cost(table, name):
    """Inclusive cost of a function (its .cold clone included)."""
    return sum(v for k, v in table.items() if k.startswith("LAMMPS_NS::" + name) or k.startswith(name))


def callgrind_run(a, tag, cmd):
    d = os.path.join(a.out, "callgrind", tag)
    shutil.rmtree(d, ignore_errors=True)
    out = os.path.join(d, "callgrind.out")
    os.makedirs(d)
    wall, _, _ = run(["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out,
                      "--toggle-collect=LAMMPS_NS::Verlet::run(int)"] + cmd, d, timeout=7200)
    incl, self_, total = callgrind_costs(out)
    return d, wall, incl, self_, total


def fix_times(text):
    """[(fluid s, coupling s)] of each run, from fix mpm/fluid's summary lines."""
    out = []
    for m in re.finditer(r"fix mpm/fluid: wall time in this run: fluid (\S+) s(?: \([^)]*\))?(?:, coupling (\S+) s)?", text):
        out.append((float(m.group(1)), float(m.group(2) or 0.0)))
    return out


def section_coupling(a):
    say("== coupling: C3 tank at Grid40 x 8, fix timers (one rank)")
    tank = os.path.join(TOP, "inputs", "tank", "in.tank")
    segment = ["-var", "tdry", "0.0004", "-var", "tsnap", "0.0001", "-var", "tsettle", "0.0005",
               "-var", "tend", "0.0005", "-var", "tfront", "0.0001"]
    short = list(segment)
    # the fluid every step with the weakly compressible model, as docs/validation/performance.md measured it
    # (in.tank defaults to the projection with the fluid every 10 DEM steps)
    short += ["-var", "pressure", "eos", "-var", "wallkind", "noslip", "-var", "damp", "100",
              "-var", "extra", "transfer apic theta_smooth 0.01"]
    cmd = [a.exe, "-in", tank, "-echo", "none"] + short
    wall, out, _ = run(cmd, os.path.join(a.out, "coupling", "native"))
    coupled = loop_times(out)[1:]       # the dry run has no fluid
    ft = fix_times(out)
    loop = sum(t[0] for t in coupled)
    steps = max(1, sum(t[2] for t in coupled))
    fluid = sum(t[0] for t in ft)
    cpl = sum(t[1] for t in ft)
    rest = loop - fluid - cpl
    say("    %d coupled steps: loop %.3f s, fluid %.3f s, coupling %.3f s, LIGGGHTS + output %.3f s"
        % (steps, loop, fluid, cpl, rest))
    note = ("C3 Grid40x8 (32000 points, 7762 beads, 20 dry steps), %d coupled steps, one rank, "
            "fix timers: coupling / fluid" % steps)
    add("coupling_overhead_fraction", cpl / fluid if fluid else float("nan"), "ratio", note)
    add("c3_share_liggghts", rest / loop, "fraction of step", "Loop time minus the fix's timers: DEM, neighbour "
        "lists, exchange, other fixes, HDF5 output every 10 steps")
    add("c3_share_mpm_fluid", fluid / loop, "fraction of step", "fix timer: the fluid's own work")
    add("c3_share_coupling", cpl / loop, "fraction of step", "fix timer: fluid fraction, pressure fit, "
        "drag and pressure exchange (halo exchanges included)")
    add("c3_ms_per_coupled_step", 1e3 * loop / steps, "ms/step", "native, same segment, 1 rank")
    RUNS.append(dict(section="coupling", case="tank_timers", wall_s=wall, loop_s=loop, fluid_s=fluid,
                     coupling_s=cpl, steps=steps))

    # the same segment with the input's defaults: the default pressure model (projection), the
    # fluid and the coupling every 10 DEM steps
    cmd = [a.exe, "-in", tank, "-echo", "none"] + segment
    wall, out, _ = run(cmd, os.path.join(a.out, "coupling", "default"))
    ft = fix_times(out)
    fluid = sum(t[0] for t in ft)
    cpl = sum(t[1] for t in ft)
    say("    default model (projection, every 10): fluid %.3f s, coupling %.3f s" % (fluid, cpl))
    add("coupling_overhead_fraction_default", cpl / fluid if fluid else float("nan"), "ratio",
        "C3 Grid40x8, the same segment with in.tank's defaults (pressure projection, every 10), one rank, "
        "fix timers: coupling / fluid")
    RUNS.append(dict(section="coupling", case="tank_timers_default", wall_s=wall, fluid_s=fluid, coupling_s=cpl))

    say("== coupling: pure-fluid 3-D dam break under callgrind (hot spots)")
    cmd = [a.exe, "-in", os.path.join(TOP, "inputs", "bench", "in.dambreak3d"), "-echo", "none",
           "-var", "cells", "10", "-var", "warm", "2", "-var", "nsteps", "10"]
    d, wall, incl, self_, total = callgrind_run(a, "dambreak3d", cmd)
    cpl0 = find_cost(incl, "FixMpmFluid::couple_fluid_grains") + find_cost(incl, "FixMpmFluid::fluid_fraction")
    add("coupling_cost_without_grains", cpl0, "instructions",
        "pure-fluid run (8000 points, 12 steps): couple_fluid_grains and fluid_fraction never run")
    pfi0 = find_cost(incl, "FixMpmFluid::pre_final_integrate()")
    steps_pts = 8000 * 12
    add("mpm_instructions_per_point_step", pfi0 / steps_pts, "Ir/(point step)",
        "callgrind, fluid step (pre_final_integrate), 8000 points, bspline2; compare code versions with it")
    rows = sorted(((v, k) for k, v in self_.items()), reverse=True)[:15]
    with open(os.path.join(a.out, "hotspots.md"), "w") as f:
        f.write("| function | self Ir | share of Verlet::run | Ir per point-step |\n| --- | --- | --- | --- |\n")
        for v, k in rows:
            f.write("| `%s` | %.4g | %.1f %% | %.0f |\n" % (k[:90], v, 100.0 * v / total, v / steps_pts))
    say("    hot spots -> %s" % os.path.join(a.out, "hotspots.md"))

    if not a.quick:
        say("== coupling: whole C3 tank at Grid40 x 8 (default input, long)")
        wall, out, _ = run([a.exe, "-in", tank, "-echo", "none"], os.path.join(a.out, "coupling", "full_tank"),
                           timeout=6 * 3600)
        add("c3_whole_case_walltime", wall, "s", "in.tank defaults (pressure projection, the fluid every 10 steps; 0.25 s dry, 0.05 s settling, 0.2 s lift), 1 rank")


# ---------------------------------------------------------------- laser

def section_laser(a):
    say("== laser")
    d = os.path.join(a.out, "laser")
    os.makedirs(d, exist_ok=True)
    best = None
    for k in range(3):  # the best of three: the process wall time, start-up included
        t0 = time.perf_counter()
        code, s, err = run_case(a.laser_exe, os.path.join(d, "table51_%d" % k),
                                ["--config", os.path.join(TOP, "inputs", "laser", "table51.toml")])
        w = time.perf_counter() - t0
        if code != 0:
            raise RuntimeError("laser_drill failed: " + err)
        best = w if best is None else min(best, w)
    add("laser_case_s", best, "s", "Table 5.1 (inputs/laser/table51.toml), process wall time, best of 3")
    if a.quick:
        return
    cases = [(I, m, p, args) for I in laser_sweep.INTENSITIES for m, p, args in laser_sweep.cases(True)]

    def one(c):
        I, m, p, args = c
        name = "I%.3g_%s%s" % (I, m, "" if p is None else "_%g" % p)
        code, s, err = run_case(a.laser_exe, os.path.join(d, "sweep", name), ["--intensity", I, "--model", m] + args)
        return code
    for workers in (1, 2):
        t0 = time.perf_counter()
        with cf.ThreadPoolExecutor(max_workers=workers) as ex:
            codes = list(ex.map(one, cases))
        w = time.perf_counter() - t0
        add("laser_sweep_s_%dcore%s" % (workers, "s" if workers > 1 else ""), w, "s",
            "%d cases (every model of laser_sweep.py --full x 7 intensities), %d failed" %
            (len(cases), sum(1 for c in codes if c != 0)))


# ---------------------------------------------------------------- SPH against MPM

def pareto(points):
    """(wall, err) sorted by wall, keeping only runs more accurate than every cheaper one."""
    out = []
    for w, e in sorted(points):
        if not out or e < out[-1][1]:
            out.append((w, e))
    return out


def time_at_error(front, e):
    """Wall time to reach error e on a front (log-log interpolation); (time, exact?)."""
    if e >= front[0][1]:
        return front[0][0], e == front[0][1]   # even the cheapest run is as accurate: an upper bound
    for (w0, e0), (w1, e1) in zip(front, front[1:]):
        if e1 <= e <= e0:
            t = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(w0) + t * (math.log(w1) - math.log(w0))), True
    return float("nan"), False


def section_sph(a):
    say("== sph: 2-D square-column dam break, LIGGGHTS SPH against fix mpm/fluid (1 rank each)")
    tend = 3.0
    sph_n = [10, 15, 25] if a.quick else [10, 15, 25, 35, 50, 70]
    mpm_c = [12, 16, 20] if a.quick else [12, 16, 20, 24, 32]
    pts = {"sph": [], "mpm": []}
    for n in sph_n:
        d = os.path.join(a.out, "sph", "sph_n%d" % n)
        shutil.rmtree(d, ignore_errors=True)
        wall, out, _ = run([a.exe, "-in", os.path.join(TOP, "inputs", "bench", "in.sph_dambreak"), "-echo", "none",
                            "-var", "n", str(n), "-var", "tend", str(tend)], d)
        ef, eh, _ = dambreak_error.errors(os.path.join(d, "front.csv"), tmax=tend)
        s = dambreak_error.read_csv(os.path.join(d, "summary.csv"))
        pts["sph"].append((wall, ef))
        RUNS.append(dict(section="sph", case="SPH n=%d" % n, points=n * n, wall_s=wall, front_rms_a=ef,
                         height_rms_a=eh, lost=int(s["lost"][0])))
        say("    SPH %3d x %-3d particles: wall %6.1f s, front RMS %.4f a, height RMS %.4f a, lost %d" %
            (n, n, wall, ef, eh, int(s["lost"][0])))
    for c in mpm_c:
        d = os.path.join(a.out, "sph", "mpm_c%d" % c)
        shutil.rmtree(d, ignore_errors=True)
        wall, out, _ = run([a.exe, "-in", os.path.join(TOP, "inputs", "dambreak", "in.dambreak"), "-echo", "none",
                            "-var", "cells", str(c), "-var", "tend", str(tend), "-var", "pressure", "eos"], d)
        ef, eh, _ = dambreak_error.errors(os.path.join(d, "front.csv"), tmax=tend)
        pts["mpm"].append((wall, ef))
        RUNS.append(dict(section="sph", case="MPM%d" % c, points=4 * c * c, wall_s=wall, front_rms_a=ef,
                         height_rms_a=eh))
        say("    MPM%-3d (%5d points): wall %6.1f s, front RMS %.4f a, height RMS %.4f a" %
            (c, 4 * c * c, wall, ef, eh))
    fs, fm = pareto(pts["sph"]), pareto(pts["mpm"])
    target = max(fs[-1][1], fm[-1][1])  # the smallest error both methods reach
    ts, exs = time_at_error(fs, target)
    tm, exm = time_at_error(fm, target)
    bound = "" if exs and exm else " (%s cheapest run is already more accurate: its time is an upper bound)" % (
        "SPH's" if not exs else "MPM's")
    add("sph_over_mpm_walltime_same_error", ts / tm, "ratio",
        "at front RMS error %.3f a: SPH %.1f s, MPM %.1f s; T <= %g, 1 rank each%s" % (target, ts, tm, tend, bound))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(5.5, 4))
        for k, lab, mk in (("sph", "LIGGGHTS SPH (n x n)", "s-"), ("mpm", "fix mpm/fluid (MPMn)", "o-")):
            w, e = zip(*sorted(pts[k]))
            ax.plot(w, e, mk, label=lab)
        ax.axhline(target, color="k", lw=0.8, ls=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time (s, 1 rank)")
        ax.set_ylabel("front RMS error / a")
        ax.set_title("2-D dam break vs Martin & Moyce")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, "sph_vs_mpm.png"), dpi=120)
        plt.close(fig)
    except ImportError:
        pass


# ---------------------------------------------------------------- main

def snapshot(exe, d):
    """A private copy of the executable, so that a rebuild during the benchmark changes nothing."""
    os.makedirs(d, exist_ok=True)
    dst = os.path.join(d, os.path.basename(exe))
    for _ in range(60):  # wait while someone is linking it
        try:
            if os.access(exe, os.X_OK):
                shutil.copy2(exe, dst)
                return dst
        except OSError:
            pass
        time.sleep(2)
    raise SystemExit("cannot copy %s" % exe)


SECTIONS = {"mpm": section_mpm, "coupling": section_coupling, "laser": section_laser, "sph": section_sph}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default="bench-out")
    ap.add_argument("--np", type=int, default=2)
    ap.add_argument("--exe", default=os.path.join(TOP, "build", "liggghts_mpm"))
    ap.add_argument("--laser-exe", default=None)
    ap.add_argument("--only", nargs="*", choices=sorted(SECTIONS))
    ap.add_argument("--no-taichi", action="store_true", help="skip the Taichi reference (its rows are nan)")
    a = ap.parse_args()
    a.out = os.path.abspath(a.out)
    a.exe = os.path.abspath(a.exe)
    if a.laser_exe is None:
        for c in (os.path.join(TOP, "build", "laser_drill"), os.path.join(TOP, "build", "laser", "laser_drill"),
                  os.path.join(TOP, "build-laser", "laser_drill")):
            if os.path.exists(c):
                a.laser_exe = c
                break
    os.makedirs(a.out, exist_ok=True)
    exe_given = a.exe
    a.exe = snapshot(a.exe, os.path.join(a.out, "bin"))
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    failed = []
    for name in (a.only or ["mpm", "coupling", "laser", "sph"]):
        try:
            SECTIONS[name](a)
        except (RuntimeError, subprocess.TimeoutExpired, OSError, ValueError, IndexError, KeyError) as e:
            failed.append(name)
            say("!! section %s failed: %s" % (name, e))
    total = time.perf_counter() - t0
    load = os.getloadavg()
    machine = "%s, %d cores, %s; load average (1 min) %.2f at the start, %.2f at the end (other jobs share the " \
        "cores); %s" % (platform.processor() or platform.machine(), os.cpu_count(), platform.node(), load0, load[0],
                        exe_given)
    add("bench_total_s", total, "s", ("quick" if a.quick else "full") + " mode; " + machine)

    with open(os.path.join(a.out, "results.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["metric", "value", "unit", "note"])
        w.writerows(RESULTS)
    with open("bench-results.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["metric", "value", "unit"])
        w.writerows([r[:3] for r in RESULTS])
    with open(os.path.join(a.out, "results.md"), "w") as f:
        f.write("| metric | value | unit | note |\n| --- | --- | --- | --- |\n")
        for m, v, u, n in RESULTS:
            f.write("| %s | %s | %s | %s |\n" % (m, fmt(v), u, n))
    mpm_io.write_rows(os.path.join(a.out, "runs.csv"), RUNS)
    say("wrote bench-results.csv, %s/results.csv, results.md, runs.csv (%.0f s)" % (a.out, total))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
