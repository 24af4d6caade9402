#!/usr/bin/env python3
"""Runs and checks the wet tumbling mill inputs/drum/in.drum (CASES.md C7, docs/validation/drum.md).

run:     writes drum.stl (tools/make_drum_stl.py), sets the mixture height hfill so that the water
         fills a third of the drum's inside for the chosen bead count, runs liggghts_mpm in a work
         folder, times it, and analyses the run as 'check' does.
check:   reads drum.csv and drum_run.txt of run folders and prints, per folder, the figures of the
         scene's physical checks (all computed from the inputs alone):
           * axial uniformity: share of the beads in the middle third of the drum length, every row
             (the beads go in as 1/3 per third; uniform = 1/3); the bound: its mean over each
             quarter turn within 10 % of 1/3 (rows alone carry the binomial noise of the bead count);
           * pressure: largest point pressure against 5 (rho g hfill + rho (omega R)^2);
           * fluid mass: largest relative change of f_fluid[1] over the rotation;
           * points outside the drum (beyond the mantle polygon or the end caps) and inside a
             lifter bar, beads outside the drum (largest count over the rows);
           * wall time (of the run, when timed by 'run').
         --json writes the figures of all folders to a file.

  tools/python tools/drum_run.py run --exe build/liggghts_mpm --work /tmp/drum_p [--nbeads 600]
        [--cells 20] [--ppc 2] [--turns 2] [--pressure projection|eos] [--bulk 5e4] [--var NAME VALUE ...]
  tools/python tools/drum_run.py check /tmp/drum_p /tmp/drum_e [--json figures.json]
Standard library only (tests/cases/test_drum.py imports it).
"""
import argparse
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
INPUT = os.path.normpath(os.path.join(HERE, "..", "inputs", "drum", "in.drum"))
sys.path.insert(0, HERE)
from make_drum_stl import drum_triangles, write_stl  # noqa: E402

# the scene's geometry (in.drum's and make_drum_stl.py's defaults)
D, L, HL, WL, NLIFT, PHASE, NSEG = 0.16, 0.04, 0.008, 0.008, 6, 90.0, 72
UNIFORM_TOL = 0.10       # share of the middle third within 10 % of 1/3 ...
WINDOW = 0.25            # ... averaged over each quarter turn (the instantaneous share of 600 beads
                         # in the dry drum swings by 13.5 %: binomial noise, 5.8 % for one sigma)
PRESSURE_FACTOR = 5.0    # largest pressure below 5 (rho g h + rho (omega R)^2)


def segment_area(h, r):
    """Area of the circular segment of height h of a circle of radius r."""
    return r * r * math.acos((r - h) / r) - (r - h) * math.sqrt(max(2 * r * h - h * h, 0.0))


def fill_height(nbeads, d, water_fraction=1.0 / 3.0):
    """Height of the water-and-beads mixture at rest for water filling water_fraction of the drum's
    inside (cylinder less the bars): the circular segment holds the water, the beads and the bars
    below the surface (the bars as rectangles hl x wl; at phase 90 the bars at 210, 270 and 330
    degrees lie below any surface above z = R - (R - hl) sin 30 deg + wl/2)."""
    r = 0.5 * D
    inside = math.pi * r * r * L - NLIFT * HL * WL * L
    target = (water_fraction * inside + nbeads * math.pi / 6.0 * d ** 3) / L
    lo, hi = 0.0, 2.0 * r
    for _ in range(200):
        h = 0.5 * (lo + hi)
        bars = sum(1 for k in range(NLIFT)
                   if r + (r - 0.5 * HL) * math.sin(math.radians(PHASE + 360.0 * k / NLIFT)) < h)
        if segment_area(h, r) - bars * HL * WL < target:
            lo = h
        else:
            hi = h
    return 0.5 * (lo + hi)


def read_csv(path):
    rows = [ln.strip() for ln in open(path) if ln.strip() and not ln.startswith("#")]
    names = rows[0].split(",")
    cols = {n: [] for n in names}
    for ln in rows[1:]:
        for n, v in zip(names, ln.split(",")):
            cols[n].append(float(v))
    return cols


def read_info(path):
    return dict((k.strip(), v.strip()) for k, v in
                (ln.split(" = ", 1) for ln in open(path).read().splitlines() if " = " in ln))


def analyse(d):
    """Figures of one run folder (a dict)."""
    c = read_csv(os.path.join(d, "drum.csv"))
    info = read_info(os.path.join(d, "drum_run.txt"))
    rho, g, hfill = float(info["rho"]), float(info["g"]), float(info["hfill"])
    omega, r = float(info["omega"]), 0.5 * float(info["D"])
    bound = PRESSURE_FACTOR * (rho * g * hfill + rho * (omega * r) ** 2)
    mid = c["mid"]
    dev = [abs(m - 1.0 / 3.0) * 3.0 for m in mid]
    # the share averaged over each quarter turn (rows with turn in (k W, (k + 1) W]); a run shorter
    # than a quarter turn is one window
    win = {}
    for tu, m in zip(c["turn"], mid):
        win.setdefault(max(0, math.ceil(tu / WINDOW - 1e-9) - 1), []).append(m)
    groups = [v for _, v in sorted(win.items())]
    if len(groups) > 1 and len(groups[-1]) < 3:  # a last row or two past the end: into the window before
        last = groups.pop()
        groups[-1] = groups[-1] + last
    means = [sum(v) / len(v) for v in groups]
    wdev = [abs(m - 1.0 / 3.0) * 3.0 for m in means]
    m0 = c["mass"][0]
    wet = info.get("water", "1") == "1"
    r_in = math.pi * r * r * float(info["L"]) - NLIFT * HL * WL * float(info["L"])
    f = {
        "folder": d,
        "pressure": info["pressure"] if wet else "dry",
        "nbeads": int(float(info["nbeads"])),
        "cells": int(float(info["cells"])),
        "ppc": int(float(info["ppc"])),
        "turns": c["turn"][-1],
        "rows": len(mid),
        "mid_first": mid[0],
        "mid_last": mid[-1],
        "mid_min": min(mid),
        "mid_max": max(mid),
        "mid_dev_max": max(dev),
        "mid_window_means": means,
        "mid_window_dev_max": max(wdev),
        "mid_at_turn": {f"{k}": mid[min(range(len(mid)), key=lambda i: abs(c["turn"][i] - k))]
                        for k in (0.25, 0.5, 1.0, 1.5, 2.0) if c["turn"][-1] >= k - 1e-9},
        "pmax_max": max(c["pmax"]),
        "pmax_median": statistics.median(c["pmax"]),
        "pmax_turn_of_max": c["turn"][c["pmax"].index(max(c["pmax"]))],
        "pressure_bound": bound,
        "rho_g_h": rho * g * hfill,
        "rho_wR2": rho * (omega * r) ** 2,
        "mass": m0,
        "mass_dev_max": max(abs(m - m0) / m0 for m in c["mass"]) if wet else 0.0,
        "water_fraction": m0 / rho / r_in,
        "points_outside_max": max(c["pout"]),
        "points_in_lifters_max": max(c["plift"]),
        "beads_outside_max": max(c["bout"]),
        "corrections_last": c["corr"][-1],
        "ke_max": max(c["ke"]),
    }
    wt = os.path.join(d, "wall_time.txt")
    if os.path.exists(wt):
        f["wall_s"] = float(open(wt).read().split()[0])
    f["uniform_ok"] = f["mid_window_dev_max"] <= UNIFORM_TOL
    f["pressure_ok"] = f["pmax_max"] < bound or not wet
    return f


def report(f):
    lines = [
        f"{f['folder']}: pressure {f['pressure']}, {f['nbeads']} beads, cells {f['cells']} x {f['ppc']}^3 points, "
        f"{f['turns']:.3f} turns ({f['rows']} rows)",
        f"  share of beads in the middle third: start {f['mid_first']:.4f}, end {f['mid_last']:.4f}, "
        f"range {f['mid_min']:.4f}-{f['mid_max']:.4f}, largest |share - 1/3| / (1/3) of a row {f['mid_dev_max']:.3f}; "
        f"at turns " + ", ".join(f"{k}: {v:.4f}" for k, v in f["mid_at_turn"].items()),
        f"  quarter-turn means " + " ".join(f"{m:.4f}" for m in f["mid_window_means"])
        + f": largest deviation {f['mid_window_dev_max']:.3f} ({'within' if f['uniform_ok'] else 'OUTSIDE'} "
        f"{UNIFORM_TOL:.0%})",
        f"  largest point pressure {f['pmax_max']:.4g} Pa (median of the rows {f['pmax_median']:.4g} Pa, "
        f"at turn {f['pmax_turn_of_max']:.3f}); bound 5 (rho g h + rho (omega R)^2) = 5 ({f['rho_g_h']:.4g} + "
        f"{f['rho_wR2']:.4g}) = {f['pressure_bound']:.4g} Pa: {'below' if f['pressure_ok'] else 'ABOVE'}",
        f"  fluid mass {f['mass']:.6g} kg ({f['water_fraction']:.3f} of the drum's inside), largest relative change {f['mass_dev_max']:.2e}; points outside the drum "
        f"(max over rows) {f['points_outside_max']:.0f}, in a lifter {f['points_in_lifters_max']:.0f}; beads outside "
        f"{f['beads_outside_max']:.0f}; points put back (cumulative) {f['corrections_last']:.0f}; largest fluid KE "
        f"{f['ke_max']:.3g} J",
    ]
    if "wall_s" in f:
        lines.append(f"  wall time {f['wall_s']:.0f} s")
    return "\n".join(lines)


def write_stl_file(path):
    centre = (0.5 * D, 0.5 * L, 0.5 * D)
    tris = drum_triangles(D, L, NSEG, NLIFT, HL, WL, PHASE, centre)
    write_stl(path, tris, name="drum")


def run(exe, work, variables, timeout=None):
    """Runs in.drum in an emptied folder 'work' with the -var pairs; returns (process, wall seconds)."""
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    shutil.copy(INPUT, work)
    write_stl_file(os.path.join(work, "drum.stl"))
    cmd = [exe, "-in", "in.drum", "-echo", "none"]
    for k, v in variables.items():
        cmd += ["-var", k, str(v)]
    t0 = time.time()
    p = subprocess.run(cmd, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       errors="replace", timeout=timeout)
    wall = time.time() - t0
    with open(os.path.join(work, "output.txt"), "w") as fo:
        fo.write(p.stdout)
    with open(os.path.join(work, "wall_time.txt"), "w") as fo:
        fo.write(f"{wall:.1f} s\n")
    return p, wall


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--exe", required=True)
    r.add_argument("--work", required=True)
    r.add_argument("--nbeads", type=int, default=2400)
    r.add_argument("--cells", type=int, default=32)
    r.add_argument("--ppc", type=int, default=2)
    r.add_argument("--turns", type=float, default=2.0)
    r.add_argument("--pressure", choices=("projection", "eos"), default="projection")
    r.add_argument("--bulk", type=float, default=5.0e4)
    r.add_argument("--var", nargs=2, action="append", default=[], metavar=("NAME", "VALUE"))
    c = sub.add_parser("check")
    c.add_argument("folders", nargs="+")
    c.add_argument("--json")
    a = ap.parse_args()
    if a.cmd == "run":
        if a.nbeads < 3 or a.cells < 4 or a.ppc < 1 or a.turns <= 0 or a.bulk <= 0:
            ap.error(f"--nbeads >= 3, --cells >= 4, --ppc >= 1, --turns > 0, --bulk > 0 "
                     f"(given {a.nbeads}, {a.cells}, {a.ppc}, {a.turns}, {a.bulk})")
        v = {"nbeads": a.nbeads, "cells": a.cells, "ppc": a.ppc, "turns": a.turns, "pressure": a.pressure,
             "bulk": a.bulk, "hfill": f"{fill_height(a.nbeads, 0.003):.6g}"}
        v.update(dict(a.var))
        p, wall = run(os.path.abspath(a.exe), os.path.abspath(a.work), v)
        print(f"liggghts_mpm exit {p.returncode}, wall time {wall:.0f} s")
        if p.returncode != 0:
            print("\n".join(p.stdout.splitlines()[-15:]))
            return 1
        print(report(analyse(a.work)))
        return 0
    figs = [analyse(d) for d in a.folders]
    for f in figs:
        print(report(f))
    if a.json:
        with open(a.json, "w") as fo:
            json.dump(figs, fo, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
