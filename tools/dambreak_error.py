#!/usr/bin/env python3
"""Error of a dam-break run (front.csv) against Martin & Moyce (1952).

The error is the RMS over the measured times T_k of the surge-front position
error, in units of the column width a:  sqrt(mean_k (Z_sim(T_k) - Z_exp(T_k))^2),
with Z_sim linearly interpolated in time. The same for the wall height H.
Usage: tools/python tools/dambreak_error.py front.csv [--width 4] [--g 9.81] [--tmax 3]
"""
import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from mpm_io import read_csv  # noqa: E402,F401  (also used as dambreak_error.read_csv by bench.py)
DATA = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "data"))


def find_data(name):
    for d in (os.environ.get("MPM_SHARED_DATA", ""), os.path.join(HERE, "..", "inputs", "dambreak"), DATA,
              os.path.join(HERE, "..", "shared", "data")):
        p = os.path.join(d, name)
        if d and os.path.exists(p):
            return p
    raise FileNotFoundError(name + " (set MPM_SHARED_DATA to the folder with the reference data)")


def input_defaults(path):
    """'variable NAME index VALUE' lines of a LIGGGHTS input, as a dict of strings ({} if missing)."""
    import re
    out = {}
    if os.path.exists(path):
        with open(path) as f:
            for ln in f:
                m = re.match(r"\s*variable\s+(\w+)\s+index\s+(\S+)", ln)
                if m:
                    out[m.group(1)] = m.group(2)
    return out


def load_reference():
    return (read_csv(find_data("martin_moyce_1952_square_front.csv")),
            read_csv(find_data("martin_moyce_1952_square_height.csv")))


def errors(csv, width=4.0, g=9.81, tmax=None):
    """Returns (rms front error, rms height error, number of front points compared) in units of a."""
    sim = read_csv(csv)
    T = sim["t"] * np.sqrt(g / width)
    Z = sim["x_front"] / width
    H = sim["h_wall"] / width
    front, height = load_reference()
    res = []
    for ref, col, val in ((front, "Z", Z), (height, "H", H)):
        Tr = ref["T"]
        keep = (Tr >= T.min()) & (Tr <= T.max())
        if tmax is not None:
            keep &= Tr <= tmax
        if not np.any(keep):
            res.append((float("nan"), 0))
            continue
        d = np.interp(Tr[keep], T, val) - ref[col][keep]
        res.append((float(np.sqrt(np.mean(d * d))), int(keep.sum())))
    return res[0][0], res[1][0], res[0][1]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--width", type=float, default=4.0)
    ap.add_argument("--g", type=float, default=9.81)
    ap.add_argument("--tmax", type=float, default=None, help="compare only up to this T")
    a = ap.parse_args()
    ef, eh, n = errors(a.csv, a.width, a.g, a.tmax)
    print(f"front_rms_error_a={ef:.4f} height_rms_error_a={eh:.4f} front_points={n}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
