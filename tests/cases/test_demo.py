#!/usr/bin/env python3
"""mpm_case.demo_quick: tools/demo.sh on the starter scene's reduced size (--quick, a few seconds).

    test_demo.py --exe build/liggghts_mpm --work DIR

Checks: demo.sh --quick --exe EXE ends with status 0 and prints its three checks of the run (fluid
mass constant in every thermo line, the largest point pressure as a fraction of rho g h + rho U^2
below 5, the front from the gate to the end) with the values it read from the log, and writes a PNG
picture with four frames of the 36 material points and the beads; the printed mass and pressure
match the thermo lines of log.liggghts. A run that stops with an error gives status 1 and the log's
ERROR line on stderr. demo.sh draws through tools/python: where that cannot provide numpy,
matplotlib and h5py (no network to create .venv), the test is skipped (status 77) with a message.
"""
import argparse
import os
import re
import shutil
import stat
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
import cases  # noqa: E402
from cases import check  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--exe", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    py = os.path.join(TOP, "tools", "python")
    env = subprocess.run([py, "-c", "import numpy, matplotlib, h5py"], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, timeout=900)
    if env.returncode != 0:
        print("SKIP  tools/python could not provide numpy, matplotlib and h5py (creating .venv needs "
              "PyPI):\n" + env.stdout[-600:])
        return 77
    work = os.path.join(os.path.abspath(a.work), "demo_quick")
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    png = os.path.join(work, "starter-demo-quick.png")
    demo = os.path.join(TOP, "tools", "demo.sh")
    p = subprocess.run(["bash", demo, "--quick", "--exe", os.path.abspath(a.exe), "--work", os.path.join(work, "run"),
                        "--out", png], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
    print(p.stdout)
    check(p.returncode == 0, f"demo.sh --quick ends with status 0 (got {p.returncode})")
    m = re.search(r"fluid mass (\S+) kg in all (\d+) lines: constant", p.stdout)
    check(m is not None, "demo.sh reports the fluid mass constant in every thermo line")
    q = re.search(r"largest point pressure (\S+) Pa = (\S+) of rho g h \+ rho U\^2", p.stdout)
    check(q is not None and 0 < float(q.group(2)) < 5, "demo.sh reports the largest pressure below 5 (rho g h + rho U^2)")
    f = re.search(r"water front x = (\S+) m at the release -> (\S+) m at the end", p.stdout)
    check(f is not None and float(f.group(2)) > float(f.group(1)), "demo.sh reports the front moving after the release")
    # the values it printed against the thermo lines themselves
    log = open(os.path.join(work, "run", "log.liggghts")).read() if os.path.exists(os.path.join(work, "run", "log.liggghts")) else ""
    rows, hdr = [], None
    for ln in log.splitlines():
        w = ln.split()
        if w[:2] == ["Step", "Time"]:
            hdr = w if "fluid[1]" in w else None
        elif hdr and len(w) == len(hdr) and w[0].isdigit():
            rows.append(dict(zip(hdr, map(float, w))))
        elif ln.startswith("Loop time"):
            hdr = None
    if m and q and rows:
        check(all(r["fluid[1]"] == float(m.group(1)) for r in rows) and int(m.group(2)) == len(rows),
              f"the printed mass {m.group(1)} kg is the one of all {len(rows)} thermo lines")
        pmax = max(r["fluid[10"] for r in rows)
        check(abs(pmax - float(q.group(1))) <= 1e-3 * pmax, f"the printed largest pressure {q.group(1)} Pa is the log's ({pmax:.6g})")
    else:
        check(False, "log.liggghts has the thermo lines of fix mpm/fluid")
    w = re.search(r"water: (\d+) points, (\d+) grains at the last time drawn; t = ([0-9., ]+) s", p.stdout)
    check(w is not None and w.group(1) == "36" and int(w.group(2)) == 300 and len(w.group(3).split(",")) == 4,
          "the picture draws four frames of the 36 points and the 300 beads")
    ok_png = os.path.exists(png) and open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n" and os.path.getsize(png) > 20000
    check(ok_png, f"{png} is a PNG picture")

    # a run that stops with an error: status 1 and the log's ERROR line
    fake = os.path.join(work, "failing_exe")
    with open(fake, "w") as fh:
        fh.write("#!/bin/sh\necho 'ERROR: Illegal fix mpm/fluid command: test message' > log.liggghts\nexit 1\n")
    os.chmod(fake, os.stat(fake).st_mode | stat.S_IEXEC)
    e = subprocess.run(["bash", demo, "--exe", fake, "--work", os.path.join(work, "fail"), "--out", png + ".fail.png"],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=60)
    check(e.returncode == 1 and "ERROR: Illegal fix mpm/fluid command: test message" in e.stderr,
          f"a failed run: status 1 and the log's ERROR line (status {e.returncode}, stderr {e.stderr.strip()[:120]!r})")
    print(f"demo_quick: {len(cases.FAILURES)} failed check(s)")
    return 1 if cases.FAILURES else 0


if __name__ == "__main__":
    sys.exit(main())
