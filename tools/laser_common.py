"""Helpers shared by the laser_*.py tools: locate and run laser_drill."""
import glob
import json
import os
import resource
import shutil
import subprocess
import sys

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def find_exe(exe=None):
    """--exe if given; else build*/laser_drill of this repository (newest first), then PATH."""
    if exe:
        candidates = [exe]
    else:
        builds = sorted(glob.glob(os.path.join(TOP, "build*", "laser_drill")), key=os.path.getmtime, reverse=True)
        candidates = builds + [shutil.which("laser_drill")]
    for c in candidates:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return c
    sys.exit("laser_drill not found (tried %s); build it or pass --exe"
             % (", ".join(c for c in candidates if c) or os.path.join(TOP, "build*", "laser_drill") + ", PATH"))


def run_case(exe, out, args, quiet=True):
    """Runs laser_drill into directory out; returns (exit code, summary dict or None, stderr).
    The summary gains cpu_time_s, the process's user + system CPU time: on the shared
    machine it varies much less with the load than wall_time_s."""
    # --overwrite: the tools re-run cases into their own folders
    cmd = [exe, "--out", out, "--overwrite"] + [str(a) for a in args] + (["--quiet"] if quiet else [])
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(cmd, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    summary = None
    path = os.path.join(out, "summary.json")
    # exit 0 (finished) and 3 (diverged) both write summary.json
    if p.returncode in (0, 3) and os.path.exists(path):
        with open(path) as f:
            summary = json.load(f)
        summary["cpu_time_s"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return p.returncode, summary, p.stderr.strip()
