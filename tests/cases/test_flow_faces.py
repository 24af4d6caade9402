#!/usr/bin/env python3
"""Inflow and outflow faces of fix mpm/fluid (docs/fix_mpm_fluid.md, "Flow in and out"): a column of
water periodic in x and y, fed through its floor at U (boundary zlo inflow U) and draining through its
top (boundary zhi outflow), under gravity (tests/data/in.flow_faces).

    test_flow_faces.py CASE --exe build/liggghts_mpm --inputs inputs --work DIR [--mpirun "..."]

Cases:
  balance      a full column (the fill up to the outflow) and one filled to 3/4 whose free surface rises
               to the outflow: at every output the fluid mass f_ID[1] = the fill's mass + mass in - mass
               out to round-off (1e-12); the mass in is the whole layers the flux U A t has filled,
               floor(U t / s) rho A s; once the outflow runs, the mass in the box stays within one
               layer's mass of the full column's; the points move as a plug at U (continuity, 1e-9);
               the probe's pressure at mid-height of the full column is rho g (H - z) (p = 0 at the
               outflow face) while the top layer reaches the face, never above it, and at most half a
               point spacing's head below it once that layer has left (the fluid the points hold then
               ends half a spacing below the face; measured 0.47 of a spacing's head).
  np2_vs_np1   2 ranks (the column cut across its height: one rank creates, the other removes; and
               cut along x: each rank creates and removes its half of every layer) against 1: mass, mass in, mass out, points and velocity at every output to 1e-9.
  restart      the run split by write_restart / read_restart on a step on which a layer has left
               and waits for its removal (deleted at the resumed run's setup): every output of the resumed run equals the uninterrupted
               run's (depth owed and mass counters in the restart file) to 1e-10.
  bad_input    refused faces and values, naming the keyword, what it expects and the value.
"""
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from cases import DATA, check, driver_main, read_csv, water_box_script  # noqa: E402

INP = os.path.join(DATA, "in.flow_faces")
RHO, CELL, G, DT = 1000.0, 0.01, 9.81, 5e-4  # the input's water, cell, gravity and time step
L, H, PPC = 4 * CELL, 16 * CELL, 2
SP = CELL / PPC                              # point spacing
LAYER = RHO * L * L * SP                     # mass of one layer of points across the column


def case_balance(r):
    for label, U, fillh, nhalf in (("full", 0.05, H, 1000), ("rising", 0.0937, 0.12, 600)):
        d, _ = r.run(f"flow_faces/balance_{label}", INP, {"U": U, "fillh": fillh, "nhalf": nhalf, "every": 10})
        f = read_csv(os.path.join(d, "flow.csv"))
        n = len(f["step"])
        m0 = RHO * L * L * fillh  # the fill's lattice fills the region exactly
        err = max(abs(m - (m0 + a - b)) / m0 for m, a, b in zip(f["mass"], f["min"], f["mout"]))
        print(f"  {label}: {n} outputs; largest |mass - (m0 + in - out)| / m0 = {err:.1e}; "
              f"in {f['min'][-1]:.6f} kg, out {f['mout'][-1]:.6f} kg ({f['min'][-1] / LAYER:.3f} and "
              f"{f['mout'][-1] / LAYER:.3f} layers)")
        check(err < 1e-12, f"{label}: fluid mass = initial + in - out to round-off at every output")
        # the layers due after the fluid step of step k are made at the exchange of step k + 1
        def due(k):
            q = U * k * DT / SP
            return {math.floor(q - 1e-9), math.floor(q + 1e-9)}  # either, where U t / s is a whole number
        bad = [s for a, s in zip(f["min"], f["step"]) if not any(abs(a - n * LAYER) < 1e-12 * m0 for n in due(s - 1))]
        check(not bad, f"{label}: mass in = floor(U t / s) layers at every output, t up to the last step ({bad[:3]})")
        check(f["min"][-1] > 0.0 and f["mout"][-1] > 0.0, f"{label}: points were created and removed")
        vz = max(abs(v - U) / U for v in f["vz"])
        print(f"  {label}: largest |vz - U| / U = {vz:.1e}")
        check(vz < 1e-9, f"{label}: the fluid moves as a plug at the inflow's velocity")
        full = RHO * L * L * H
        steady = [m for m, b in zip(f["mass"], f["mout"]) if b > 0.0]
        dev = max(abs(m - full) for m in steady) / LAYER
        print(f"  {label}: with the outflow running ({len(steady)} outputs) mass within {dev:.3f} layers of the "
              f"full column's {full:.6f} kg")
        check(len(steady) > 10 and dev <= 1.0 + 1e-9, f"{label}: mass in the box constant within one layer's mass")
        if label == "full":
            p0 = RHO * G * (H - 8 * CELL)
            lo, hi = min(f["p"]), max(f["p"])
            print(f"  full: probe at mid-height {lo:.2f} .. {hi:.2f} Pa, rho g (H - z) = {p0:.2f} Pa "
                  f"({lo / p0 - 1:+.2%} .. {hi / p0 - 1:+.2%}); deficit {(p0 - lo) / (RHO * G * SP):.2f} of a "
                  f"spacing's head {RHO * G * SP:.2f} Pa")
            check(abs(hi - p0) < 1e-6 * p0 and p0 - lo < 1.001 * RHO * G * SP / 2,
                  "full: p at mid-height = rho g (H - z) while the top layer reaches the outflow, never above it, at "
                  "most half a point spacing's head below it (the top layer's cube gone with it)")


def case_np2_vs_np1(r):
    v = {"U": 0.0937, "fillh": 0.15, "nhalf": 200, "every": 10}
    d1, _ = r.run("flow_faces/np1", INP, v)
    f1 = read_csv(os.path.join(d1, "flow.csv"))
    check(f1["min"][-1] > 0.0 and f1["mout"][-1] > 0.0, "points were created and removed")
    # the column cut across its height (one rank creates, the other removes) and along x (both
    # create and remove, each its half of every layer)
    for cut, procs in (("z", {"procz": 2}), ("x", {"procx": 2})):
        d2, _ = r.run(f"flow_faces/np2_{cut}", INP, dict(v, **procs), np=2)
        f2 = read_csv(os.path.join(d2, "flow.csv"))
        check(len(f1["step"]) == len(f2["step"]) == 40, f"cut along {cut}: 40 outputs on 1 and on 2 ranks")
        rel = max(abs(a - b) / max(abs(a), 1e-30) for k in ("mass", "min", "mout", "points", "vz", "p")
                  for a, b in zip(f1[k], f2[k]))
        print(f"  cut along {cut}: largest relative difference of mass, in, out, points, vz, p (2 ranks against 1): "
              f"{rel:.1e}")
        check(rel < 1e-9, f"cut along {cut}: 2 ranks = 1 rank to 1e-9 at every output")


def case_restart(r):
    # the full column at U = 0.05: layers enter at steps 202, 402 and leave at steps 101, 300 (60 of
    # its 64 points, the others at 301 by round-off), 500 (measured); split at step 300, on which
    # points left and wait for their removal
    v = {"U": 0.05, "fillh": H, "nhalf": 300, "every": 1}
    d0, _ = r.run("flow_faces/restart/full", INP, dict(v, mode=0))
    d1, _ = r.run("flow_faces/restart/split", INP, dict(v, mode=1))
    p = r.execute(d1, "in.flow_faces", dict(v, mode=2), expect_ok=False, timeout=300)
    check(p.returncode == 0, "resumed run finished")
    a, b = read_csv(os.path.join(d0, "flow.csv")), read_csv(os.path.join(d1, "flow.csv"))
    check(a["step"] == b["step"] and len(a["step"]) == 600, "600 outputs in both")
    k = a["step"].index(300.0)
    check(a["mout"][k] > a["mout"][k - 1], "a layer left on the step of the restart file")
    rel = max(abs(x - y) / max(abs(x), 1e-300) for k in a for x, y in zip(a[k], b[k]))
    print(f"  largest relative difference, resumed against uninterrupted, every step: {rel:.1e}")
    check(rel < 1e-10, "the resumed run = the uninterrupted run at every step")


BAD = water_box_script(0.04, 0.04, 0.08, 0.01, 5e-4)


def case_bad_input(r):
    inflow = "keyword 'boundary inflow' expects a normal velocity U > 0 (velocity, into the grid) of the inflow"
    cases = [
        ("f", "boundary zlo inflow 0", "", (inflow, "got '0'")),
        ("f", "boundary zlo inflow -0.05", "", (inflow, "got '-0.05'")),
        ("f", "boundary zlo inflow fast", "", (inflow, "got 'fast'")),
        ("f", "boundary zlo inflow inf", "", (inflow, "got 'inf'")),
        ("f", "boundary zlo inflow", "", (inflow, "got nothing")),
        ("f", "boundary all outflow", "", ("keyword 'boundary' expects one face (xlo xhi ylo yhi zlo zhi) for 'inflow' "
                                           "or 'outflow', got 'all'",)),
        ("f", "boundary zlo sideways", "", ("keyword 'boundary' expects 'noslip', 'freeslip', 'partial f', "
                                            "'shear delta', 'inflow U' or 'outflow', got 'sideways'",)),
        ("f", "boundary xlo inflow 0.05", "", ("keyword 'boundary xlo inflow' expects a face of a non-periodic "
                                               "dimension, got xlo",)),
        ("f", "boundary yhi outflow", "", ("keyword 'boundary yhi outflow' expects a face of a non-periodic "
                                           "dimension, got yhi",)),
        ("f", "pressure eos bulk 2e6 boundary zhi outflow", "",
         ("keyword 'boundary zhi outflow' needs 'pressure projection'",)),
        ("f", "boundary zhi outflow mesh_wall nosuch freeslip", "",
         ("keyword 'boundary zhi outflow' cannot be combined with keyword 'mesh_wall'",)),
        ("f", "boundary zlo noslip", "fix_modify f boundary zlo inflow 0.05\nrun 1",
         ("fix_modify boundary cannot make face zlo an inflow or outflow face",)),
        ("f", "boundary zhi outflow", "fix_modify f boundary zhi noslip\nrun 1",
         ("fix_modify boundary cannot make face zhi an inflow or outflow face",)),
    ]
    for i, (zb, args, post, needles) in enumerate(cases):
        r.expect_error(f"flow_faces/bad_input/{i}", BAD.format(zb=zb, pre="", args=args, post=post), needles,
                       f"'{args} {post}' refused")
    # the inflow's speed enters the step limit at the setup (before a step, not once the fluid moves)
    p, msg = r.run_script("flow_faces/bad_input/fast", BAD.format(zb="f", pre="", args="boundary zlo inflow 20", post=""))
    check(p.returncode != 0 and "|v|max = 20)" in msg and "reduce the timestep to 0.00025" in msg
          and "during the run" not in msg and "Loop time" not in p.stdout,
          f"an inflow of 20 m/s refused at the setup by the advective step limit (got: {msg.strip()[:160]})")
    # accepted: fix_modify of an inflow's velocity between runs
    p, msg = r.run_script("flow_faces/bad_input/ok", BAD.format(
        zb="f", pre="", args="boundary zlo inflow 0.05 boundary zhi outflow",
        post="fix_modify f boundary zlo inflow 0.02\nrun 2"))
    check(p.returncode == 0, f"fix_modify of an inflow's velocity accepted ({msg.strip()[:120]})")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
