#!/usr/bin/env python3
"""mpm_case.install: `cmake --install BUILD --prefix P` into a temporary prefix gives working programs.

Checks, all on the installed copy: P/bin/liggghts_mpm -version prints this project's version and
LIGGGHTS' and exits 0 without writing a log file; -h lists the fix styles mpm/fluid and
balance/mpm; P/bin/laser_drill --help runs (if laser_drill is built); the docs, LICENSE and
CHANGELOG are in P/share/doc/liggghts_mpm and the example inputs in P/share/liggghts_mpm/inputs; the
installed binary runs the installed hydrostatic example (4 cells).
  test_install.py --cmake CMAKE --build BUILD_DIR --version X.Y.Z [--laser]
"""
import argparse
import os
import subprocess
import sys
import tempfile


def run(cmd, cwd):
    p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
    return p.returncode, p.stdout


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cmake", required=True)
    ap.add_argument("--build", required=True)
    ap.add_argument("--version", required=True)
    ap.add_argument("--laser", action="store_true", help="laser_drill is built: check it too")
    a = ap.parse_args()
    fails = []

    def check(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            fails.append(what)

    with tempfile.TemporaryDirectory(prefix="mpm_install_") as tmp:
        prefix = os.path.join(tmp, "prefix")
        work = os.path.join(tmp, "work")
        os.makedirs(work)
        rc, out = run([a.cmake, "--install", a.build, "--prefix", prefix], cwd=tmp)
        check(rc == 0, "cmake --install exits 0")
        if rc != 0:
            print(out)
            return 1
        exe = os.path.join(prefix, "bin", "liggghts_mpm")
        rc, out = run([exe, "-version"], cwd=work)
        print(out.rstrip())
        check(rc == 0, "liggghts_mpm -version exits 0")
        check(out.startswith("liggghts_mpm %s\n" % a.version), "-version prints 'liggghts_mpm %s'" % a.version)
        check("LIGGGHTS (Version LIGGGHTS-PUBLIC" in out, "-version prints LIGGGHTS' version string")
        rc2, out2 = run([exe, "--version"], cwd=work)
        check(rc2 == 0 and out2 == out, "--version prints the same")
        check(not os.listdir(work), "-version writes no file (found: %s)" % os.listdir(work))
        rc, out = run([exe, "-h"], cwd=work)
        styles = out[out.find("* Fix styles added by liggghts_mpm"):] if "* Fix styles added by liggghts_mpm" in out else ""
        check(rc == 0, "liggghts_mpm -h exits 0")
        check("Command line options" in out and "* Fix styles" in out, "-h prints LIGGGHTS' help")
        check("mpm/fluid" in styles.split() and "balance/mpm" in styles.split(),
              "-h lists mpm/fluid and balance/mpm among our fix styles")
        if a.laser:
            rc, out = run([os.path.join(prefix, "bin", "laser_drill"), "--help"], cwd=work)
            check(rc == 0 and "laser_drill" in out, "laser_drill --help exits 0")
        doc = os.path.join(prefix, "share", "doc", "liggghts_mpm")
        for f in ("index.md", "fix_mpm_fluid.md", "fix_balance_mpm.md", "README.md", "LICENSE", "CHANGELOG.md"):
            check(os.path.isfile(os.path.join(doc, f)), "share/doc/liggghts_mpm/" + f)
        check(os.path.isdir(os.path.join(doc, "img")), "share/doc/liggghts_mpm/img/")
        inp = os.path.join(prefix, "share", "liggghts_mpm", "inputs")
        hydro = os.path.join(inp, "hydrostatic", "in.hydrostatic")
        check(os.path.isfile(hydro), "share/liggghts_mpm/inputs/hydrostatic/in.hydrostatic")
        if os.path.isfile(hydro):
            rc, out = run([exe, "-in", hydro, "-var", "cells", "4", "-log", "none"], cwd=work)
            check(rc == 0 and "Loop time of" in out and "ERROR" not in out,
                  "installed liggghts_mpm runs the installed hydrostatic example")
            if rc != 0:
                print(out[-2000:])
    print("%d check(s) failed" % len(fails) if fails else "all checks passed")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
