#!/usr/bin/env python3
"""Redraws Figures 3.7, 3.8 and 5.1-5.8 of Yang (2016), Part I, from laser_drill output.

  tools/python tools/laser_figures.py --work figs/ [--melt-energy advected|text] [--exe build/laser_drill] [--sweep DIR]

Runs the cases it needs into --work/<melt layer>/ (a few seconds each, skipped when
the run directory already has a summary.json) and writes fig3_7.png ... fig5_8.png
into --work. --melt-energy text draws the dissertation's linear melt layer (the
model of chapter 5); the default is laser_drill's default, the energy-consistent
advected layer, whose holes are 16-22 % shallower (docs/theory/laser_model.md 2.9).
With --sweep, Figure 5.1 uses DIR/sweep.csv of tools/laser_sweep.py.
"""
import argparse
import csv
import os
import sys

import h5py
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from laser_common import find_exe, run_case  # noqa: E402

INTENSITIES = [2.5e10, 5.0e10, 7.5e10, 10.0e10, 12.5e10, 16.0e10]


def read_csv(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) if r[k] not in ("", "null") else np.nan for r in rows]) for k in rows[0]}


class Runner:
    def __init__(self, exe, work, melt_energy):
        self.exe, self.work, self.melt_energy = exe, os.path.join(work, melt_energy), melt_energy

    def get(self, name, args):
        d = os.path.join(self.work, name)
        if not os.path.exists(os.path.join(d, "summary.json")):
            code, s, err = run_case(self.exe, d, list(args) + ["--melt-energy", self.melt_energy])
            if code != 0:
                print("%s: %s" % (name, err), file=sys.stderr)
                return None
        return d


def fig3(work, exe):
    d = os.path.join(work, "conduction")
    if not os.path.exists(os.path.join(d, "conduction_table.csv")):
        import subprocess
        subprocess.run([exe, "--conduction-table", "--out", d], check=True, capture_output=True)
    t = read_csv(os.path.join(d, "conduction_table.csv"))
    x = t["s"] + 1.0  # tau / tau_m
    # per unit theta_i in n / sqrt(N_a tau_m); theta_i < 0 so the physical gradient is negative
    fig, ax = plt.subplots(figsize=(6, 4.2))
    ax.semilogx(x, -t["exact"], "k-", lw=2, label="exact (3-29)")
    ax.semilogx(x, -t["stefan_s1"], "b--", label=r"Stefan $\theta_{s1}$ (3-30)")
    ax.semilogx(x, -t["correction_s2"], "g-.", label=r"$\theta_{s2}$ (3-33)")
    ax.semilogx(x, -t["correction_s3"], "r:", label=r"$\theta_{s3}$ (FD)")
    ax.semilogx(x, -t["reference_fd"], "y.", ms=3, label="independent fine FD")
    ax.set_xlabel(r"$\tau/\tau_m$")
    ax.set_ylabel(r"$\partial\theta_s/\partial n\ \cdot \sqrt{N_\alpha\tau_m}/|\theta_i|$")
    ax.set_title("Fig. 3.7: temperature gradient at the solid-liquid boundary")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(work, "fig3_7.png"), dpi=110)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(6, 4.2))
    ax.semilogx(x, -t["exact"], "k-", lw=2, label="exact (3-29)")
    ax.semilogx(x, -t["shifted_1tau0"], "b--", label=r"approximate 1: shift $\tau_0$")
    ax.semilogx(x, -t["shifted_3tau0"], "r-.", label=r"approximate 2: shift $3\tau_0$ (3-36)")
    ax.semilogx(x, -t["shifted_flux_continuous"], "g:", label=r"shift $4\tau_m/\pi^2$ (flux continuous)")
    ax.axvline(5.0, color="gray", lw=0.7)
    ax.set_xlabel(r"$\tau/\tau_m$")
    ax.set_ylabel(r"$-\partial\theta_s/\partial n\ \cdot \sqrt{N_\alpha\tau_m}/\theta_i$")
    ax.set_title("Fig. 3.8: exact and approximate solutions")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(work, "fig3_8.png"), dpi=110)
    plt.close(fig)


def fig5_1(work, R, sweep):
    fig, ax = plt.subplots(figsize=(6, 4.2))
    if sweep:
        t = list(csv.DictReader(open(os.path.join(sweep, "sweep.csv"))))
        groups = {}
        for r in t:
            if r["status"] != "ok":
                continue
            key = r["model"] + ("" if not r["parameter"] else " %s" % r["parameter"])
            groups.setdefault(key, []).append((float(r["intensity_W_per_m2"]), float(r["removal_rate_m3_per_s"])))
    else:
        groups = {}
        for key, name_fmt, args in (("conduction", "I%g_cond", ["--model", "conduction"]),
                                    ("rising m=2", "I%g_rising2", ["--model", "rising", "--m", "2"]),
                                    ("risingfall xi_p=0.6", "I%g_rf0.6", ["--xi-p", "0.6"]),
                                    ("risingfall xi_p=1", "I%g_rf1", ["--xi-p", "1"])):
            for I in INTENSITIES:
                d = R.get(name_fmt % I, ["--intensity", I] + args)
                if d:
                    s = read_summary(d)
                    if s["status"] == "ok":
                        groups.setdefault(key, []).append((I, s["removal_rate_m3_per_s"]))
    for key, pts in groups.items():
        pts.sort()
        ax.plot([p[0] / 1e10 for p in pts], [p[1] * 1e9 for p in pts], "o-", ms=3, label=key)
    ax.set_xlabel(r"centre intensity [$10^{10}$ W/m$^2$]")
    ax.set_ylabel(r"removal rate [mm$^3$/s]")
    ax.set_title("Fig. 5.1: material removal rate (no experimental data here)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(work, "fig5_1.png"), dpi=110)
    plt.close(fig)


def read_summary(d):
    import json
    with open(os.path.join(d, "summary.json")) as f:
        return json.load(f)


def fig5_2(work, d):
    with h5py.File(os.path.join(d, "profiles.h5")) as h:
        xi, t, S1, S2 = h["xi"][:], h["time_s"][:], h["S1net_m"][:], h["S2_m"][:]
    R = 0.254e-3
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for k in np.linspace(0, len(t) - 1, 8).astype(int)[1:]:
        r = np.concatenate([-xi[::-1], xi]) * R * 1e3
        ax.plot(r, -np.concatenate([S1[k][::-1], S1[k]]) * 1e3, "-", label="%.0f us" % (t[k] * 1e6))
        ax.plot(r, -np.concatenate([S2[k][::-1], S2[k]]) * 1e3, "k:", lw=0.6)
    ax.set_xlabel("r [mm]")
    ax.set_ylabel("z [mm] (net surface; dotted: melt-solid interface)")
    ax.set_title(r"Fig. 5.2: hole profiles, rising-fall $\xi_p$ = 1, 7.5e10 W/m$^2$")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(work, "fig5_2.png"), dpi=110)
    plt.close(fig)


def fig5_3_4(work, R):
    figp, axp = plt.subplots(figsize=(6, 4.2))
    figt, axt = plt.subplots(figsize=(6, 4.2))
    for I in INTENSITIES:
        d = R.get("I%g_rf1" % I, ["--intensity", I, "--xi-p", "1"])
        if not d:
            continue
        p = read_csv(os.path.join(d, "final_profile.csv"))
        axp.plot(p["xi"], p["pressure_Pa"] / 1e6, label="%.1f" % (I / 1e10))
        axt.plot(p["xi"], p["T_surface_K"], label="%.1f" % (I / 1e10))
    axp.set_xlabel(r"$\xi$")
    axp.set_ylabel("recoil pressure [MPa]")
    axp.set_title(r"Fig. 5.3: pressure at $\tau_p$, rising-fall $\xi_p$ = 1")
    axp.legend(title=r"$I_0$ [$10^{10}$ W/m$^2$]", fontsize=7)
    figp.tight_layout()
    figp.savefig(os.path.join(work, "fig5_3.png"), dpi=110)
    axt.set_xlabel(r"$\xi$")
    axt.set_ylabel("surface temperature [K]")
    axt.set_title(r"Fig. 5.4: temperature at $\tau_p$, rising-fall $\xi_p$ = 1")
    axt.legend(title=r"$I_0$ [$10^{10}$ W/m$^2$]", fontsize=7)
    figt.tight_layout()
    figt.savefig(os.path.join(work, "fig5_4.png"), dpi=110)
    plt.close(figp)
    plt.close(figt)


def fig_history(work, d, name, title):
    c = read_csv(os.path.join(d, "centre.csv"))
    t = c["t_s"] * 1e6
    fig, ax = plt.subplots(3, 1, figsize=(6, 7), sharex=True)
    ax[0].plot(t, c["u_peak_m_per_s"])
    ax[0].set_ylabel("peak radial velocity [m/s]")
    ax[1].plot(t, c["T_K"])
    ax[1].set_ylabel("centre temperature [K]")
    ax[2].plot(t, c["p_Pa"] / 1e6)
    ax[2].set_ylabel("centre pressure [MPa]")
    ax[2].set_xlabel("t [us]")
    ax[0].set_title(title)
    fig.tight_layout()
    fig.savefig(os.path.join(work, name), dpi=110)
    plt.close(fig)


def fig_rates(work, d, name, title):
    c = read_csv(os.path.join(d, "centre.csv"))
    t = c["t_s"] * 1e6
    fig, ax = plt.subplots(2, 1, figsize=(6, 7), sharex=True)
    for key, lab, ls in (("xi1node", r"$\xi$ = 0.0125", "-"), ("xi_1", r"$\xi$ = 1", "--")):
        ax[0].plot(t, c["melting_rate_" + key], "b" + ls, label="melting, " + lab)
        ax[0].plot(t, c["vaporization_rate_" + key], "r" + ls, label="vaporization, " + lab)
        ax[1].plot(t, c["flow_v_" + key], "g" + ls, label="flow v at the surface, " + lab)
    ax[0].set_ylabel("rate [m/s]")
    ax[0].legend(fontsize=7)
    ax[1].set_ylabel("vertical flow velocity [m/s]")
    ax[1].set_xlabel("t [us]")
    ax[1].legend(fontsize=7)
    ax[0].set_title(title)
    fig.tight_layout()
    fig.savefig(os.path.join(work, name), dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--work", default="laser_figures")
    ap.add_argument("--exe")
    ap.add_argument("--sweep")
    ap.add_argument("--melt-energy", choices=("advected", "text"), default="advected")
    a = ap.parse_args()
    exe = find_exe(a.exe)
    os.makedirs(a.work, exist_ok=True)
    R = Runner(exe, a.work, a.melt_energy)
    fig3(a.work, exe)
    fig5_1(a.work, R, a.sweep)
    d = R.get("I7.5e+10_rf1", ["--intensity", 7.5e10, "--xi-p", "1"])
    fig5_2(a.work, d)
    fig5_3_4(a.work, R)
    d = R.get("rising2", ["--model", "rising", "--m", "2"])
    fig_history(a.work, d, "fig5_5.png", "Fig. 5.5: rising profile m = 2, 7.5e10 W/m$^2$")
    d = R.get("rf0.6", ["--xi-p", "0.6"])
    fig_history(a.work, d, "fig5_6.png", r"Fig. 5.6: rising-fall $\xi_p$ = 0.6, 7.5e10 W/m$^2$")
    d = R.get("I7.5e+10_rf1", ["--intensity", 7.5e10, "--xi-p", "1"])
    fig_rates(a.work, d, "fig5_7.png", "Fig. 5.7: rates, Pr = 0.142, rising-fall $\\xi_p$ = 1")
    # the explicit update (4-14) is unstable for Pr = 142 (docs/theory/laser_model.md)
    d = R.get("pr142_rf1", ["--pr", 142, "--xi-p", "1", "--melt-update", "implicit"])
    label = r"rising-fall $\xi_p$ = 1, implicit melt update"
    if d is None:
        d = R.get("pr142_rising2", ["--pr", 142, "--model", "rising", "--m", "2"])
        label = "rising m = 2 (rising-fall failed, see stderr)"
    if d:
        fig_rates(a.work, d, "fig5_8.png", "Fig. 5.8: rates, Pr = 142, " + label)
    print("wrote figures to %s (%s melt layer)" % (a.work, a.melt_energy))


if __name__ == "__main__":
    main()
