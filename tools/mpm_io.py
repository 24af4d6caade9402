"""Readers of the files liggghts_mpm runs write, shared by every tool in tools/.

  read_csv(path, keep_last_of=None)   CSV with '#' comment lines and one header line
  read_key_values(path, ...)          'key = value' files (tank_run.txt, jar_run.txt)
  read_dump(path), read_dump_frames   LIGGGHTS 'dump custom' text files
  dump_series(rundir)                 the dumps of a folder, by file name and step
  read_points(path, fields)           one HDF5 file of fix mpm/fluid's output (points)
  h5_series(rundir, prefix)           the HDF5 files of one output prefix, by time
  xmf_series(rundir)                  the fix's XDMF indexes (prefix.xmf) of a folder, with their steps
  paired_frames(rundir, prefix)       steps that have both an HDF5 file and a bead dump
  write_rows(path, rows)              a list of dicts as CSV (columns: every key, in order of first use)

The HDF5 layout (liggghts_mpm/mpm/hdf5_series.cpp, docs/fix_mpm_fluid.md 'Output'):
prefix_<step, 9 digits>.h5 with root attributes 'time' and 'step', /points/xyz (n, 3) and one data
set per point field (/points/v (n, 3), /points/p (n), ...); prefix.xmf lists the steps as comment
blocks '<!-- mpm-step step="S" time="T" file="F" -->' (a restarted run drops the later ones).
"""
import csv
import glob
import html
import os
import re

import numpy as np

WATER = "#8ecae6"   # light blue: material points in the snapshot tools
BEADS = "#08306b"   # dark blue: grains


def read_csv(path, keep_last_of=None):
    """{column: array} of a CSV with '#' comment lines and one header line; rows whose number of
    fields differs from the header (a line being written) are skipped. keep_last_of = a column
    name: one row per value of that column, the last one written (a resumed run writes the rows
    after its restart step again), in increasing order of the column."""
    with open(path) as f:
        rows = [ln.strip() for ln in f if ln.strip() and not ln.lstrip().startswith("#")]
    names = rows[0].split(",")
    data = {n: [] for n in names}
    for r in rows[1:]:
        vals = r.split(",")
        if len(vals) != len(names):
            continue
        for n, v in zip(names, vals):
            data[n].append(float(v))
    out = {n: np.array(v) for n, v in data.items()}
    if keep_last_of is None:
        return out
    t = out[keep_last_of]
    _, idx = np.unique(t[::-1], return_index=True)
    keep = np.sort(len(t) - 1 - idx)
    return {n: v[keep] for n, v in out.items()}


def read_key_values(path, numbers=False, missing_ok=False):
    """{key: value} of the 'key = value' lines of a file. numbers: values that parse as floats are
    floats (others stay strings). missing_ok: a missing file gives {} instead of an error."""
    if missing_ok and not os.path.exists(path):
        return {}
    info = {}
    with open(path) as f:
        for line in f:
            if "=" in line:
                k, v = (s.strip() for s in line.split("=", 1))
                if numbers:
                    try:
                        v = float(v)
                    except ValueError:
                        pass
                info[k] = v
    return info


def read_dump_frames(path, box=False):
    """Every frame of a LIGGGHTS/LAMMPS 'dump custom' text file: a list of (timestep, {column:
    array}), or with box=True of (timestep, {column: array}, [[xlo, xhi], [ylo, yhi], [zlo, zhi]]);
    an empty frame has empty columns."""
    with open(path) as f:
        lines = f.read().splitlines()
    frames = []
    i = 0
    while True:
        try:
            i = lines.index("ITEM: TIMESTEP", i)
        except ValueError:
            break
        step = int(lines[i + 1])
        k = lines.index("ITEM: NUMBER OF ATOMS", i)
        n = int(lines[k + 1])
        j = next(m for m in range(k, len(lines)) if lines[m].startswith("ITEM: ATOMS"))
        names = lines[j].split()[2:]
        if n == 0:
            cols = {c: np.zeros(0) for c in names}
        else:
            data = np.loadtxt(lines[j + 1:j + 1 + n], ndmin=2)
            cols = {c: data[:, m] for m, c in enumerate(names)}
        if box:  # 'ITEM: BOX BOUNDS ...' follows the atom count, then one line 'lo hi' per axis
            bounds = None
            if lines[k + 2].startswith("ITEM: BOX BOUNDS"):
                bounds = [[float(v) for v in lines[k + 3 + m].split()[:2]] for m in range(3)]
            frames.append((step, cols, bounds))
        else:
            frames.append((step, cols))
        i = j + 1 + n
    return frames


def read_dump(path):
    """The first (usually only) frame of a 'dump custom' file as {column: array}."""
    frames = read_dump_frames(path)
    if not frames:
        raise ValueError("%s: no 'ITEM: TIMESTEP' frame (not a LIGGGHTS dump?)" % path)
    return frames[0][1]


def dump_series(rundir, name=None):
    """{name: {step: path}} of the one-frame-per-file dumps NAME_<step>.dump (or NAME<step>.dump)
    in rundir ('dump ... NAME_*.dump'); name: only that one."""
    out = {}
    for p in glob.glob(os.path.join(rundir, "*.dump")):
        m = re.match(r"(.*?)_?(\d+)\.dump$", os.path.basename(p))
        if m and (name is None or m.group(1) == name):
            out.setdefault(m.group(1), {})[int(m.group(2))] = p
    return out


def read_points(path, fields=()):
    """(xyz (n, 3), {field: array}, attrs {'time', 'step'}) of one HDF5 file of the fix."""
    import h5py
    with h5py.File(path, "r") as f:
        xyz = f["points/xyz"][()]
        vals = {k: f["points/" + k][()] for k in fields}
        attrs = {k: np.ravel(f.attrs[k])[0] for k in ("time", "step") if k in f.attrs}
    return xyz, vals, attrs


def h5_series(rundir, prefix):
    """[(time, path)] of the files prefix_*.h5 in rundir that open and have a 'time' attribute,
    ordered by time."""
    import h5py
    out = []
    for p in sorted(glob.glob(os.path.join(rundir, prefix + "_*.h5"))):
        try:
            with h5py.File(p, "r") as f:
                t = float(np.ravel(f.attrs["time"])[0])
        except (OSError, KeyError):
            continue
        out.append((t, p))
    out.sort()
    return out


_XMF_STEP = re.compile(r'<!-- mpm-step step="(-?\d+)" time="([^"]+)" file="([^"]+)" -->')


def xmf_series(rundir):
    """{prefix: [(step, time, h5 path)]} of the fix's XDMF indexes (prefix.xmf written by
    mpm::Hdf5Series) in rundir, each list in the order of the index (increasing step); entries
    whose file is missing are left out."""
    out = {}
    for x in sorted(glob.glob(os.path.join(rundir, "*.xmf"))):
        with open(x) as f:
            text = f.read()
        if "written by mpm::Hdf5Series" not in text:
            continue
        rows = []
        for m in _XMF_STEP.finditer(text):
            p = os.path.join(os.path.dirname(x), html.unescape(m.group(3)))
            if os.path.exists(p):
                rows.append((int(m.group(1)), float(m.group(2)), p))
        out[os.path.basename(x)[:-4]] = rows
    return out


def paired_frames(rundir, prefix, dump_name="beads"):
    """{step: (h5 path, dump path)} for every step that has both prefix_<step>.h5 and
    <dump_name>_<step>.dump in rundir."""
    out = {}
    for p in glob.glob(os.path.join(rundir, prefix + "_*.h5")):
        m = re.search(r"_(\d+)\.h5$", p)
        if m:
            out.setdefault(int(m.group(1)), [None, None])[0] = p
    for p in glob.glob(os.path.join(rundir, dump_name + "_*.dump")):
        m = re.search(dump_name + r"_(\d+)\.dump$", p)
        if m:
            out.setdefault(int(m.group(1)), [None, None])[1] = p
    return {s: tuple(v) for s, v in out.items() if v[0] and v[1]}


def write_rows(path, rows):
    """rows (dicts) as a CSV file whose columns are every key of any row, in the order of first use;
    a row without a key leaves its cell empty."""
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
