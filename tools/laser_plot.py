#!/usr/bin/env python3
"""Draws one laser_drill run as PNG: hole profile over time, centre surface
temperature and pressure, and the removal rate.

    tools/python tools/laser_plot.py RUN_DIR [--out FILE.png]

RUN_DIR is a complete output folder of laser_drill (summary.json present);
profiles.h5 gives the profiles (every dataset carries a 'units' attribute)
and centre.csv the centre history.
"""
import argparse
import json
import pathlib
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read_run(run):
    run = pathlib.Path(run)
    summary = run / "summary.json"
    if not summary.is_file():
        sys.exit(f"laser_plot: {run} holds no summary.json (not a complete laser_drill run)")
    with open(summary) as f:
        s = json.load(f)
    with h5py.File(run / "profiles.h5", "r") as h:
        units = {k: h[k].attrs["units"].decode() if isinstance(h[k].attrs["units"], bytes)
                 else str(h[k].attrs["units"]) for k in h}
        p = {k: np.asarray(h[k]) for k in h}
    c = np.genfromtxt(run / "centre.csv", delimiter=",", names=True)
    return s, p, units, c


def plot(run, out):
    s, p, units, c = read_run(run)
    R = s["case"]["radius_m"]
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    # hole profile (net surface) at up to 8 times
    t = p["time_s"]
    r_mm = p["xi"] * R * 1e3
    for k in np.unique(np.linspace(0, len(t) - 1, min(8, len(t))).astype(int)):
        ax[0, 0].plot(r_mm, -p["S1net_m"][k] * 1e3, label=f"{t[k] * 1e6:.3g} us")
    ax[0, 0].set_xlabel("r [mm]")
    ax[0, 0].set_ylabel(f"surface [mm] (profiles.h5 S1net in {units['S1net_m']})")
    ax[0, 0].set_title("hole profile")
    ax[0, 0].legend(fontsize=7)
    tc = c["t_s"] * 1e6
    ax[0, 1].plot(tc, c["T_K"], color="tab:red")
    ax[0, 1].set_xlabel("t [us]")
    ax[0, 1].set_ylabel("centre surface temperature [K]")
    ax2 = ax[0, 1].twinx()
    ax2.plot(tc, c["p_Pa"] / 1e6, color="tab:blue")
    ax2.set_ylabel("centre pressure [MPa]", color="tab:blue")
    ax[0, 1].set_title("centre temperature (red) and pressure (blue)")
    # removal rate from the frames: d(volume)/dt, volume = sum of depth x ring area
    dxi = p["xi"][1] - p["xi"][0]
    area = np.where(p["xi"] == 0, np.pi * 0.25 * dxi ** 2, 2 * np.pi * p["xi"] * dxi) * R * R
    vol = p["S1net_m"] @ area
    if len(t) > 1:
        ax[1, 0].plot(0.5 * (t[1:] + t[:-1]) * 1e6, np.diff(vol) / np.diff(t) * 1e9)
    ax[1, 0].set_xlabel("t [us]")
    ax[1, 0].set_ylabel("removal rate [mm3/s]")
    ax[1, 0].set_title("removal rate")
    ax[1, 1].plot(tc, c["depth_m"] * 1e3)
    ax[1, 1].set_xlabel("t [us]")
    ax[1, 1].set_ylabel("centre depth [mm]")
    ec = s.get("energy_check", {})
    ts = s.get("time_step", {})
    ax[1, 1].set_title(f"status {s['status']}; v/(q/rho H) = {ec.get('centre_velocity_over_bound', float('nan')):.3f};"
                       f" est. error {ts.get('depth_error_estimate', float('nan')):.1e}", fontsize=9)
    c_ = s["case"]
    fig.suptitle(f"laser_drill: I0 {c_['intensity_W_per_m2']:.3g} W/m2, pulse {c_['pulse_s']:.3g} s, "
                 f"R {R:.3g} m, {c_['model']}, melt energy {c_.get('melt_energy', '?')}")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"laser_plot: wrote {out}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", help="output folder of one laser_drill run")
    ap.add_argument("--out", help="PNG file (default RUN/run.png)")
    a = ap.parse_args()
    plot(a.run, a.out or str(pathlib.Path(a.run) / "run.png"))


if __name__ == "__main__":
    main()
