#!/usr/bin/env python3
"""The fluidized bed of C8 (inputs/fluidized_bed/in.fluidized_bed, docs/validation/fluidized_bed.md).

Runs the input (or reads a finished run's folder) and compares, stage by stage (each held
superficial velocity U, the means over the last half of the stage):

* the pressure drop over the bed dP = (G - rho_f g) L_z against Ergun for the bed at rest (its
  height H0 and voidage eps0 from the run's RESULT line) below minimum fluidization, and against the
  beads' buoyant weight per area W/A = N V (rho_p - rho_f) g / A above it (the plateau);
* the onset: where a fit dP = a U + b U^2 through the fixed-bed stages meets the plateau, against
  Wen and Yu's correlation Re_mf = sqrt(33.7^2 + 0.0408 Ar) - 33.7 (and Ergun's own onset at eps0);
* the expansion: the bed height H = 2 zmean (mean height of the beads' centres above the
  distributor; exact for a uniform bed) gives the voidage eps = 1 - N V / (A H), against
  Richardson and Zaki, U = u_t eps^n, with u_t the terminal velocity of one bead under the drag law
  the fix uses (ergun_wenyu at theta = 1: Wen-Yu's C_D, Schiller-Naumann below Re = 1000, 0.43 above)
  and n from Richardson and Zaki's correlation in Re_t (no wall term: the box is periodic); and
  against the uniform bed that the drag law itself holds up (the law's balance, for reference).

    fluidized_bed.py run --exe build/liggghts_mpm --work DIR [--var NAME VALUE ...] [--figure PNG]
    fluidized_bed.py analyse DIR [--figure PNG]
    fluidized_bed.py analyse_open DIR     (a run of in.fluidized_bed_open: fed through the floor)

Prints the table of docs/validation/fluidized_bed.md and the acceptance lines. Standard library for
the analysis (tests/cases/test_fluidized_bed.py imports it); matplotlib only for --figure.
"""
import argparse
import math
import os
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "cases"))
from cases import read_csv  # noqa: E402  (the case drivers' CSV reader, plain Python)
sys.path.insert(0, HERE)
# per-bead drag coefficient K (F = K w) of the fix's ergun_wenyu law, consistent form
# (docs/theory/drag.md), written out in suspension.py from the formulas, not taken from the code
from suspension import k_ergun_wenyu  # noqa: E402
INPUT = os.path.join(HERE, "..", "inputs", "fluidized_bed", "in.fluidized_bed")


def read_result(log):
    """The key/value pairs of the input's RESULT line."""
    m = re.search(r"^RESULT (.*)$", log, re.M)
    if not m:
        raise RuntimeError("no RESULT line in the run's output")
    w = m.group(1).split()
    return {w[i]: float(w[i + 1]) for i in range(0, len(w) - 1, 2)}


# ------------------------------------------------------------------ references (inputs alone)
def ergun_dp(U, eps, H, d, rho, mu):
    """Ergun's pressure drop over a fixed bed of height H (Pa)."""
    return H * (150.0 * (1 - eps) ** 2 / eps ** 3 * mu * U / d ** 2 + 1.75 * (1 - eps) / eps ** 3 * rho * U * U / d)


def wen_yu_umf(d, rhop, rho, mu, g):
    ar = rho * (rhop - rho) * g * d ** 3 / mu ** 2
    return (math.sqrt(33.7 ** 2 + 0.0408 * ar) - 33.7) * mu / (rho * d)


def bisect(f, lo, hi, n=200):
    """The root of an increasing f on [lo, hi]."""
    for _ in range(n):
        m = 0.5 * (lo + hi)
        if f(m) < 0.0:
            lo = m
        else:
            hi = m
    return 0.5 * (lo + hi)


def terminal_velocity(d, rhop, rho, mu, g):
    """One bead alone (theta = 1) under the law: K(1, u) u = (rho_p - rho_f) V g."""
    wgt = (rhop - rho) * math.pi * d ** 3 / 6 * g
    return bisect(lambda u: k_ergun_wenyu(rho, mu, d, 1.0, u) * u - wgt, 0.0, 100.0)


def rz_exponent(re_t):
    """Richardson and Zaki (1954), d/D -> 0."""
    if re_t < 0.2:
        return 4.65
    if re_t < 1.0:
        return 4.35 * re_t ** -0.03
    if re_t < 500.0:
        return 4.45 * re_t ** -0.1
    return 2.39


def law_voidage(U, d, rhop, rho, mu, g):
    """The uniform bed the law holds up at superficial velocity U (beads at rest): per bead
    K(eps, U/eps) U/eps = eps (rho_p - rho_f) V g (the mixture's balance, docs/validation/suspension.md)."""
    V = math.pi * d ** 3 / 6
    return bisect(lambda e: -(k_ergun_wenyu(rho, mu, d, e, U / e) * U / e - e * (rhop - rho) * V * g), 0.3, 0.999)


# ------------------------------------------------------------------ the run's stages
def stages(cols):
    """Per stage: the means over its last half of U (target), the measured U, dP, zmean, and the
    standard deviation of dP."""
    out = []
    count = {s: cols["stage"].count(s) for s in set(cols["stage"])}
    full = max(count.values())
    for s in sorted(count):
        idx = [i for i, v in enumerate(cols["stage"]) if v == s]
        if len(idx) < full:  # a run stopped inside this stage
            print(f"stage {s:.0f} incomplete ({len(idx)} of {full} rows): left out")
            continue
        half = idx[len(idx) // 2:]
        mean = lambda k: sum(cols[k][i] for i in half) / len(half)  # noqa: E731
        dp = mean("dP")
        sd = math.sqrt(sum((cols["dP"][i] - dp) ** 2 for i in half) / len(half))
        out.append({"U": mean("Ut"), "Um": mean("U"), "dP": dp, "dP_sd": sd, "zmean": mean("zmean"),
                    "n": len(half), "nfloor": mean("nfloor") if "nfloor" in cols else float("nan")})
    return out


def analyse(folder, figure=None, out=sys.stdout):
    with open(os.path.join(folder, "log.txt")) as f:
        res = read_result(f.read())
    cols = read_csv(os.path.join(folder, "fluidized_bed.csv"))
    d, rhop, rho, mu, g = res["d"], res["rhop"], res["rho"], res["mu"], res["g"]
    N, L, H0, eps0 = res["beads"], res["L"], res["H0"], res["eps0"]
    V, A = math.pi * d ** 3 / 6, L * L
    W = N * V * (rhop - rho) * g / A
    umf_wy = wen_yu_umf(d, rhop, rho, mu, g)
    umf_erg = bisect(lambda u: ergun_dp(u, eps0, H0, d, rho, mu) - W, 0.0, 10.0)
    ut = terminal_velocity(d, rhop, rho, mu, g)
    re_t = rho * ut * d / mu
    n = rz_exponent(re_t)
    st = stages(cols)
    fixed, fluid = [], []
    p = lambda *a: print(*a, file=out)  # noqa: E731
    p(f"beads {N:.0f}, d {d * 1e3:g} mm, box {L * 1e3:g} mm x {L * 1e3:g} mm x {res['Lz'] * 1e3:g} mm, "
      f"bed at rest H0 = {H0 * 1e3:.2f} mm, eps0 = {eps0:.4f}")
    p(f"buoyant weight per area W/A = {W:.2f} Pa; U_mf: Wen-Yu {umf_wy:.4f} m/s, Ergun at eps0 {umf_erg:.4f} m/s; "
      f"u_t = {ut:.4f} m/s (Re_t {re_t:.0f}), Richardson-Zaki n = {n:.3f}")
    p("")
    p("| U (m/s) | U held (m/s) | dP (Pa) | sd dP (Pa) | dP / (W/A) | Ergun at eps0 (Pa) | H / H0 | eps | "
      "eps R-Z | eps / eps R-Z - 1 | eps of the law | beads on the distributor |")
    p("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for s in st:
        H = 2.0 * s["zmean"]
        eps = 1.0 - N * V / (A * H)
        s.update(H=H, eps=eps)
        erg = ergun_dp(s["U"], eps0, H0, d, rho, mu)
        # fixed: clearly below the plateau and not expanded; fluidized: expanded by more than 5 %;
        # between them the onset (in the table, in neither set)
        if H / H0 < 1.03 and s["dP"] < 0.9 * W:
            fixed.append(s)
            p(f"| {s['U']:.4f} | {s['Um']:.6f} | {s['dP']:.2f} | {s['dP_sd']:.2f} | {s['dP'] / W:.4f} | {erg:.2f} | "
              f"{H / H0:.4f} | {eps:.4f} | - | - | - | {s['nfloor']:.1f} |")
        else:
            rz = (s["U"] / ut) ** (1.0 / n)
            law = law_voidage(s["U"], d, rhop, rho, mu, g)
            s.update(rz=rz, law=law)
            if H / H0 > 1.05:
                fluid.append(s)
            p(f"| {s['U']:.4f} | {s['Um']:.6f} | {s['dP']:.2f} | {s['dP_sd']:.2f} | {s['dP'] / W:.4f} | {erg:.2f} | "
              f"{H / H0:.4f} | {eps:.4f} | {rz:.4f} | {eps / rz - 1.0:+.3f} | {law:.4f} | {s['nfloor']:.1f} |")
    p("")
    result = {"inputs": res, "W": W, "umf_wy": umf_wy, "umf_ergun": umf_erg, "ut": ut, "n": n, "stages": st, "eps0": eps0, "H0": H0}
    # the onset: dP = a U + b U^2 through the fixed-bed stages (least squares), met with the plateau
    if len(fixed) >= 2 and fluid:
        s11 = sum(s["U"] ** 2 for s in fixed)
        s12 = sum(s["U"] ** 3 for s in fixed)
        s22 = sum(s["U"] ** 4 for s in fixed)
        r1 = sum(s["U"] * s["dP"] for s in fixed)
        r2 = sum(s["U"] ** 2 * s["dP"] for s in fixed)
        det = s11 * s22 - s12 * s12
        a, b = (r1 * s22 - r2 * s12) / det, (s11 * r2 - s12 * r1) / det
        plateau = sum(s["dP"] for s in fluid) / len(fluid)
        umf = (-a + math.sqrt(a * a + 4.0 * b * plateau)) / (2.0 * b) if b > 0 else plateau / a
        erg_dev = max(abs(s["dP"] / ergun_dp(s["U"], eps0, H0, d, rho, mu) - 1.0) for s in fixed)
        pl_dev = max(abs(s["dP"] / W - 1.0) for s in fluid)
        rz_dev = max(abs(s["eps"] / s["rz"] - 1.0) for s in fluid)
        law_dev = max(abs(s["eps"] / s["law"] - 1.0) for s in fluid)
        result.update(umf=umf, plateau=plateau / W, ergun_dev=erg_dev, plateau_dev=pl_dev, rz_dev=rz_dev,
                      law_dev=law_dev)
        p(f"fixed bed: {len(fixed)} stages, dP within {100 * erg_dev:.1f} % of Ergun at eps0")
        p(f"onset (fixed-bed fit dP = {a:.4g} U + {b:.4g} U^2 met with the plateau): U_mf = {umf:.4f} m/s, "
          f"{100 * (umf / umf_wy - 1):+.1f} % of Wen-Yu ({umf_wy:.4f}); acceptance 10 %: "
          f"{'holds' if abs(umf / umf_wy - 1) <= 0.10 else 'FAILS'}")
        p(f"plateau: {len(fluid)} fluidized stages, dP / (W/A) = {plateau / W:.4f} on average, each within "
          f"{100 * pl_dev:.2f} %; acceptance 5 %: {'holds' if pl_dev <= 0.05 else 'FAILS'}")
        for s in fluid:
            p(f"expansion at U = {s['U']:.4f}: eps {s['eps']:.4f}, {100 * (s['eps'] / s['rz'] - 1):+.1f} % of "
              f"Richardson-Zaki ({'holds' if abs(s['eps'] / s['rz'] - 1) <= 0.15 else 'FAILS'} 15 %), "
              f"{100 * (s['eps'] / s['law'] - 1):+.1f} % of the drag law's uniform bed (the law itself "
              f"{100 * (s['law'] / s['rz'] - 1):+.1f} % of Richardson-Zaki)")
        p(f"expansion: eps within {100 * rz_dev:.1f} % of Richardson-Zaki at every fluidized stage (acceptance 15 %: "
          f"{'holds' if rz_dev <= 0.15 else 'FAILS'}), within {100 * law_dev:.1f} % of the drag law's uniform bed")
    else:
        p(f"not enough stages for the onset: {len(fixed)} fixed, {len(fluid)} fluidized")
    if figure:
        plot(result, d, rhop, rho, mu, g, figure)
    return result


def plot(r, d, rhop, rho, mu, g, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    st = r["stages"]
    umax = 1.1 * max(s["U"] for s in st)
    us = [umax * i / 200 for i in range(1, 201)]
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    a = ax[0]
    a.plot(us, [ergun_dp(u, r["eps0"], r["H0"], d, rho, mu) for u in us], "k--", lw=1, label="Ergun (bed at rest)")
    a.axhline(r["W"], color="tab:green", lw=1, label="buoyant weight per area")
    a.axvline(r["umf_wy"], color="tab:red", lw=1, ls=":", label="Wen-Yu $U_{mf}$")
    if "umf" in r:
        a.axvline(r["umf"], color="tab:blue", lw=1, ls="-.", label="onset (measured)")
    a.plot([s["U"] for s in st], [s["dP"] for s in st], "o", color="tab:blue", label="fix mpm/fluid")
    a.set_ylim(0, 1.4 * r["W"])
    a.set_xlabel("superficial velocity U (m/s)")
    a.set_ylabel("pressure drop over the bed (Pa)")
    a.legend(fontsize=8)
    a = ax[1]
    fl = [s for s in st if "rz" in s]
    uf = [umax * i / 200 for i in range(1, 201) if umax * i / 200 >= 0.8 * r["umf_wy"]]
    a.plot(uf, [(u / r["ut"]) ** (1 / r["n"]) for u in uf], "k--", lw=1,
           label=f"Richardson-Zaki, n = {r['n']:.2f}")
    a.plot(uf, [law_voidage(u, d, rhop, rho, mu, g) for u in uf], ":", color="gray", lw=1,
           label="uniform bed of the drag law")
    a.plot([s["U"] for s in st], [s["eps"] for s in st], "o", color="tab:blue", label="fix mpm/fluid (2 zmean)")
    a.set_xlabel("superficial velocity U (m/s)")
    a.set_ylabel("bed voidage")
    a.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


def run(exe, work, variables, np=1, mpirun=None):
    os.makedirs(work, exist_ok=True)
    shutil.copy(INPUT, work)
    cmd = [os.path.abspath(exe), "-in", "in.fluidized_bed", "-echo", "none"]
    for k, v in variables:
        cmd += ["-var", k, str(v)]
    if np > 1:
        cmd = (mpirun or ["mpirun", "--allow-run-as-root", "--oversubscribe"]) + ["-np", str(np)] + cmd
    p = subprocess.run(cmd, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, errors="replace")
    with open(os.path.join(work, "log.txt"), "w") as f:
        f.write(p.stdout)
    if p.returncode != 0 or "ERROR" in p.stdout:
        raise RuntimeError("liggghts_mpm exited with %d:\n%s" % (p.returncode, "\n".join(p.stdout.splitlines()[-15:])))


def analyse_open(folder, out=sys.stdout):
    """The run of in.fluidized_bed_open (the water fed through the floor, drained at the top): per
    stage (the means over its second half) dP from the two probes against Ergun at the bed's
    voidage at rest and the buoyant weight per area W/A, the bed height; the water's mass against the
    fill's + in - out at every output, and the range of the mass in the box over each stage's second
    half in layers of points across the inflow (rho A dx / 2, fill 2 2 2)."""
    with open(os.path.join(folder, "log.txt")) as f:
        p = read_result(f.read())
    cols = read_csv(os.path.join(folder, "fluidized_bed_open.csv"))
    A, V = p["L"] * p["L"], math.pi * p["d"] ** 3 / 6.0
    W = p["beads"] * V * (p["rhop"] - p["rho"]) * p["g"] / A
    layer = p["rho"] * A * p["dx"] / 2.0
    bal = [m - a + b for m, a, b in zip(cols["mass"], cols["min"], cols["mout"])]
    res = {"W": W, "H0": p["H0"], "eps0": p["eps0"], "balance": (max(bal) - min(bal)) / bal[0], "stages": []}
    print(f"beads {int(p['beads'])}, H0 {p['H0'] * 1e3:.2f} mm, eps0 {p['eps0']:.4f}, W/A {W:.2f} Pa; "
          f"water mass - in + out over {len(bal)} outputs: spread {res['balance']:.1e} of it", file=out)
    print("| U (m/s) | dP (Pa) | sd dP (Pa) | dP / (W/A) | Ergun at eps0 (Pa) | H / H0 | mass in the box: range (layers) | "
          "in, out (layers) |", file=out)
    print("|---|---|---|---|---|---|---|---|", file=out)
    for s in sorted(set(cols["stage"])):
        idx = [i for i, v in enumerate(cols["stage"]) if v == s]
        idx = idx[len(idx) // 2:]
        mean = lambda k: sum(cols[k][i] for i in idx) / len(idx)  # noqa: E731
        dp = mean("dP")
        sd = math.sqrt(sum((cols["dP"][i] - dp) ** 2 for i in idx) / len(idx))
        U, H = cols["U"][idx[0]], 2.0 * mean("zmean")
        ms = [cols["mass"][i] for i in idx]
        st = {"U": U, "dP": dp, "sd": sd, "H": H, "range": (max(ms) - min(ms)) / layer}
        res["stages"].append(st)
        print(f"| {U:.4f} | {dp:.2f} | {sd:.2f} | {dp / W:.4f} | {ergun_dp(U, p['eps0'], p['H0'], p['d'], p['rho'], p['mu']):.2f} "
              f"| {H / p['H0']:.4f} | {st['range']:.3f} | {cols['min'][idx[-1]] / layer:.2f}, "
              f"{cols['mout'][idx[-1]] / layer:.2f} |", file=out)
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--exe", required=True)
    r.add_argument("--work", required=True)
    r.add_argument("--var", nargs=2, action="append", default=[], metavar=("NAME", "VALUE"))
    r.add_argument("--figure")
    a = sub.add_parser("analyse")
    a.add_argument("folder")
    a.add_argument("--figure")
    o = sub.add_parser("analyse_open")
    o.add_argument("folder")
    args = ap.parse_args()
    if args.cmd == "run":
        run(args.exe, args.work, args.var)
        analyse(args.work, args.figure)
    elif args.cmd == "analyse_open":
        analyse_open(args.folder)
    else:
        analyse(args.folder, args.figure)


if __name__ == "__main__":
    main()
