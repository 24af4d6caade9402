#!/usr/bin/env python3
"""Keyword superficial_velocity of fix mpm/fluid (docs/fix_mpm_fluid.md, "Driving a periodic flow"):
the fluid's mean flux along a periodic axis held at a target by a uniform driving gradient G,
reported as the last entry of the global vector.

    test_flow_drive.py CASE --exe build/liggghts_mpm --inputs inputs --work DIR [--mpirun "..."]

Cases:
  exact        water alone (both pressure models), the target ramped by an equal-style variable: the
               mean flux from the points' momentum equals the target to round-off after every step;
               G is rho dU/dt (the only force a periodic fluid without walls or grains needs: rho U/h
               at the first step, rho U1/(nramp h) on the ramp, 0 after it); the fluid mass is the
               same number at every step.
  ergun        the fixed simple-cubic bed of C2 (inputs/ergun, -var drive flux) at U = 0.002 and
               0.02 m/s, both pressure models: the reported G equals Ergun's dp/L at U within 1e-6
               (the C2 body-force runs reach U at that G, docs/validation/ergun.md).
  mixture      free grains with gravity (no contacts, held flux): G tends to the mixture's weight
               per volume (eps rho_f + (1 - eps) rho_p) g, the gradient that carries fluid and grains.
  np2_vs_np1   free grains with gravity: 2 ranks against 1, every step, to 1e-9.
  restart      the same run split by write_restart / read_restart: the resumed run equals the
               uninterrupted one (the driving gradient is in the restart file), both pressure models.
  bad_input    refused keywords and variables, naming the keyword, what it expects and the value.
"""
import math
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from cases import DATA, check, driver_main, read_csv, water_box_script  # noqa: E402

INP = os.path.join(DATA, "in.flow_drive")
RHO, H = 1000.0, 0.25 * 2.0e-3 / 2.0  # the input's water and time step


def case_exact(r):
    U0, U1, nramp = 0.01, 0.01, 20
    for pressure in ("projection", "eos"):
        d, _ = r.run(f"flow_drive/exact_{pressure}", INP, {"pressure": pressure, "U0": U0, "U1": U1, "nramp": nramp})
        f = read_csv(os.path.join(d, "flow.csv"))
        n = len(f["step"])
        check(n == 80, f"{pressure}: 80 steps written ({n})")
        err = max(abs(u - t) / abs(t) for u, t in zip(f["U"], f["target"]))
        print(f"  {pressure}: largest |U - target| / target over {n} steps {err:.1e}")
        check(err < 1e-12, f"{pressure}: the mean flux equals the target after every step (round-off, 1e-12)")
        g_scale = RHO * U0 / H
        expect = [RHO * (U0 + U1 / nramp) / H] + [RHO * U1 / nramp / H if s <= nramp else 0.0 for s in f["step"][1:]]
        gerr = max(abs(g - e) / g_scale for g, e in zip(f["G"], expect))
        print(f"  {pressure}: G at step 1 {f['G'][0]:.6e} (rho U(1)/h {expect[0]:.6e}), on the ramp {f['G'][5]:.6e} "
              f"(rho dU/dt {expect[5]:.6e}), at the end {f['G'][-1]:.2e} Pa/m; largest deviation {gerr:.1e} of rho U0/h")
        check(gerr < 1e-12, f"{pressure}: G = rho dU/dt at every step (0 once the target is constant) to round-off")
        check(all(m == f["mass"][0] for m in f["mass"]), f"{pressure}: fluid mass the same number at every step")


def case_ergun(r):
    inp = os.path.join(r.inputs, "ergun", "in.ergun")
    eps, mu, d, rho = 1.0 - math.pi / 6.0, 1.5e-3, 1e-3, 10.0
    A = 150.0 * (1 - eps) ** 2 / eps ** 3 * mu / d ** 2
    B = 1.75 * (1 - eps) / eps ** 3 * rho / d
    for pressure in ("eos", "projection"):
        for U in (0.002, 0.02):
            dd, _ = r.run(f"flow_drive/ergun_{pressure}_U{U}", inp, {"drive": "flux", "Uz": U, "pressure": pressure})
            f = read_csv(os.path.join(dd, "ergun.csv"))
            G, dp = f["G"][-1], A * U + B * U * U
            err = G / dp - 1.0
            flux = max(abs(u - U) / U for u in f["U"][1:])
            print(f"  {pressure}, U = {U}: G = {G:.6f} Pa/m, Ergun {dp:.6f} ({err:+.1e}); flux within {flux:.1e} of U")
            check(abs(err) < 1e-6, f"{pressure}, U = {U}: the reported gradient is Ergun's dp/L within 1e-6")
            check(flux < 1e-12, f"{pressure}, U = {U}: the flux held at U to round-off at every output")
            check(abs(f["G"][-1] - f["G"][-2]) < 1e-6 * G, f"{pressure}, U = {U}: G steady")


def case_mixture(r):
    eps, rhop, g = 1.0 - math.pi / 6.0, 2500.0, 9.81
    W = (eps * RHO + (1.0 - eps) * rhop) * g
    d, _ = r.run("flow_drive/mixture", INP, {"bed": 1, "mobile": 1, "g": g, "U0": 0.02, "nhalf": 400})
    f = read_csv(os.path.join(d, "flow.csv"))
    G = f["G"][-1]
    print(f"  after {len(f['G'])} steps G = {G:.2f} Pa/m, mixture weight per volume {W:.2f} Pa/m ({G / W - 1.0:+.2e})")
    check(abs(G / W - 1.0) < 1e-3, "free grains carried by the held flux: G = the mixture's weight per volume within 0.1 %")


def case_np2_vs_np1(r):
    v = {"bed": 1, "mobile": 1, "g": 9.81, "U0": 0.02, "U1": 0.01}
    d1, _ = r.run("flow_drive/np1", INP, v)
    d2, _ = r.run("flow_drive/np2", INP, v, np=2)
    f1, f2 = read_csv(os.path.join(d1, "flow.csv")), read_csv(os.path.join(d2, "flow.csv"))
    check(len(f1["step"]) == len(f2["step"]) == 80, "80 steps on 1 and on 2 ranks")
    rel = max(abs(a - b) / max(abs(a), 1e-30) for k in ("U", "G", "P") for a, b in zip(f1[k], f2[k]))
    print(f"  largest relative difference of U, G, P (2 ranks against 1): {rel:.1e}")
    check(rel < 1e-9, "2 ranks = 1 rank to 1e-9 at every step")


def case_restart(r):
    for pressure in ("projection", "eos"):
        v = {"bed": 1, "mobile": 1, "g": 9.81, "U0": 0.02, "pressure": pressure}
        d0, _ = r.run(f"flow_drive/restart_{pressure}/full", INP, dict(v, mode=0))
        d1, _ = r.run(f"flow_drive/restart_{pressure}/split", INP, dict(v, mode=1))
        p = r.execute(d1, "in.flow_drive", dict(v, mode=2), expect_ok=False, timeout=120)
        check(p.returncode == 0, f"{pressure}: resumed run finished")
        a, b = read_csv(os.path.join(d0, "state.csv")), read_csv(os.path.join(d1, "state.csv"))
        for k in a:
            rel = abs(a[k][0] - b[k][0]) / max(abs(a[k][0]), 1e-300)
            check(rel < 1e-10, f"{pressure}: {k} of the resumed run = uninterrupted run (rel. diff {rel:.1e})")


BAD = water_box_script(0.008, 0.008, 0.008, 0.002, 2.5e-4)


def case_bad_input(r):
    sv = "keyword 'superficial_velocity' expects"
    cases = [
        ("p", "", "superficial_velocity q 0.01", "", (sv + " an axis x, y or z, got 'q'",)),
        ("p", "", "superficial_velocity z fast", "", (sv + " a finite superficial velocity (velocity)", "got 'fast'")),
        ("p", "", "superficial_velocity z inf", "", (sv + " a finite superficial velocity (velocity)", "got 'inf'")),
        ("p", "", "superficial_velocity z", "", (sv, "got nothing")),
        ("p", "", "superficial_velocity z v_", "", (sv + " a variable name after 'v_', got 'v_'",)),
        ("f", "", "superficial_velocity z 0.01", "", (sv + " a periodic axis", "got 'z'")),
        ("p", "", "superficial_velocity z v_nosuch", "", (sv + " an equal-style variable, got 'v_nosuch' (no such variable)",)),
        ("p", "variable U atom 0.01*x", "superficial_velocity z v_U", "", (sv + " an equal-style variable, got 'v_U' (not equal-style)",)),
        ("p", "variable U equal exp(1000)", "superficial_velocity z v_U", "",
         (sv + " a finite superficial velocity (velocity), got inf from variable v_U",)),
        ("p", "", "superficial_velocity z 0.01 gate z 0.004 lower never", "",
         ("keyword 'gate' across axis z stops the flux that keyword 'superficial_velocity' holds",)),
        ("p", "", "superficial_velocity z 0.01", "fix_modify f superficial_velocity x 0.01\nrun 1",
         ("keyword 'fix_modify superficial_velocity' expects the axis of the fix command, z, got 'x'",)),
        ("p", "", "", "fix_modify f superficial_velocity z 0.01\nrun 1",
         ("fix_modify superficial_velocity needs the keyword in the fix command",)),
    ]
    for i, (zb, pre, args, post, needles) in enumerate(cases):
        r.expect_error(f"flow_drive/bad_input/{i}", BAD.format(zb=zb, pre=pre, args=args, post=post), needles,
                       f"'{pre} {args} {post}' refused")
    # accepted: a constant, a variable, and fix_modify of the value between runs (the new target
    # holds from the next step)
    p, msg = r.run_script("flow_drive/bad_input/ok", BAD.format(
        zb="p", pre="variable U equal 0.01", args="superficial_velocity z v_U",
        post="fix_modify f superficial_velocity z 0.03\nvariable Ux equal vcm(all,z)\nrun 1\nprint \"RESULT ${Ux}\""))
    m = re.search(r"RESULT (\S+)", p.stdout)
    ok = p.returncode == 0 and m is not None and abs(float(m.group(1)) - 0.03) < 1e-14
    check(ok, f"a variable target, then fix_modify to 0.03 between runs: the flux follows ({msg.strip()[:120]})")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
