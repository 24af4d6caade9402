#!/usr/bin/env python3
"""Uniform suspension settling (inputs/suspension/in.suspension, docs/validation/suspension.md).

The reference is computed from the inputs alone: the steady hindered settling velocity of a
uniform suspension, where each grain's drag (the law's formula, written out here again from
docs/theory/drag.md, not taken from the code) balances its buoyant weight in the mixture,

    K(theta, w) w = theta (rho_p - rho_f) V g,    theta = 1 - phi,
    w = v_p - u_f (slip),  u_f = -phi/(1 - phi) v_p (no net volume flux)  =>  v_p = theta w.

    suspension.py ref  [--d 1e-3 --rhop 1500 ...]      reference velocities
    suspension.py analyse suspension.csv --vref V      settling and ringing of one run
    suspension.py sweep --exe build/liggghts_mpm --work DIR [--quick]   the table of docs/validation/suspension.md

Standard library only (tests/cases/test_suspension.py imports it).
"""
import argparse
import cmath
import math
import os
import re
import shutil
import subprocess
import sys
import time

G = 9.81


def k_difelice(rho, mu, d, th, w):
    """Di Felice (1994), consistent per-grain coefficient K [kg/s]: F = K w."""
    re_ = th * rho * w * d / mu
    chi = 3.7 - 0.65 * math.exp(-(1.5 - math.log10(max(re_, 1e-300))) ** 2 / 2)
    cdre = (0.63 * math.sqrt(re_) + 4.8) ** 2  # Dallavalle C_D times Re
    return math.pi * mu * d / 8 * cdre * th ** (1 - chi)


def k_ergun_wenyu(rho, mu, d, th, w):
    """Ergun (theta <= 0.8) / Wen-Yu (theta > 0.8), the text's (8-27)-(8-29), consistent form."""
    v = math.pi * d ** 3 / 6
    re_ = th * rho * w * d / mu
    if th <= 0.8:
        return v * mu / (d * d * th) * (150 * (1 - th) + 1.75 * re_)
    cdre = 24 * (1 + 0.15 * re_ ** 0.687) if re_ <= 1000 else 0.43 * re_
    return v * 0.75 * mu / d ** 2 * cdre * th ** -2.7


LAWS = {"difelice": k_difelice, "ergun_wenyu": k_ergun_wenyu}


def reference(phi, law="difelice", d=1e-3, rhop=1500.0, rho=1000.0, mu=1e-3, g=G):
    """Steady settling velocity of the grains (m/s, positive down), slip w and Re of the law."""
    th = 1.0 - phi
    f = th * (rhop - rho) * math.pi * d ** 3 / 6 * g  # drag on one grain: buoyant weight in the mixture
    k = LAWS[law]
    lo, hi = 0.0, 100.0
    for _ in range(200):  # K(w) w increases with w
        m = 0.5 * (lo + hi)
        if k(rho, mu, d, th, m) * m < f:
            lo = m
        else:
            hi = m
    w = 0.5 * (lo + hi)
    return th * w, w, th * rho * w * d / mu


def read_csv(path):
    with open(path) as fh:
        rows = [ln.strip() for ln in fh if ln.strip()]
    names = rows[0].split(",")
    cols = {n: [] for n in names}
    for r in rows[1:]:
        for n, x in zip(names, r.split(",")):
            cols[n].append(float(x))
    return cols


def analyse(csv, vref, t1=0.1, t2=None, tring=0.03):
    """Settling and ringing of one run.

    ratio: mean settling velocity of the middle region over [t1, t2] / vref.
    ring: largest |v(t) - v_smooth(t)| / vref over [tring, t2], v_smooth the running mean over
      10 ms (an oscillation faster than about 50 Hz shows in full; the relaxation, tau ~ 15 ms,
      hardly); freq: frequency of the largest Fourier peak of that residual.
    swing: largest |v(t)| / vref over the whole run (the first swings of an acoustic start).
    pring: the same residual measure for the largest pressure, relative to its mean over [t1, t2].
    """
    c = read_csv(csv)
    t, v, p = c["t"], [-x for x in c["v_mid"]], c["p_max"]
    t2 = t[-1] if t2 is None else t2
    win = [i for i, x in enumerate(t) if t1 <= x <= t2 + 1e-12]
    vm = sum(v[i] for i in win) / len(win)
    pm = sum(p[i] for i in win) / len(win)
    dt = (t[-1] - t[0]) / (len(t) - 1)
    h = max(1, int(round(0.005 / dt)))

    def resid(y):
        out = []
        for i in range(len(y)):
            a, b = max(0, i - h), min(len(y), i + h + 1)
            out.append(y[i] - sum(y[a:b]) / (b - a))
        return out

    rv, rp = resid(v), resid(p)
    sel = [i for i, x in enumerate(t) if tring <= x <= t2 + 1e-12 and i >= h and i < len(t) - h]
    ring = max(abs(rv[i]) for i in sel) / vref
    pring = max(abs(rp[i]) for i in sel) / pm if pm else float("nan")
    # frequency of the residual (direct DFT over the selected samples)
    n = len(sel)
    best, freq = 0.0, 0.0
    for kf in range(1, n // 2):
        s = sum(rv[sel[j]] * cmath.exp(-2j * math.pi * kf * j / n) for j in range(n))
        if abs(s) > best:
            best, freq = abs(s), kf / (n * dt)
    swing = max(abs(x) for x in v) / vref
    return {"ratio": vm / vref, "v": vm, "ring": ring, "freq": freq, "swing": swing, "pring": pring,
            "pmean": pm, "nmid": sum(c["n_mid"][i] for i in win) / len(win)}


def run(exe, work, name, variables, mpirun=()):
    d = os.path.join(work, name)
    os.makedirs(d, exist_ok=True)
    shutil.copy(INPUT, os.path.join(d, "in.suspension"))  # the run reads its own copy
    cmd = list(mpirun) + [os.path.abspath(exe), "-in", "in.suspension", "-log", "log.lammps", "-echo", "none"]
    for k, x in variables.items():
        cmd += ["-var", k, str(x)]
    t0 = time.time()
    p = subprocess.run(cmd, cwd=d, capture_output=True, text=True)
    wall = time.time() - t0
    if p.returncode != 0:
        raise RuntimeError(f"{name}: exit {p.returncode}\n{p.stdout[-3000:]}\n{p.stderr[-3000:]}")
    return os.path.join(d, "suspension.csv"), result_line(p.stdout), wall, p.stdout


def result_line(stdout):
    """The RESULT line of in.suspension as a dict of floats (grains, phi, L, hs, depth, dx, dt, z0, z1)."""
    m = re.search(r"RESULT grains (\S+) phi (\S+) L (\S+) hs (\S+) depth (\S+) dx (\S+) mid (\S+) (\S+) dt (\S+)", stdout)
    if not m:
        return None
    return dict(zip(("grains", "phi", "L", "hs", "depth", "dx", "z0", "z1", "dt"), map(float, m.groups())))


def phi_mid(res, info, d=1e-3):
    """Solid fraction of the middle region: its mean grain count over the window (analyse) times V."""
    return res["nmid"] * math.pi * d ** 3 / 6 / (info["L"] ** 2 * (info["z1"] - info["z0"]))


INPUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "inputs", "suspension", "in.suspension")

# model x options of the table in docs/validation/suspension.md
VARIANTS = [
    ("proj", {"pressure": "projection"}),
    ("eos", {"pressure": "eos"}),
    ("proj smooth", {"pressure": "projection", "extra": "theta_smooth 0.002"}),
    ("eos smooth", {"pressure": "eos", "extra": "theta_smooth 0.002"}),
    # the grains' pressure force from the projection's multiplier (the default before 24 Nov 2026)
    ("proj smooth multiplier", {"pressure": "projection", "extra": "theta_smooth 0.002 grain_pressure multiplier"}),
]


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("ref")
    r.add_argument("--law", default="difelice")
    r.add_argument("--d", type=float, default=1e-3)
    r.add_argument("--rhop", type=float, default=1500.0)
    a = sub.add_parser("analyse")
    a.add_argument("csv")
    a.add_argument("--vref", type=float, required=True)
    a.add_argument("--t1", type=float, default=0.1)
    s = sub.add_parser("sweep")
    s.add_argument("--exe", required=True)
    s.add_argument("--work", required=True)
    s.add_argument("--phis", default="0.1,0.2,0.3")
    s.add_argument("--variants", default="")
    s.add_argument("--var", action="append", default=[], help="k=v passed to every run")
    s.add_argument("--t1", type=float, default=0.1)
    o = ap.parse_args()
    if o.cmd == "ref":
        for phi in (0.0, 0.1, 0.2, 0.3):
            v, w, re_ = reference(phi, o.law, o.d, o.rhop)
            print(f"phi {phi:.1f}: v_p {v:.5f} m/s  slip {w:.5f} m/s  Re {re_:.2f}")
    elif o.cmd == "analyse":
        print(analyse(o.csv, o.vref, o.t1))
    else:
        common = dict(kv.split("=", 1) for kv in o.var)
        names = [x for x in o.variants.split(",") if x] or [n for n, _ in VARIANTS]
        print("| phi | model | options | grains | phi (all) | phi (mid) | v_ref(mid) mm/s | v/v_ref(mid) | v/v_ref(all) "
              "| ring | freq Hz | swing | p ring | wall s |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for name, var in VARIANTS:
            if name not in names:
                continue
            for phi in [float(x) for x in o.phis.split(",")]:
                vv = dict(var, phi=phi, **common)
                tag = f"phi{phi}_{name.replace(' ', '_')}" + "".join(f"_{k}{x}" for k, x in common.items())
                csv, info, wall, _ = run(o.exe, o.work, tag, vv)
                law, dg, rp = vv.get("drag", "difelice"), float(vv.get("d", 1e-3)), float(vv.get("rhop", 1500.0))
                vglob = reference(info["phi"], law, dg, rp)[0]
                res = analyse(csv, vglob, o.t1)
                pm = phi_mid(res, info, dg)
                vref = reference(pm, law, dg, rp)[0]
                res = analyse(csv, vref, o.t1)
                model, _, opts = name.partition(" ")
                print(f"| {phi} | {model} | {opts or '-'} | {int(info['grains'])} | {info['phi']:.4f} | {pm:.4f} | "
                      f"{1e3 * vref:.2f} | {res['ratio']:.4f} | {res['v'] / vglob:.4f} | "
                      f"{res['ring']:.3f} | {res['freq']:.0f} | {res['swing']:.2f} | {res['pring']:.3f} | {wall:.0f} |",
                      flush=True)


if __name__ == "__main__":
    main()
