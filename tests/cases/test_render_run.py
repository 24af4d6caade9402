#!/usr/bin/env python3
"""tools/render_run.py on a small fluid run, and the HDF5 root attributes of fix mpm/fluid's output.

    test_render_run.py --exe build/liggghts_mpm --work DIR

A 1 m box with water in the corner block [0, 0.3] x [0, 1] x [0, 0.2] writes an HDF5 series. Checks:
the root attributes 'time' and 'step' are scalars (int(f.attrs["step"]) works with numpy 2); a file
with the former 1-element arrays is still read by tools/mpm_io.py; render_run.py fits its axes to
the water (not the 1 m box), draws only the points of a --slab, takes --zoom as its axes and refuses
a reversed --slab or --zoom. Runs the tools in tools/python (the project's environment).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.path.join(HERE, "..", "..", "tools")
sys.path.insert(0, HERE)
import cases  # noqa: E402
from cases import check  # noqa: E402

SCRIPT = """atom_style sphere
atom_modify map array sort 0 0
boundary f f f
units si
region box block 0 1 0 1 0 1 units box
create_box 1 box
neighbor 0.02 bin
neigh_modify delay 0 every 1 check yes binsize 0.1
region water block 0 0.3 0 1 0 0.2 units box
fix fluid all mpm/fluid cell 0.1 density 1000 boundary all freeslip fill water 2 2 2 type 1 &
    hydrostatic z 0.2 9.81 output 5 water points p v
fix grav all gravity 9.81 vector 0 0 -1
timestep 1e-3
run 10
"""

AXES = re.compile(r"axes (\w) \[([-0-9.e+]+), ([-0-9.e+]+)\] (\w) \[([-0-9.e+]+), ([-0-9.e+]+)\]")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--exe", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--inputs", default=None)
    ap.add_argument("--mpirun", default="mpirun")
    a = ap.parse_args()
    r = cases.Runner(a)
    d = r.fresh("render_run")
    with open(os.path.join(d, "in.render"), "w") as f:
        f.write(SCRIPT)
    r.execute(d, "in.render")
    py = os.path.join(TOOLS, "python")

    def tool(*args):
        q = subprocess.run([py] + list(args), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
        return q.returncode, q.stdout

    # scalar attributes, and the old 1-element arrays still read
    old = os.path.join(d, "old")
    os.makedirs(old)
    code = ("import sys, glob, h5py, numpy as np\n"
            "sys.path.insert(0, %r)\n"
            "import mpm_io\n"
            "fs = sorted(glob.glob(%r))\n"
            "with h5py.File(fs[-1], 'r') as f:\n"
            "    print('shapes', f.attrs['time'].shape, f.attrs['step'].shape, 'step', int(f.attrs['step']), "
            "'time', float(f.attrs['time']))\n"
            "import shutil\n"
            "dst = %r + '/water_000000010.h5'\n"
            "shutil.copy(fs[-1], dst)\n"
            "with h5py.File(dst, 'r+') as f:\n"
            "    t, s = float(f.attrs['time']), int(f.attrs['step'])\n"
            "    del f.attrs['time']; del f.attrs['step']\n"
            "    f.attrs['time'] = np.array([t]); f.attrs['step'] = np.array([s], dtype=np.int64)\n"
            "    print('old shapes', f.attrs['time'].shape, f.attrs['step'].shape)\n"
            "xyz, vals, at = mpm_io.read_points(dst, ['p'])\n"
            "ser = mpm_io.h5_series(%r, 'water')\n"
            "print('old read', len(xyz), int(at['step']), float(at['time']), len(ser), ser[0][0])\n"
            ) % (os.path.abspath(TOOLS), os.path.join(d, "water_*.h5"), old, old)
    rc, out = tool("-c", code)
    print(out.strip())
    check(rc == 0 and "shapes () () step 10" in out, "time and step are scalar attributes (int(f.attrs['step']) = 10)")
    check(rc == 0 and "old shapes (1,) (1,)" in out and "old read 480 10 0.01 1 0.01" in out,
          "a file with 1-element time and step attributes is still read (mpm_io.read_points, h5_series)")

    def axes(out):
        m = AXES.search(out)
        return (m.group(1), float(m.group(2)), float(m.group(3)), m.group(4), float(m.group(5)),
                float(m.group(6))) if m else None

    png = os.path.join(d, "r.png")
    rc, out = tool(os.path.join(TOOLS, "render_run.py"), d, "--prefix", "water", "--out", png)
    print(out.strip())
    ax = axes(out)
    # the water: x in [0.025, 0.275], z in [0.025, 0.175] (point centres); the box is 1 m
    check(rc == 0 and ax is not None and ax[0] == "x" and -0.02 < ax[1] < 0.025 and 0.275 < ax[2] < 0.3
          and ax[3] == "z" and -0.02 < ax[4] < 0.025 and 0.175 < ax[5] < 0.2,
          f"axes fitted to the water, not the 1 m box (got {ax})")
    check(rc == 0 and "480 points" in out, "all 480 points drawn")
    rc, out = tool(os.path.join(TOOLS, "render_run.py"), d, "--prefix", "water", "--out", png, "--slab", "0", "0.5")
    print(out.strip())
    check(rc == 0 and "240 points" in out, "--slab 0 0.5 draws the 240 points of y < 0.5")
    rc, out = tool(os.path.join(TOOLS, "render_run.py"), d, "--prefix", "water", "--out", png, "--zoom", "0.1", "0.2",
                   "0", "0.05")
    print(out.strip())
    check(rc == 0 and axes(out) == ("x", 0.1, 0.2, "z", 0.0, 0.05), "--zoom sets the axes")
    rc, out = tool(os.path.join(TOOLS, "render_run.py"), d, "--out", png, "--slab", "0.5", "0.1")
    check(rc != 0 and "--slab expects LO < HI (m), got 0.5 0.1" in out, f"a reversed --slab is refused ({out.strip()[-80:]})")
    rc, out = tool(os.path.join(TOOLS, "render_run.py"), d, "--out", png, "--zoom", "0", "1", "1", "0")
    check(rc != 0 and "--zoom expects H0 < H1 and V0 < V1" in out, "a reversed --zoom is refused")
    shutil.rmtree(old, ignore_errors=True)
    return cases.exit_status()


if __name__ == "__main__":
    sys.exit(main())
