#!/usr/bin/env python3
"""Whole-program tests of fix balance/mpm (liggghts_mpm/fix_balance_mpm.h; docs/fix_balance_mpm.md).
Standard library only.

    test_balance.py CASE --exe build/liggghts_mpm --inputs inputs --work DIR [--mpirun "mpirun ..."]

CASE: np2 (3-D dam break of inputs/bench on 2 ranks with the balance fix against 1 rank),
every_fluid (the same re-balanced every 50 steps inside one run, eos and projection),
every_dem (re-balancing inside a run, no fluid), volume_dem (keyword volume), measured (cuts by the
measured work), grid2d (4 ranks on a 2 x 2 grid, dim x y against dim x and 1 rank), grid2d_measured (the same
re-balanced in a run by measured work; thresh on the rank grid), bad_input,
bad_input_dims (keyword dim with several dims), all. Exit status 0 when every check passes.
"""
import argparse
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import cases  # noqa: E402
from cases import check, read_csv  # noqa: E402


def cut_lines(text):
    """[(step, [cuts], imbalance before, after)] from the fix's log lines."""
    out = []
    for m in re.finditer(r"fix balance/mpm: step (\d+), cuts in \w:([-\d.eE+ ]+)\((measured )?imbalance (\S+) -> (\S+)\)",
                         text):
        out.append((int(m.group(1)), [float(v) for v in m.group(2).split()], float(m.group(4)),
                    float(m.group(5)), bool(m.group(3))))
    return out


def grid_lines(text):
    """[(step, {dim: [cuts]}, imbalance before, after)] from the fix's log lines, any number of dims
    ("cuts in x: 0 0.5 3, in y: 0 1 2 (imbalance ...)")."""
    out = []
    for m in re.finditer(r"fix balance/mpm: step (\d+), cuts in (.*) \((measured )?imbalance (\S+) -> (\S+)\)", text):
        cuts = {}
        for part in m.group(2).split(", in "):
            dim, vals = part.split(":")
            cuts[dim.strip()] = [float(v) for v in vals.split()]
        out.append((int(m.group(1)), cuts, float(m.group(4)), float(m.group(5))))
    return out


def rank_points(text):
    """[(min, mean, max)] of the per-rank material points fix mpm/fluid prints after each run."""
    return [tuple(float(v) for v in m.groups())
            for m in re.finditer(r"fix mpm/fluid: work per rank \(min/mean/max over \d+ ranks\): points (\S+)/(\S+)/(\S+),",
                                 text)]


def case_grid2d(r):
    """4 ranks on a 2 x 2 x 1 grid (processors * * 1): the 3-D dam break's cube stands in the corner
    x < a, y < a of the 3a x 2a tank, non-uniform in x and in y. 5 cells across the cube and 3 x 3 x 3
    points per cell: 15 lattice planes of points along each of x and y. Each cut is placed by its
    marginal and never splits a plane, so it leaves 7 or 8 of the 15 planes on each side, and the
    cube's points (a product of the x and y planes) make the largest of the four ranks hold 8 x 8 of
    the 15 x 15 columns: max/mean = 4 (8/15)^2 = (16/15)^2 = 1.1378, the lattice's bound (no pair of
    cuts between planes does better). With dim x alone the y cut stays at a of the 2a: two ranks
    hold nothing, max/mean = 4 (8/15) / 2 = 2.133. Per-rank points are read from fix mpm/fluid's
    line after the first run (10 steps after the balance at step 0), independent of the balance
    fix's own sum. The 4-rank run with dim x y = 1 rank to 1e-10 (as np2)."""
    inp = os.path.join(r.inputs, "bench", "in.dambreak3d")
    v = dict(cells=5, ppc=3, warm=10, nsteps=40, segments=2, cellw=0, alongx=2)
    bound = (16.0 / 15.0) ** 2
    d1, _ = r.run("balance_grid2d/np1", inp, v)
    res = {}
    for name, dims in (("xy", "x y"), ("x", "x")):
        d, p = r.run(f"balance_grid2d/np4_{name}", inp, dict(v, balance=1, baldim=dims), np=4)
        lines, pts = grid_lines(p.stdout), rank_points(p.stdout)
        print(f"  dim {dims}: " + "\n    ".join(str(ln) for ln in lines) + f"\n    per-rank points after each run: {pts}")
        check(len(lines) == 3 and len(pts) == 3, f"dim {dims}: balanced at the setup of each of 3 runs ({len(lines)}), "
              f"per-rank points after each ({len(pts)})")
        check(all(sorted(ln[1]) == sorted(dims.split()) and all(len(c) == 3 for c in ln[1].values()) for ln in lines),
              f"dim {dims}: the cuts of {dims} printed, 2 ranks along each")
        res[name] = (d, lines, pts)
    _, lxy, pxy = res["xy"]
    _, lx, px = res["x"]
    if len(lxy) == 3 and len(lx) == 3 and len(pxy) == 3 and len(px) == 3:
        mm_xy, mm_x = pxy[0][2] / pxy[0][1], px[0][2] / px[0][1]
        print(f"  per-rank points max/mean after the first run: dim x y {mm_xy:.4f}, dim x {mm_x:.4f} "
              f"(lattice bound {bound:.4f})")
        check(pxy[0][1] == 3375 / 4, f"the 3375 points over 4 ranks (mean {pxy[0][1]})")
        check(abs(mm_xy - bound) < 1e-9, f"dim x y: per-rank points max/mean {mm_xy:.4f} = the lattice bound (16/15)^2")
        check(abs(lxy[0][3] - bound) < 5e-4, f"dim x y: the fix's imbalance after at step 0 {lxy[0][3]} = (16/15)^2")
        check(all(ln[3] <= 1.25 for ln in lxy), f"dim x y: imbalance after every balance <= 1.25 "
              f"({[ln[3] for ln in lxy]})")
        check(abs(mm_x - 64.0 / 30.0) < 1e-9 and abs(lx[0][3] - 64.0 / 30.0) < 5e-4,
              f"dim x alone: per-rank points max/mean {mm_x:.4f} = 32/15, imbalance after {lx[0][3]}")
        check(all(b[3] < 0.65 * a[3] for a, b in zip(lx, lxy)),
              f"dim x y below 0.65 of dim x at every balance ({[ln[3] for ln in lxy]} vs {[ln[3] for ln in lx]})")
    f1 = read_csv(os.path.join(d1, "bench3d.csv"))
    f4 = read_csv(os.path.join(res["xy"][0], "bench3d.csv"))
    for k in ("front_x", "front_y", "points", "steps"):
        diff = abs(f1[k][0] - f4[k][0])
        check(diff < 1e-10, f"{k}: np4 (dim x y) = np1 to 1e-10 (|diff| = {diff:.1e})")
    check(f1["front_x"][0] > 1.0 + 1e-3, "the column has started to spread")


def case_grid2d_measured(r):
    """The grid2d scene (4 ranks, 2 x 2) re-balanced every 25 steps of a 100-step run along x and y by
    the work fix mpm/fluid measured on each rank: = 1 rank to 1e-10 m (eos, as the 2-rank measured
    case); every balance after the first is by measured work, and the largest measured imbalance
    after a re-cut is below the largest before one. (A single re-cut may raise it: cuts shared along
    a dimension and placed by marginals even out the ranks only as far as the weight is a product
    of its x and y parts, and a plane of points holds 1/15 of them; seen once in 100 re-cuts,
    1.076 -> 1.106.) thresh compares the imbalance of the rank grid: at 1.2, dim x y balances at step 0
    (4 -> (16/15)^2) and then skips (1.138 <= 1.2); dim x alone balances at every setup, because its
    ranks' imbalance stays 2.13 although its x slabs are even."""
    inp = os.path.join(r.inputs, "bench", "in.dambreak3d")
    v = dict(cells=5, ppc=3, warm=10, nsteps=100, segments=1, cellw=0, alongx=2)
    d1, _ = r.run("balance_grid2d_measured/np1", inp, v)
    d4, p4 = r.run("balance_grid2d_measured/np4", inp, dict(v, balance=1, baldim="x y", rebal=25, measured="yes"), np=4)
    lines = grid_lines(p4.stdout)
    measured = re.findall(r"fix balance/mpm: step \d+, cuts in .* \((measured )?imbalance", p4.stdout)
    print("  " + "\n  ".join(str(ln) for ln in lines))
    # setups at steps 0 and 10, then steps 25, 50, 75, 100 of the second run
    check(len(lines) == 6 and all(sorted(ln[1]) == ["x", "y"] for ln in lines),
          f"balanced along x and y at both setups and every 25 steps ({len(lines)} of 6)")
    check(len(measured) == 6 and measured[0] == "" and all(m for m in measured[1:]),
          "the first balance by points (nothing measured yet), the others by measured work")
    before, after = [ln[2] for ln in lines[1:]], [ln[3] for ln in lines[1:]]
    check(bool(lines[1:]) and all(b >= 1.0 and a >= 1.0 for b, a in zip(before, after)) and max(after) < max(before),
          f"measured imbalance >= 1; the largest after a re-cut {max(after, default=0)} below the largest before "
          f"{max(before, default=0)}")
    f1 = read_csv(os.path.join(d1, "bench3d.csv"))
    f4 = read_csv(os.path.join(d4, "bench3d.csv"))
    for k in ("front_x", "front_y", "mass"):
        diff = abs(f1[k][0] - f4[k][0])
        check(diff < 1e-10, f"{k}: np4 (dim x y, measured, re-balanced in the run) = np1 to 1e-10 (|diff| = {diff:.1e})")
    vt = dict(v, nsteps=20, segments=2, balance=1, balthresh=1.2)
    for dims, nexp, after in (("x y", 1, (16.0 / 15.0) ** 2), ("x", 3, 32.0 / 15.0)):
        _, p = r.run(f"balance_grid2d_measured/thresh_{dims.replace(' ', '')}", inp, dict(vt, baldim=dims), np=4)
        tl = grid_lines(p.stdout)
        print(f"  thresh 1.2, dim {dims}: {tl}")
        check(len(tl) == nexp and bool(tl) and abs(tl[0][3] - after) < 5e-4,
              f"thresh 1.2, dim {dims}: {len(tl)} of 3 setups balanced (expected {nexp}), the first to {after:.4f}")


def case_np2(r):
    """2 ranks with balance/mpm (re-balanced at the setup of each of 3 runs) = 1 rank to 1e-10."""
    inp = os.path.join(r.inputs, "bench", "in.dambreak3d")
    v = dict(cells=8, warm=10, nsteps=90, segments=3, cellw=0)  # by point counts (volume: volume_dem)
    d1, _ = r.run("balance_np2/np1", inp, v)
    d2, p2 = r.run("balance_np2/np2", inp, dict(v, balance=1), np=2)
    f1 = read_csv(os.path.join(d1, "bench3d.csv"))
    f2 = read_csv(os.path.join(d2, "bench3d.csv"))
    for k in ("front_x", "front_y", "points", "steps"):
        diff = abs(f1[k][0] - f2[k][0])
        check(diff < 1e-10, f"{k}: np2 (balanced) = np1 to 1e-10 (|diff| = {diff:.1e})")
    check(f1["front_x"][0] > 0.5 + 1e-3, "the column has started to spread")
    lines = cut_lines(p2.stdout)
    print("  " + "\n  ".join(str(ln) for ln in lines))
    check(len(lines) == 4, f"balanced at the setup of every run ({len(lines)} of 4)")
    if lines:
        step, cuts, before, after, _ = lines[0]
        # uniform cut of the 3 m box would be 1.5 m; the column occupies x < 1
        check(abs(cuts[1] - 1.5) > 0.5 and 0.0 < cuts[1] < 1.0, f"the cut moved into the column ({cuts[1]:.4f} m)")
        check(before > 1.9 and after < 1.05, f"imbalance {before:.3f} -> {after:.3f} (max rank / mean)")


def rebalanced_np2_same(r, group, pressure, tol, more, what):
    """The 3-D dam break (cells 8, 300 steps) on 1 rank and on 2 re-balanced every 50 steps (more:
    further variables): front, height and mass equal to tol. Returns np1's bench3d.csv and np2's
    process."""
    inp = os.path.join(r.inputs, "bench", "in.dambreak3d")
    v = dict(cells=8, warm=10, nsteps=300, segments=1, cellw=0, pressure=pressure)
    d1, p1 = r.run(f"{group}/{pressure}_np1", inp, v)
    d2, p2 = r.run(f"{group}/{pressure}_np2", inp, dict(v, balance=1, rebal=50, **more), np=2)
    if pressure == "projection":
        # the end-of-run line counts every solve of the run, also across the re-cuts (each builds
        # a new patch and pressure solver)
        solves = r"wall time in this run: fluid \S+ s \(pressure solver \S+ s = \S+ of it, (\d+) solves"
        s1, s2 = re.findall(solves, p1.stdout), re.findall(solves, p2.stdout)
        check(len(s1) == 2 and s1 == s2 and int(s1[-1]) >= 300,
              f"{pressure}: solves per run reported on 2 re-balanced ranks = 1 rank ({s2} and {s1})")
    f1 = read_csv(os.path.join(d1, "bench3d.csv"))
    f2 = read_csv(os.path.join(d2, "bench3d.csv"))
    for k in ("front_x", "front_y", "mass"):
        diff = abs(f1[k][0] - f2[k][0])
        check(diff < tol, f"{pressure}, {k}: np2 ({what}) = np1 to {tol:g} (|diff| = {diff:.1e})")
    return f1, p2


def case_every_fluid(r):
    """2 ranks re-balanced every 50 steps inside one run of 300 (`every 50`: fix mpm/fluid builds its
    grid patch again after each re-cut, the projection's last solve carried into it) = 1 rank:
    eos to 1e-10 m, projection to 1e-6 m (the solver tolerance); the cut follows the front."""
    for pressure, tol in (("eos", 1e-10), ("projection", 1e-6)):
        f1, p2 = rebalanced_np2_same(r, "balance_every_fluid", pressure, tol, {}, "re-balanced in the run")
        lines = cut_lines(p2.stdout)
        cuts = [ln[1][1] for ln in lines]
        print(f"  {pressure}: {len(lines)} balances, cut {cuts[0]:.4f} -> {cuts[-1]:.4f} m, front {f1['front_x'][0]:.4f} m"
              if lines else f"  {pressure}: no balance line")
        # at the setups of the two runs (10 and 300 steps) and at steps 50, 100, ..., 300 of the second
        check(len(lines) == 8, f"{pressure}: balanced at both setups and every 50 steps ({len(lines)} of 8)")
        if pressure == "projection" and cuts:
            check(cuts[-1] > cuts[0] + 0.3, f"the cut follows the water ({cuts[0]:.3f} -> {cuts[-1]:.3f} m)")


def case_measured(r):
    """Keyword measured: 2 ranks re-balanced every 50 steps by the work fix mpm/fluid measured on each
    rank = 1 rank (eos to 1e-10 m, projection to 1e-6 m); every balance after the first is by measured
    work, its imbalance before >= 1 and the cuts it places even the measured weights out."""
    for pressure, tol in (("eos", 1e-10), ("projection", 1e-6)):
        _, p2 = rebalanced_np2_same(r, "balance_measured", pressure, tol, {"measured": "yes"}, "measured work")
        lines = cut_lines(p2.stdout)
        print("  " + "\n  ".join(str(ln) for ln in lines))
        check(len(lines) == 8, f"{pressure}: balanced at both setups and every 50 steps ({len(lines)} of 8)")
        check(lines and not lines[0][4] and all(ln[4] for ln in lines[1:]),
              f"{pressure}: the first balance by points (nothing measured yet), the others by measured work")
        check(all(ln[2] >= 1.0 and 1.0 <= ln[3] <= ln[2] + 1e-9 for ln in lines[1:]),
              f"{pressure}: measured imbalance >= 1 before, and not above it after each re-cut")
        # the end-of-run line: per-rank busy time and halo waits, consistent with the fluid timer
        runs = re.findall(r"wall time in this run: fluid (\S+) s.*; per rank: busy (\S+) to (\S+) s \(max/mean (\S+)\), "
                          r"waits for halo messages (\S+) to (\S+) s", p2.stdout)
        print(f"  per-rank lines: {runs}")
        check(len(runs) == 2, f"{pressure}: both runs print the per-rank busy time and halo waits ({len(runs)} of 2)")
        check(all(0.0 <= float(b0) <= float(b1) and 0.0 <= float(w0) <= float(w1) and float(mm) >= 1.0 - 1e-12
                  # busy + wait of the busiest rank = its fluid time <= the slowest's, exactly; the line
                  # prints 6 significant digits, so each printed value is off by up to 5e-6 of itself
                  and float(b1) + float(w0) <= float(fl) + 5e-6 * (float(b1) + float(w0) + float(fl))
                  for fl, b0, b1, mm, w0, w1 in runs),
              f"{pressure}: busy and waits are ordered min <= max, max/mean >= 1, and busy + wait of a rank "
              f"is not more than the slowest rank's fluid time")


# a small fluid scene whose fix balance/mpm line takes {args}
BAD_TMPL = """atom_style sphere
atom_modify map array sort 0 0
boundary f f f
units si
region box block 0 2 0 1 0 1 units box
create_box 1 box
region col block 0 1 0 1 0 1 units box
neighbor 0.1 bin
fix b all balance/mpm {args}
fix f all mpm/fluid cell 0.25 density 1000 pressure eos bulk 2e6 fill col 2 2 2 type 1
run 0
"""


def expect_refusals(r, case, tmpl, bad):
    """Each (arguments, message) of bad, put into tmpl's {args}, stops with an error containing the message."""
    for i, (args, expect) in enumerate(bad):
        r.expect_error(f"{case}/{i}", tmpl.format(args=args), (expect,), f"'{args}' -> \"{expect}\"")


def case_bad_input(r):
    """Bad arguments stop with an error naming the command and the keyword."""
    tmpl = BAD_TMPL
    bad = [
        ("dim x colour red", "Fix balance/mpm: unknown keyword 'colour'"),
        ("dim", "Fix balance/mpm: keyword 'dim' expects x, y or z, got nothing"),
        ("dim w", "Fix balance/mpm: keyword 'dim' expects x, y or z, got 'w'"),
        ("every 10", "Fix balance/mpm: keyword 'dim' (x, y or z) is required"),
        ("dim x every", "Fix balance/mpm: keyword 'every' expects"),
        ("dim x every -3", "Fix balance/mpm: keyword 'every' expects"),
        ("dim x thresh 0.5", "Fix balance/mpm: keyword 'thresh' expects an imbalance factor >= 1"),
        ("dim x weight nogroup 2", "Fix balance/mpm: keyword 'weight' expects an existing group ID"),
        ("dim x weight all", "Fix balance/mpm: keyword 'weight' expects a weight >= 0"),
        ("dim x volume -1", "Fix balance/mpm: keyword 'volume' expects a weight per unit volume >= 0"),
        ("dim x volume", "Fix balance/mpm: keyword 'volume' expects a weight per unit volume >= 0"),
        ("dim x every 4294967296", "Fix balance/mpm: keyword 'every' expects a number of steps >= 0"),
        ("dim x weight all 1e308", "Fix balance/mpm: keyword 'weight' expects a weight per atom (dimensionless"),
        ("dim x volume 1e308", "Fix balance/mpm: keyword 'volume' expects a weight per unit volume (1/length^3) in"),
        ("dim x measured maybe", "Fix balance/mpm: keyword 'measured' expects yes or no, got 'maybe'"),
        ("dim x measured", "Fix balance/mpm: keyword 'measured' expects yes or no, got nothing"),
    ]
    expect_refusals(r, "balance_bad_input", tmpl, bad)
    p, msg = r.run_script("balance_bad_input/ok", tmpl.format(args="dim x every 0 weight all 1.0 thresh 1.1"))
    check(p.returncode == 0, f"valid arguments run ({msg.strip()[:120]})")


def case_bad_input_dims(r):
    """Keyword dim with several dims: repeated, unknown or z in a 2-D run stop with an error naming
    the keyword, what it expects and the values given; a valid list runs."""
    tmpl = BAD_TMPL
    bad = [
        ("dim x x", "Fix balance/mpm: keyword 'dim' expects one to three distinct dimensions x, y or z "
                    "(each at most once), got 'x x'"),
        ("dim x y x", "Fix balance/mpm: keyword 'dim' expects one to three distinct dimensions x, y or z "
                      "(each at most once), got 'x y x'"),
        ("dim x q", "Fix balance/mpm: keyword 'dim' expects x, y or z, got 'q'"),
        ("dim y 1 every 5", "Fix balance/mpm: keyword 'dim' expects x, y or z, got '1'"),
        ("dim x y colour red", "Fix balance/mpm: unknown keyword 'colour'"),
        ("dim x yz", "Fix balance/mpm: unknown keyword 'yz'"),
    ]
    expect_refusals(r, "balance_bad_input_dims", tmpl, bad)
    two_d = """dimension 2
atom_style sphere
boundary f f p
units si
region box block 0 2 0 1 -0.5 0.5 units box
create_box 1 box
fix b all balance/mpm dim x z
"""
    r.expect_error("balance_bad_input_dims/2d", two_d, ("Fix balance/mpm: keyword 'dim' is z in a 2d run",),
                   "'dim x z' in a 2d run -> \"keyword 'dim' is z in a 2d run\"")
    for i, args in enumerate(("dim x y z every 0 thresh 1.1", "dim z x", "dim y")):
        p, msg = r.run_script(f"balance_bad_input_dims/ok{i}", tmpl.format(args=args))
        check(p.returncode == 0, f"valid arguments '{args}' run ({msg.strip()[:120]})")


DEM = """atom_style sphere
atom_modify map array sort 0 0
boundary f f f
units si
processors * 1 1
region box block 0 4 0 1 0 1 units box
create_box 1 box
region left block 0 1 0 1 0 1 units box
lattice sc 0.1
create_atoms 1 region left
set group all diameter 0.01 density 1000
neighbor 0.05 bin
neigh_modify delay 0 every 1 check yes
velocity all set 1.0 0 0 units box
fix bal all balance/mpm dim x every 50
fix nve all nve/sphere
thermo_style custom step atoms f_bal[1] f_bal[3] f_bal[5]
thermo 50
timestep 0.005
run 400
"""


def case_every_dem(r):
    """Without fix mpm/fluid, 'every 50' re-balances inside a run: a slab of atoms drifting in +x."""
    d = r.fresh("balance_every_dem")
    with open(os.path.join(d, "in.dem"), "w") as f:
        f.write(DEM)
    p = r.execute(d, "in.dem", np=2)
    lines = cut_lines(p.stdout)
    check(len(lines) == 9, f"balanced at setup and every 50 steps ({len(lines)} of 9)")
    cuts = [ln[1][1] for ln in lines]
    # 11 planes of 100 atoms (x = 0, 0.1, ..1.0) move at 1 m/s: the cut follows them
    check(all(b > a for a, b in zip(cuts, cuts[1:])), f"the cut follows the atoms ({cuts[0]:.3f} -> {cuts[-1]:.3f})")
    check(abs(cuts[-1] - (0.45 + 2.0)) < 1e-6, "cut between the 5th and 6th plane after 2 s")
    check(all(ln[3] < 1.1 for ln in lines), "imbalance after each balance at most 6/5.5")
    check(re.search(r"^\s*400\s+1100\s", p.stdout, re.M) is not None, "no atom lost (1100 at step 400)")


def case_volume_dem(r):
    """Keyword volume: the box volume counts too (grid work where there are no atoms). 1100 atoms in
    x < 1 of a 4 m box (cross-section 1 m^2), volume 1100 per m^3: total 5500, half at
    1100 + 1100 c = 2750, so the cut is at c = 1.5 m, between planes of atoms no more."""
    d = r.fresh("balance_volume_dem")
    src = DEM.replace("fix bal all balance/mpm dim x every 50", "fix bal all balance/mpm dim x volume 1100")
    src = src.replace("velocity all set 1.0 0 0 units box", "").replace("run 400", "run 0")
    with open(os.path.join(d, "in.dem"), "w") as f:
        f.write(src)
    p = r.execute(d, "in.dem", np=2)
    lines = cut_lines(p.stdout)
    check(len(lines) == 1, f"balanced at setup ({len(lines)} of 1)")
    if lines:
        cut = lines[0][1][1]
        check(abs(cut - 1.5) < 1e-6, f"cut at 1.5 m ({cut:.9f})")
        check(lines[0][3] < 1.0 + 1e-6, f"imbalance after {lines[0][3]:.6f} (atoms + volume per rank equal)")
    # without the volume the cut lies between the 5th and 6th plane
    src0 = src.replace(" volume 1100", "")
    d0 = r.fresh("balance_volume_dem0")
    with open(os.path.join(d0, "in.dem"), "w") as f:
        f.write(src0)
    lines0 = cut_lines(r.execute(d0, "in.dem", np=2).stdout)
    check(bool(lines0) and abs(lines0[0][1][1] - 0.45) < 1e-6, "without volume: cut at 0.45 m")


CASES = {"np2": case_np2, "every_fluid": case_every_fluid, "measured": case_measured, "bad_input": case_bad_input, "every_dem": case_every_dem,
         "volume_dem": case_volume_dem, "grid2d": case_grid2d, "grid2d_measured": case_grid2d_measured,
         "bad_input_dims": case_bad_input_dims}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", choices=sorted(CASES) + ["all"])
    ap.add_argument("--exe", required=True)
    ap.add_argument("--inputs", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--mpirun", default="mpirun --allow-run-as-root --oversubscribe")
    a = ap.parse_args()
    return cases.run_cases(CASES, a.case, cases.Runner(a))


if __name__ == "__main__":
    sys.exit(main())
