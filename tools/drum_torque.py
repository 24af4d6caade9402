#!/usr/bin/env python3
"""The beads' torque on the drum sampled on fluid steps against its mean over every step
(inputs/drum/in.drum run with -var tqsteps 1, which writes drum_tq.txt: the torque of every step of
the rotation). With `every N` the fluid advances on the steps that are multiples of N; a DEM output
sampled there is unbiased when its mean over those steps equals its mean over all steps.

    tools/python tools/drum_torque.py drum_tq.txt --every 20 --dt 2e-5 [--skip 0.1]

Prints the mean torque over the steps of the rotation after --skip seconds: over all of them, over
the fluid steps (step = 0 mod N), and by the step's place in the N steps (step mod N). Standard
library only.
"""
import argparse


def read_steps(path):
    steps, values = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            s, v = line.split()[:2]
            steps.append(int(s))
            values.append(float(v))
    return steps, values


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file", help="drum_tq.txt of in.drum -var tqsteps 1")
    ap.add_argument("--every", type=int, required=True, help="fix mpm/fluid every N of the run")
    ap.add_argument("--dt", type=float, required=True, help="the run's DEM time step (s)")
    ap.add_argument("--skip", type=float, default=0.1, help="seconds of the rotation left out at its start")
    a = ap.parse_args()
    if a.every < 1:
        ap.error(f"--every expects an integer N >= 1, got {a.every}")
    if a.dt <= 0.0 or a.skip < 0.0:
        ap.error(f"--dt expects a positive step and --skip a non-negative time, got {a.dt} and {a.skip}")
    steps, values = read_steps(a.file)
    if not steps:
        raise SystemExit(f"{a.file}: no torque rows")
    n0 = steps[0] - 1  # the rotation's first step is the first row
    sel = [(s, v) for s, v in zip(steps, values) if (s - n0) * a.dt > a.skip]
    if len(sel) < a.every:
        raise SystemExit(f"{a.file}: {len(sel)} steps after {a.skip} s, fewer than N = {a.every}")
    mean_all = sum(v for _, v in sel) / len(sel)
    by_phase = [[v for s, v in sel if s % a.every == j] for j in range(a.every)]
    mean_fluid = sum(by_phase[0]) / len(by_phase[0])
    print(f"steps {len(sel)} ({sel[0][0]}..{sel[-1][0]}, t > {a.skip} s of the rotation), every {a.every}")
    print(f"mean torque over every step   {mean_all:+.5f} N m")
    print(f"mean torque over fluid steps  {mean_fluid:+.5f} N m ({len(by_phase[0])} steps; "
          f"{100.0 * (mean_fluid - mean_all) / abs(mean_all):+.1f} % of the mean over every step)")
    print("by step mod N: " + " ".join(f"{sum(p) / len(p):+.4f}" for p in by_phase))


if __name__ == "__main__":
    main()
