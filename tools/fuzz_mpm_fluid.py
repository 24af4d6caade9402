#!/usr/bin/env python3
"""Fuzz driver for the arguments of fix mpm/fluid and fix balance/mpm (standard library only).

For every keyword of the keyword table of docs/fix_mpm_fluid.md (and the keywords of fix
balance/mpm) it writes small input scripts with bad values in each argument position (0,
negative, nan, inf, 1e308, 1e-308, 1e400, huge integers, words, a missing argument), repeated
keywords, conflicting keyword pairs, and the same through fix_modify, runs liggghts_mpm on each and
classifies the outcome:

  named    an ERROR line that names the keyword (the wanted outcome of a bad value)
  unnamed  an ERROR line that does not name it
  crash    a non-zero exit without an ERROR line, or a signal
  hang     no exit within the time limit
  silent   exit 0: the bad value was accepted

Values inside the documented range at its extremes (1e308 where "> 0", the tiniest normal number,
the largest int) are 'extremes': they must run (exit 0) or stop with an error naming the keyword;
a crash, hang or an error that does not name it counts against them.

    tools/python tools/fuzz_mpm_fluid.py --exe build/liggghts_mpm --work /tmp/fuzz [--quick] [-j 2]

--quick runs a fixed sample (every keyword, fewer values; the CTest case
mpm_case.reliability_fuzz_quick). The last line is the summary that the test reads:
"fuzz: cases N named A unnamed B crashes C hangs D silent E". The cases that are not 'named'
are listed before it.
"""
import argparse
import concurrent.futures
import os
import re
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
DOC = os.path.join(HERE, "..", "docs", "fix_mpm_fluid.md")

FLUID = """atom_style sphere
atom_modify map array sort 0 0
boundary f f f
newton off
communicate single vel yes
units si
region box block 0 0.4 0 0.05 0 0.3 units box
create_box 2 box
neighbor 0.005 bin
neigh_modify delay 0 every 1 check yes
region col block 0 0.1 0 0.05 0 0.2 units box
create_atoms 2 single 0.2 0.025 0.1 units box
set type 2 diameter 0.004 density 2500
group grains type 2
{pre}
fix fluid all mpm/fluid {args}
{post}
fix grav all gravity 9.81 vector 0 0 -1
timestep 2e-4
run 3
"""
# the fix group: the points only (type 1); grains (type 2) in group 'grains'
FLUID = FLUID.replace("fix fluid all mpm/fluid", "group water type 1\nfix fluid water mpm/fluid")

BASE = "cell 0.025 density 1000 pressure eos bulk 2e5 viscosity 1e-3 boundary all freeslip fill col 2 2 2 type 1"
BASE_PROJ = "cell 0.025 density 1000 viscosity 1e-3 pressure projection boundary all freeslip fill col 2 2 2 type 1"
COUPLED = " couple grains"
NVE = "fix nve grains nve/sphere"

# Argument slots: ('real', lo, hi, open_lo, open_hi) | ('int', lo, hi) | ('words', [valid]) | ('free', example)
R = lambda lo, hi, ol=False, oh=False: ("real", lo, hi, ol, oh)  # noqa: E731
INF = float("inf")
AXIS = ("words", ["x", "y", "z"])
YESNO = ("words", ["yes", "no"])

# keyword -> (argument slots with a valid example each, context): context 'eos', 'proj', 'couple',
# 'couple_proj'. The ranges are those of the keyword table (docs/fix_mpm_fluid.md).
SPEC = {
    "cell": ([(R(0, INF, True, True), "0.025")], "eos"),
    "grid": ([(R(-INF, INF), v) for v in ("0", "0.4", "0", "0.05", "0", "0.3")], "eos"),
    "density": ([(R(0, INF, True, True), "1000")], "eos"),
    "bulk": ([(R(0, INF, True, True), "2e5")], "eos"),
    "viscosity": ([(R(0, INF, False, True), "1e-3")], "eos"),
    "eos": ([(("words", ["tait"]), "tait"), (R(1, INF, False, True), "7")], "eos"),
    "shape": ([(("words", ["linear", "bspline2"]), "linear")], "eos"),
    "transfer": ([(("words", ["flip"]), "flip"), (R(0, 1), "0.5")], "eos"),
    "update": ([(("words", ["musl", "usl"]), "usl")], "eos"),
    "model": ([(("words", ["standard", "yang2016"]), "yang2016")], "couple"),
    "boundary": ([(("words", ["xlo", "xhi", "ylo", "yhi", "zlo", "zhi", "all"]), "xlo"),
                  (("words", ["partial"]), "partial"), (R(0, 1), "0.5")], "eos"),
    "gate": ([(AXIS, "x"), (R(0.1, 0.4, False, True), "0.2"), (("words", ["lower", "upper"]), "lower"),
              (R(0, INF, False, True), "0.001")], "eos"),
    "damping": ([(R(0, INF, False, True), "1")], "eos"),
    "cfl": ([(R(0, 1, True, False), "0.4")], "eos"),
    "subcycle": ([(YESNO, "yes")], "eos"),
    "every": ([(("int", 1, 2 ** 31 - 1), "2")], "eos"),
    "mass_threshold": ([(R(0, 1, False, True), "1e-4")], "eos"),
    "sparse": ([(YESNO, "no")], "eos"),
    "pressure": ([(("words", ["eos", "projection"]), "eos")], "eos"),
    "tolerance": ([(R(0, INF, True, True), "1e-6")], "proj"),
    "max_iterations": ([(("int", 1, 1000000), "100")], "proj"),
    "volume_correction": ([(R(0, INF, False, True), "1")], "proj"),
    "pressure_output": ([(("words", ["multiplier", "acceleration"]), "acceleration")], "proj"),
    "grain_pressure": ([(("words", ["multiplier", "acceleration"]), "multiplier")], "couple_proj"),
    "pressure_average": ([(R(0, INF, False, True), "0.01")], "proj"),
    "fill": ([(("free", "col"), "col"), (("int", 1, 8), "2"), (("int", 1, 8), "2"), (("int", 1, 8), "2"),
              (("words", ["type"]), "type"), (("int", 1, 1), "1")], "fill"),
    "hydrostatic": ([(AXIS, "z"), (R(0, 0.3), "0.2"), (R(0, 1e3), "9.81")], "eos"),
    "pmin": ([(R(-INF, 0, False, False), "-1e4")], "eos"),
    "couple": ([(("words", ["grains"]), "grains")], "couple_bare"),
    "drag": ([(("words", ["ergun_wenyu", "difelice", "stokes"]), "stokes")], "couple"),
    "cell_check": ([(YESNO, "no")], "couple"),
    "theta_min": ([(R(0, 1, True, True), "0.4")], "couple"),
    "theta_smooth": ([(R(0, 0.4), "0.01")], "couple"),
    "front": ([(AXIS, "y")], "eos"),
    "height": ([(AXIS, "z"), (("words", ["x", "y"]), "x"), (R(0, 0.4), "0.1")], "eos"),
    "output": ([(("int", 0, 2 ** 31 - 1), "10"), (("free", "o"), "o"), (("words", ["points"]), "points"),
                (("words", ["v", "p", "rho"]), "v")], "eos"),
    "mesh_wall": ([(("free", "nosuch"), "nosuch"), (("words", ["freeslip"]), "freeslip")], "mesh"),
    "probe": ([(("words", ["point", "box"]), "point"), (R(0, 0.4), "0.1"), (R(0, 0.05), "0.02"), (R(0, 0.3), "0.1")],
              "eos"),
    "probe_window": ([(R(0, INF, False, True), "0.01")], "probe"),
    # the box is not periodic: every use is refused naming the keyword (the valid ones are tested by
    # mpm_case.flow_drive_*)
    "superficial_velocity": ([(AXIS, "z"), (R(-INF, INF, True, True), "0.01")], "eos"),
}

BAD_REAL = ["0", "-1", "nan", "inf", "-inf", "1e308", "-1e308", "1e-308", "1e400", "99999999999999999999",
            "0x10", "1,5", "abc", None]
BAD_INT = ["0", "-1", "1.5", "nan", "2147483648", "9223372036854775808", "99999999999999999999", "1e3", "abc", None]
BAD_WORD = ["maybe", "1", "YES", "\"x y\"", None]
# --quick: one bad value per argument, taken in turn from these lists (the keyword's and argument's
# positions pick it), so that the sample still sees every kind of value
QUICK_REAL = ["nan", "-1", "1e400", "inf", "abc", "1e-308", "0x10"]
QUICK_INT = ["2147483648", "-1", "1.5", "abc", "9223372036854775808"]
QUICK_WORD = ["maybe", "1", "YES"]
EXTREME_REAL = ["1e308", "2.2250738585072014e-308", "1e-300"]
EXTREME_INT = ["2147483647"]

# conflicting or inert combinations: (label, extra args, context, keyword the error must name)
CONFLICTS = [
    ("projection+bulk", "bulk 2e5", "proj", "bulk"),
    ("projection+pmin", "pmin -1", "proj", "pmin"),
    ("projection+eos", "eos tait 7", "proj", "eos"),
    ("projection+yang2016", "model yang2016", "proj", "model"),
    ("eos+tolerance", "tolerance 1e-6", "eos", "tolerance"),
    ("eos+max_iterations", "max_iterations 10", "eos", "max_iterations"),
    ("eos+volume_correction", "volume_correction 1", "eos", "volume_correction"),
    ("eos+pressure_average", "pressure_average 1", "eos", "pressure_average"),
    ("drag_without_couple", "drag stokes", "eos", "drag"),
    ("theta_smooth_without_couple", "theta_smooth 0.01", "eos", "theta_smooth"),
    ("theta_min_without_couple", "theta_min 0.5", "eos", "theta_min"),
    ("cell_check_without_couple", "cell_check no", "eos", "cell_check"),
    ("shear_without_viscosity", "boundary xlo shear 0.001", "eos_inviscid", "boundary"),
    ("couple_without_viscosity", "couple grains", "eos_inviscid", "couple"),
    ("gate_beyond_fluid", "gate x 0.01 lower never", "eos", "gate"),
    ("gate_at_face", "gate x 1e-300 lower never", "eos", "gate"),
    ("height_outside", "height z x -1", "eos", "height"),
    ("output_no_field", "output 10 o points", "eos", "output"),
]

# boundary FACE inflow U | outflow: the inflow's velocity, and the combinations refused
FLOW_U = R(0, INF, True, True)
FLOW_CONFLICTS = [
    ("inflow_all", "boundary all inflow 0.05", "proj"),
    ("outflow_eos", "boundary zhi outflow", "eos"),
    ("inflow_eos", "boundary zlo inflow 0.05", "eos"),
    ("outflow_mesh_wall", "boundary zhi outflow mesh_wall nosuch freeslip", "mesh_proj"),
]

BAL_SPEC = {
    "dim": [(AXIS, "x")],
    "every": [(("int", 0, 2 ** 31 - 1), "5")],
    "weight": [(("words", ["grains"]), "grains"), (R(0, INF, False, True), "2")],
    "volume": [(R(0, INF, False, True), "1")],
    "thresh": [(R(1, INF, False, True), "1.1")],
    "measured": [(YESNO, "no")],
}


def doc_keywords():
    """The keyword column of the Keywords table of docs/fix_mpm_fluid.md."""
    names, inside = [], False
    for line in open(DOC):
        if line.startswith("## "):
            inside = line.strip() == "## Keywords"
        if inside and line.startswith("| `"):
            names.append(line[3:line.index("`", 3)])
    return names


def fixargs(context):
    base = BASE_PROJ if "proj" in context else BASE
    if context == "eos_inviscid":
        base = base.replace("viscosity 1e-3 ", "")
    if context in ("couple", "couple_proj"):
        base += COUPLED
    if context == "probe":  # probe_window needs a probe
        base += " probe point 0.1 0.02 0.1"
    return base


def script(context, extra, post="", pre=""):
    base = fixargs(context)
    if context == "fill":
        base = base.replace(" fill col 2 2 2 type 1", "")
    if context in ("couple", "couple_proj", "couple_bare"):
        post = NVE + "\n" + post
    if context in ("mesh", "mesh_proj"):
        pre += "fix nosuch all property/global x scalar 1\n"
    return FLUID.format(pre=pre, args=base + " " + extra, post=post)


def in_range(slot, v):
    """True if word v is a valid value of the slot (so not a bad case)."""
    kind = slot[0]
    if v is None:
        return False
    if kind == "words":
        return v in slot[1]
    if kind == "free":
        return False
    if kind == "int":
        if not re.fullmatch(r"[+-]?\d+", v):
            return False
        return slot[1] <= int(v) <= slot[2]
    if not re.fullmatch(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?", v):
        return False
    x = float(v)
    if x != x or x in (INF, -INF) or (x != 0.0 and abs(x) < 2.2250738585072014e-308):
        return False
    _, lo, hi, ol, oh = slot
    return (x > lo if ol else x >= lo) and (x < hi if oh else x <= hi)


def values_for(slot, quick, turn=0):
    kind = slot[0]
    pick = lambda lst: [lst[turn % len(lst)]]  # noqa: E731
    if kind in ("real",):
        return (pick(QUICK_REAL) if quick else BAD_REAL), ([] if quick else EXTREME_REAL)
    if kind == "int":
        return (pick(QUICK_INT) if quick else BAD_INT), ([] if quick else EXTREME_INT)
    return (pick(QUICK_WORD) if quick else BAD_WORD), []


def cases(quick):
    """(name, script text, keyword the error must name, expected 'bad' or 'extreme')"""
    out = []
    table = doc_keywords()
    for ikw, kw in enumerate(table):
        if kw not in SPEC:
            out.append((f"{kw}/unspecified", None, kw, "bad"))  # the driver lacks a row: reported
            continue
        slots, ctx = SPEC[kw]
        example = [ex for _, ex in slots]
        for pos, (slot, _) in enumerate(slots):
            if slot[0] == "free" and kw != "mesh_wall":
                continue
            bad, extreme = values_for(slot, quick, ikw + pos)
            for group, vals in (("bad", bad), ("extreme", extreme)):
                if group == "bad" and (not quick or (pos == 0 and ikw % 4 == 0)) and (kw, pos) not in OPTIONAL:
                    vals = vals + [None] if None not in vals else vals
                for v in vals:
                    if v is None and (kw, pos) in OPTIONAL:
                        continue
                    if group == "bad" and in_range(slot, v):
                        continue
                    if group == "extreme" and not in_range(slot, v):
                        continue
                    words = example[:pos] + ([v] if v is not None else [])
                    if v is not None:
                        words += example[pos + 1:]
                    extra = kw + (" " + " ".join(words) if words else "")
                    if v is None and kw == "fill":
                        extra = "fill col 2 2 2 type 1".split()[:pos + 1]
                        extra = " ".join(extra)
                    label = f"{kw}/{pos}/{v if v is not None else 'missing'}"
                    out.append((label, script(ctx, extra), kw, group))
                    # the same through fix_modify for the keywords it changes
                    if v is not None and kw in MODIFIABLE and group == "bad" and (not quick or (pos == 0 and ikw % 4 == 0)):
                        mod = "fix_modify fluid " + kw + " " + " ".join(example[:pos] + [v] + example[pos + 1:])
                        if kw == "gate":
                            mod = "fix_modify fluid gate " + v
                        out.append(("fix_modify/" + label, script(ctx, "", post=mod), kw, "bad"))
        # repeated keyword (boundary, mesh_wall and probe may repeat: one face, mesh or probe each)
        if kw not in ("boundary", "mesh_wall", "probe", "fill", "couple", "pressure") and (not quick or kw in ("cfl", "gate", "drag")):
            one = kw + " " + " ".join(example)
            out.append((f"{kw}/repeated", script(ctx, one + " " + one), kw, "repeat"))
    for kw in ("tolerance", "cell", "pressure", "mesh_wall", "couple", "density", "colour"):
        out.append((f"fix_modify/{kw}/not_modifiable", script("eos", "", post=f"fix_modify fluid {kw} 1"), kw, "bad"))
    for label, extra, ctx, kw in (CONFLICTS if not quick else CONFLICTS[::4]):
        out.append((f"conflict/{label}", script(ctx, extra), kw, "bad"))
    # boundary FACE inflow U (the row above varies the face and the partial kind): U, a real > 0
    # (BAD_REAL ends with the missing value already; QUICK_REAL has none)
    for v in (BAD_REAL if not quick else QUICK_REAL[:3] + [None]):
        if in_range(FLOW_U, v):
            continue
        extra = "boundary zlo inflow" + (" " + v if v is not None else "")
        out.append((f"boundary/inflow/{v if v is not None else 'missing'}", script("proj", extra), "boundary", "bad"))
    for label, extra, ctx in (FLOW_CONFLICTS if not quick else FLOW_CONFLICTS[::2]):
        out.append((f"conflict/{label}", script(ctx, extra), "boundary", "bad"))
    # fix balance/mpm
    for ikw, (kw, slots) in enumerate(BAL_SPEC.items()):
        example = [ex for _, ex in slots]
        for pos, (slot, _) in enumerate(slots):
            if quick and pos > 0:
                continue
            bad, extreme = values_for(slot, quick, ikw + pos)
            if (not quick or (pos == 0 and ikw % 2 == 0)) and None not in bad:
                bad = bad + [None]
            for group, vals in (("bad", bad), ("extreme", extreme)):
                for v in vals:
                    if (group == "bad") == in_range(slot, v):
                        continue
                    words = example[:pos] + ([v] if v is not None else []) + (example[pos + 1:] if v is not None else [])
                    bal = "fix bal all balance/mpm " + ("" if kw == "dim" else "dim x ") + kw + " " + " ".join(words)
                    out.append((f"balance/{kw}/{pos}/{v if v is not None else 'missing'}",
                                script("eos", "", pre=bal), kw, group))
        if kw != "weight":
            one = kw + " " + " ".join(example)
            bal = "fix bal all balance/mpm " + ("" if kw == "dim" else "dim x ") + one + " " + one
            out.append((f"balance/{kw}/repeated", script("eos", "", pre=bal), kw, "repeat"))
        if quick and ikw % 2:
            continue
        out.append((f"balance/fix_modify/{kw}", script("eos", "", pre="fix bal all balance/mpm dim x",
                                                        post=f"fix_modify bal {kw} {example[0]}"), kw, "bad"))
    out.append(("balance/measured_without_fluid",
                script("eos", "", pre="fix bal all balance/mpm dim x measured yes").replace(
                    "fix fluid water mpm/fluid " + fixargs("eos") + " ", "create_atoms 1 single 0.05 0.02 0.05 units box\n#"),
                "measured", "bad"))
    out.append(("balance/unknown", script("eos", "", pre="fix bal all balance/mpm dim x colour red"), "colour", "bad"))
    return out


# optional arguments: leaving them out is valid
OPTIONAL = {("transfer", 1)}

MODIFIABLE = ("gate", "damping", "cfl", "boundary", "subcycle", "cell_check")


def case_folder(name):
    """The folder of a case under the work folder: its label with the characters a path may not hold replaced."""
    return re.sub(r"[^A-Za-z0-9_.+-]", "_", name)


def run_one(exe, work, case, timeout):
    name, text, kw, group = case
    if text is None:
        return name, kw, group, "unspecified", "the driver has no argument spec for this keyword"
    d = os.path.join(work, case_folder(name))
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    with open(os.path.join(d, "in.script"), "w") as f:
        f.write(text)
    try:
        p = subprocess.run([exe, "-in", "in.script", "-echo", "none"], cwd=d, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, timeout=timeout)
    except subprocess.TimeoutExpired:
        return name, kw, group, "hang", ""
    out = p.stdout.decode(errors="replace")
    err = next((ln for ln in out.splitlines() if ln.startswith("ERROR")), "")
    warn = next((ln for ln in out.splitlines() if ln.startswith("WARNING") and kw in ln), "")
    if p.returncode == 0 and group == "repeat" and warn:
        outcome, err = "warned", warn
    elif p.returncode == 0:
        outcome = "ran" if group == "extreme" else "silent"
    elif err:
        outcome = "named" if kw in err else "unnamed"
    else:
        outcome = "crash"
    if outcome in ("named", "ran", "warned"):
        shutil.rmtree(d, ignore_errors=True)
    return name, kw, group, outcome, err.strip()[:300] if err else out.strip()[-200:].replace("\n", " | ")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--exe", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("-j", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=60.0)
    a = ap.parse_args()
    exe = os.path.abspath(a.exe)
    os.makedirs(a.work, exist_ok=True)
    todo = cases(a.quick)
    # each case runs in its own folder, named from its label: two cases with one folder would
    # run at once in it under -j > 1 and read each other's files
    dirs = [case_folder(c[0]) for c in todo]
    dup = sorted({x for x in dirs if dirs.count(x) > 1})
    if dup:
        sys.exit("fuzz_mpm_fluid.py: cases share a folder: " + " ".join(dup))
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.j) as pool:
        results = list(pool.map(lambda c: run_one(exe, a.work, c, a.timeout), todo))
    counts = {}
    for name, kw, group, outcome, msg in results:
        counts[(group, outcome)] = counts.get((group, outcome), 0) + 1
        if outcome not in ("named", "ran", "warned"):
            print(f"{outcome:9s} {name}: {msg}")
    bad = [r for r in results if r[2] in ("bad", "repeat")]
    ext = [r for r in results if r[2] == "extreme"]
    c = lambda rows, o: sum(1 for r in rows if r[3] == o)  # noqa: E731
    print(f"fuzz: extremes {len(ext)} ran {c(ext, 'ran')} named {c(ext, 'named')} unnamed {c(ext, 'unnamed')} "
          f"crashes {c(ext, 'crash')} hangs {c(ext, 'hang')}")
    rep = [r for r in results if r[2] == "repeat"]
    print(f"fuzz: repeated keywords {len(rep)} warned {c(rep, 'warned')} named {c(rep, 'named')}")
    print(f"fuzz: cases {len(bad)} named {c(bad, 'named') + c(bad, 'warned')} unnamed {c(bad, 'unnamed') + c(bad, 'unspecified')} "
          f"crashes {c(bad, 'crash')} hangs {c(bad, 'hang')} silent {c(bad, 'silent')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
