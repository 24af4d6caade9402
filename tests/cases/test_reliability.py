#!/usr/bin/env python3
"""Inputs that once gave silent wrong results, crashes or unhelpful messages, each as a
case that must now either run correctly or stop with a message naming the keyword or quantity.

    test_reliability.py CASE --exe build/liggghts_mpm --inputs inputs --work DIR --mpirun "mpirun ..."
"""
import math
import os
import re
import shutil
import subprocess
import time
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cases  # noqa: E402
from cases import check, driver_main, read_csv  # noqa: E402

# A water column on the floor of a box; grains of type 2 may be added; granular contacts between
# grains (pair gran); {pre} before the fix (exclusion lines), {fixargs} more keywords.
COLUMN = cases.PREAMBLE + """region box block 0 0.4 0 0.05 0 0.3 units box
create_box 2 box
neighbor 0.005 bin
neigh_modify delay 0 every 1 check yes
{pre}
fix m1 all property/global kn peratomtypepair 2 1000 1000 1000 1000
fix m2 all property/global kt peratomtypepair 2 300 300 300 300
fix m3 all property/global gamman peratomtypepair 2 1 1 1 1
fix m4 all property/global gammat peratomtypepair 2 1 1 1 1
fix m5 all property/global coefficientFriction peratomtypepair 2 0.3 0.3 0.3 0.3
pair_style gran model hooke/stiffness tangential history
pair_coeff * *
region col block 0 0.1 0 0.05 0 0.2 units box
fix fluid all mpm/fluid cell 0.025 density 1000 pressure eos bulk 2e5 viscosity 1e-3 boundary all freeslip &
    fill col 2 2 2 type 1 front x {fixargs}
fix grav all gravity 9.81 vector 0 0 -1
timestep 2e-4
variable xf equal f_fluid[4]
variable np equal f_fluid[9]
run {steps}
print "RESULT front ${{xf}} points ${{np}} atoms $(atoms)"
"""


def execute_text(r, d, text, variables=None):
    """Writes the input text as in.script in folder d and runs it (no error expected or not)."""
    with open(os.path.join(d, "in.script"), "w") as f:
        f.write(text)
    return r.execute(d, "in.script", variables, expect_ok=False, timeout=300)


def result(p):
    m = re.search(r"RESULT front (\S+) points (\S+) atoms (\S+)", p.stdout)
    return tuple(float(x) for x in m.groups()) if m else None


def case_pair_exclusion(r):
    """Without 'neigh_modify exclude' the granular pair style treated the points as grains (the
    column piled up like sand, an atom was lost, no message). Now: the same result as with the
    exclusion, or an error that gives the line to add."""
    ok_script = COLUMN.format(pre="neigh_modify exclude type 1 1\nneigh_modify exclude type 1 2",
                              fixargs="", steps=400)
    bare = COLUMN.format(pre="", fixargs="", steps=400)
    d = r.fresh("pair_exclusion/with")
    p1 = execute_text(r, d, ok_script)
    ref = result(p1)
    check(ref is not None, f"column with the exclusion lines runs ({ref})")
    d = r.fresh("pair_exclusion/without")
    p2 = execute_text(r, d, bare)
    got = result(p2)
    err = next((ln for ln in p2.stdout.splitlines() if "ERROR" in ln), "")
    if p2.returncode == 0 and got is not None:
        check(ref is not None and got == ref, f"without the exclusion: same front, points and atoms ({got} vs {ref})")
    else:
        check("neigh_modify exclude type 1 1" in err, f"without the exclusion: error names the line to add ({err.strip()[:200]})")


def case_theta_smooth_bound(r):
    """theta_smooth 1e3 hung (2e8 passes a step), 1e5 and 1e308 overflowed the pass count and
    silently smoothed nothing: a length beyond the grid is an error naming the keyword."""
    for v in ("1e3", "1e5", "1e308"):
        r.expect_error(f"theta_smooth/{v}", GRAINS.format(fixargs=f"theta_smooth {v}", d="0.004", steps=5),
                       ("theta_smooth", "m"), f"theta_smooth {v} -> error naming the keyword")


# A few grains in a fluid-filled box (coupled); {d} grain diameter
GRAINS = cases.PREAMBLE + """region box block 0 0.04 0 0.04 0 0.04 units box
create_box 2 box
neighbor 0.001 bin
neigh_modify delay 0 every 1 check yes exclude type 1 1 exclude type 1 2
create_atoms 2 single 0.02 0.02 0.02 units box
create_atoms 2 single 0.012 0.02 0.02 units box
set type 2 diameter {d} density 2500
group grains type 2
group fluid type 1
fix f fluid mpm/fluid cell 0.005 density 1000 pressure eos bulk 1e5 viscosity 1e-3 fill box 1 1 1 type 1 couple grains {fixargs}
fix nve grains nve/sphere
timestep 1e-5
run {steps}
"""


def case_integer_bounds(r):
    """Integers >= 2^32 wrapped (fill 4294967298 ran as 2): now an error naming the keyword."""
    tmpl = COLUMN.replace("fill col 2 2 2 type 1", "fill col {n} 2 2 type {t}")
    for n, t, kw in (("4294967298", "1", "fill"), ("2", "4294967297", "fill type")):
        r.expect_error(f"integer_bounds/{n}_{t}", tmpl.format(pre="neigh_modify exclude type 1 1\nneigh_modify exclude type 1 2",
                                                               fixargs="", steps=1, n=n, t=t),
                       (kw,), f"fill {n} .. type {t} -> error naming '{kw}'")
    r.expect_error("integer_bounds/every", GRAINS.format(fixargs="every 4294967297", d="0.002", steps=1),
                   ("every",), "every 4294967297 -> error naming 'every'")


def case_nonfinite_grain(r):
    """A grain whose mass underflows (d = 1e-110) gets a non-finite position: it segfaulted in the
    fluid fraction; now the run stops with a message naming the atom, the quantity and the step."""
    d = r.fresh("nonfinite_grain")
    p = execute_text(r, d, GRAINS.format(fixargs="", d="1e-110", steps=20))
    err = next((ln for ln in p.stdout.splitlines() if "ERROR" in ln), "")
    check(p.returncode not in (0,) and p.returncode > 0, f"stopped with an error exit code, no signal ({p.returncode})")
    check("grain" in err and ("not finite" in err or "non-finite" in err), f"message names the grain ({err.strip()[:200]})")


def case_messages(r):
    """Messages that name the keyword: overflowing values, six digits of the time step, 'flip nan'."""
    ex = "neigh_modify exclude type 1 1\nneigh_modify exclude type 1 2"
    r.expect_error("messages/flipnan", COLUMN.format(pre=ex, fixargs="transfer flip nan", steps=1),
                   ("transfer flip",), "transfer flip nan -> error naming 'transfer flip'")
    r.expect_error("messages/bulk", COLUMN.format(pre=ex, fixargs="", steps=5).replace("bulk 2e5", "bulk 1e308"),
                   ("bulk",), "bulk 1e308 -> error naming 'bulk'")
    r.expect_error("messages/visc", COLUMN.format(pre=ex, fixargs="", steps=5).replace("viscosity 1e-3", "viscosity 1e300"),
                   ("viscosity",), "viscosity 1e300 -> error naming 'viscosity'")
    # the time-step error prints the step and the limit to six significant digits
    d = r.fresh("messages/dt")
    p = execute_text(r, d, COLUMN.format(pre=ex, fixargs="", steps=5).replace("timestep 2e-4", "timestep 3e-3"))
    err = next((ln for ln in p.stdout.splitlines() if "ERROR" in ln), "")
    m = re.search(r"exceeds the largest stable time step (\S+)", err)
    check(m is not None and len(re.sub(r"[^0-9]", "", m.group(1).split("e")[0]).lstrip("0")) >= 6,
          f"stable time step printed to 6 digits ({err.strip()[:160]})")


def case_restart_gate_time(r):
    """read_restart reset the simulated time to 0: a gate timed at 0.1 s opened late after a restart.
    The fix keeps its own time: the resumed run equals the uninterrupted one."""
    tmpl = """variable mode index 0
if "${mode} == 2" then "jump SELF restarted"
atom_style sphere
atom_modify map array sort 0 0
boundary f f f
newton off
communicate single vel yes
units si
region box block 0 2.0 0 0.1 0 1.2 units box
create_box 1 box
region column block 0 0.8 0 0.1 0 0.8 units box
jump SELF common
label restarted
read_restart restart.mpm
label common
atom_modify sort 0 0
neighbor 0.02 bin
neigh_modify delay 0 every 1 check yes
fix fluid all mpm/fluid cell 0.1 density 1000 pressure eos bulk 2e6 viscosity 0.01 boundary all freeslip &
    fill column 2 1 2 type 1 front x gate x 0.8 lower 0.1 output 125 col points p
fix grav all gravity 9.81 vector 0.0 0.0 -1.0
timestep 2e-4
variable steps equal 500
if "${mode} == 1" then "variable steps equal 250"
if "${mode} == 2" then "variable steps equal 750"
run ${steps} upto
if "${mode} == 1" then "write_restart restart.mpm"
variable xf equal f_fluid[4]
variable ke equal f_fluid[2]
print "RESULT ${xf} ${ke}"
"""
    # 'run N upto' runs to step N, so all three end at step 500 / 250 / 750 ... the full run
    # goes to 750 as well
    full = tmpl.replace("variable steps equal 500", "variable steps equal 750")
    d0 = r.fresh("restart_gate/full")
    p0 = execute_text(r, d0, full, {"mode": 0})
    d1 = r.fresh("restart_gate/split")
    execute_text(r, d1, tmpl, {"mode": 1})
    p2 = r.execute(d1, "in.script", {"mode": 2}, expect_ok=False, timeout=120)
    a = re.search(r"RESULT (\S+) (\S+)", p0.stdout)
    b = re.search(r"RESULT (\S+) (\S+)", p2.stdout)
    check(a is not None and b is not None, "both runs finished")
    if a and b:
        check(a.groups() == b.groups(), f"resumed run equals the uninterrupted one (front, ke: {a.groups()} vs {b.groups()})")
    check("gate removed at time 0.1" in p2.stdout or "gate removed at time 0.1" in p0.stdout,
          "the gate opened at 0.1 s")
    # the HDF5 series: the XDMF index of the resumed run has the uninterrupted run's times (they
    # jumped back to 0 at the restart before)
    def xmf_times(d):
        with open(os.path.join(d, "col.xmf")) as f:
            return re.findall(r'mpm-step step="(\d+)" time="([^"]+)"', f.read())
    t0, t1 = xmf_times(d0), xmf_times(d1)
    print(f"  XDMF (step, time) uninterrupted {t0[-3:]}, resumed {t1[-3:]}")
    check(len(t0) == 7 and t1 == t0, "XDMF steps and times of the resumed run equal the uninterrupted run's")


# Grains on the cut between two ranks (np 2 splits the 0.04 m box at x = 0.02), free in a fluid
# under gravity; {model}: the coupling model; per-grain position, velocity and fluid force dumped.
CUT = """atom_style sphere
atom_modify map array sort 0 0
boundary f f f
newton off
communicate single vel yes
units si
region box block 0 0.04 0 0.02 0 0.02 units box
create_box 2 box
neighbor 0.001 bin
neigh_modify delay 0 every 1 check yes
create_atoms 2 single 0.0195 0.010 0.010 units box
create_atoms 2 single 0.0205 0.008 0.012 units box
create_atoms 2 single 0.0200 0.012 0.008 units box
create_atoms 2 single 0.0180 0.009 0.011 units box
create_atoms 2 single 0.0220 0.011 0.009 units box
set type 2 diameter 0.002 density 2500
group grains type 2
group fluid type 1
fix grav all gravity 9.81 vector 0 0 -1
fix f fluid mpm/fluid cell 0.0025 density 1000 pressure eos bulk 1e5 viscosity 1e-3 fill box 1 1 1 type 1 couple grains model {model}
fix nve grains nve/sphere
timestep 1e-5
dump d grains custom {steps} grains.dump id x y z vx vy vz f_dragforce[1] f_dragforce[2] f_dragforce[3]
dump_modify d sort id format "%d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g"
run {steps}
"""


def last_rows(path):
    text = open(path).read().split("ITEM: TIMESTEP")[-1].splitlines()
    start = next(i for i, ln in enumerate(text) if ln.startswith("ITEM: ATOMS")) + 1
    return [[float(v) for v in ln.split()] for ln in text[start:] if ln.strip()]


def case_np2_cut(r):
    """np 2 = np 1 to round-off for both models with grains on the cut. The text's fitted gradient
    (model yang2016) needs flags forwarded to the halo, else a rank skips the pressure moments of
    nodes only the other rank's grains read (4e-6 relative)."""
    steps = 20
    for gp in ("yang2016", "standard"):
        res = []
        for np_ in (1, 2):
            d = r.fresh(f"np2_cut/{gp}_np{np_}")
            with open(os.path.join(d, "in.script"), "w") as f:
                f.write(CUT.format(model=gp, steps=steps))
            p = r.execute(d, "in.script", np=np_, expect_ok=False, timeout=300)
            check(p.returncode == 0, f"model {gp} np {np_} runs")
            res.append(last_rows(os.path.join(d, "grains.dump")) if p.returncode == 0 else None)
        if None in res:
            continue
        a, b = res
        check(len(a) == len(b) == 5, f"model {gp}: five grains in both runs")
        # scales: the box for positions, the largest velocity component, and for the fluid force
        # the buoyancy rho_f V g of a grain (4.1e-5 N): early in the run the force is a small
        # difference of pressure terms of that size, so its own size would measure cancellation
        scales = {1: 0.04, 4: max(abs(row[c]) for row in a for c in (4, 5, 6)), 7: 1000 * math.pi / 6 * 0.002**3 * 9.81}
        rel = 0.0
        for col in range(1, 10):
            scale = scales[1 + 3 * ((col - 1) // 3)]
            rel = max(rel, max(abs(x[col] - y[col]) for x, y in zip(a, b)) / scale)
        fmax = max(abs(row[c]) for row in a for c in (7, 8, 9))
        print(f"  model {gp}: largest difference np2 vs np1 (x, v, fluid force per grain, relative to box, |v|max, rho_f V g) {rel:.2e}; "
              f"largest fluid force {fmax:.3e} N")
        check(fmax > 0.0 and rel < 1e-12, f"model {gp}: np 2 = np 1 within 1e-12 relative ({rel:.2e})")


def case_density_warning(r):
    """A column hitting the floor at 200 m/s was compressed 220x with no word: one warning (once per
    run) when the density deviates from rho0 by more than 3 % or the largest point pressure exceeds
    5 rho0 (|g| H + |v|max^2), with the figures and the remedies; none for the ordinary column."""
    ex = "neigh_modify exclude type 1 1\nneigh_modify exclude type 1 2"
    fast = COLUMN.format(pre=ex, fixargs="", steps=300).replace("fix grav all gravity 9.81 vector 0 0 -1",
                                                                "velocity all set 0 0 -200 units box")
    fast = fast.replace("timestep 2e-4", "timestep 2e-5")
    d = r.fresh("density_warning/fast")
    p = execute_text(r, d, fast)
    n = p.stdout.count("the weakly compressible fluid is outside its range")
    line = next((ln for ln in p.stdout.splitlines() if "outside its range" in ln), "")
    check(p.returncode == 0 and n == 1, f"fast column: run completes with one warning ({n}: {line.strip()[:200]})")
    check("by more than 3 %" in line and "'bulk' (2e+05)" in line and "pressure projection" in line,
          "the warning names the density deviation, the bulk modulus and the remedies")
    # real water's stiffness, the column set moving at 1 m/s onto the floor: a water hammer of
    # rho c v = 1.5 MPa against the scene's rho0 (g H + v^2) = 3 kPa, the density within 0.1 %
    hammer = COLUMN.format(pre=ex, fixargs="", steps=150).replace("bulk 2e5", "bulk 2.2e9")
    hammer = hammer.replace("fix grav all gravity 9.81 vector 0 0 -1",
                            "fix grav all gravity 9.81 vector 0 0 -1\nvelocity all set 0 0 -1 units box")
    hammer = hammer.replace("timestep 2e-4", "timestep 5e-6")
    d = r.fresh("density_warning/hammer")
    p = execute_text(r, d, hammer)
    line = next((ln for ln in p.stdout.splitlines() if "outside its range" in ln), "")
    check(p.returncode == 0 and "exceeds 5 times the scene's scale" in line and "density left" not in line,
          f"water hammer: one warning naming the pressure against its scale, not the density ({line.strip()[:220]})")
    d = r.fresh("density_warning/calm")
    p = execute_text(r, d, COLUMN.format(pre=ex, fixargs="", steps=200))
    check(p.returncode == 0 and "outside its range" not in p.stdout, "ordinary column: no warning")


def case_group_messages(r):
    """Messages that say what is wrong: grains in the fix's group (not 'fix nve also integrates'),
    atoms of the points' type outside the group, a restart file without the fix's state, and a
    fill that would not fit into memory (an error before creating, screen and log not empty)."""
    r.expect_error("group_messages/grains_in_group",
                   GRAINS.format(fixargs="", d="0.002", steps=1).replace("fix f fluid mpm/fluid", "fix f all mpm/fluid")
                   .replace("couple grains", "").replace("fix nve grains", "fix nve grains"),
                   ("group 'all'", "fill type only"), "grains in the fix's group -> error naming the group")
    r.expect_error("group_messages/shared_type",
                   GRAINS.format(fixargs="", d="0.002", steps=1).replace("create_atoms 2 single 0.012", "create_atoms 1 single 0.012")
                   .replace("group fluid type 1", "group fluid type 1\ngroup stray id 2\ngroup fluid subtract fluid stray")
                   .replace("couple grains", ""),
                   ("type 1", "outside"), "an atom of the points' type outside the group -> error")
    # a restart written with fix ID 'f', read with fix ID 'g': the points have no state of 'g'
    base = GRAINS.format(fixargs="", d="0.002", steps=5) + "write_restart r.bin\n"
    d = r.fresh("group_messages/foreign_restart")
    with open(os.path.join(d, "in.a"), "w") as f:
        f.write(base)
    pa = r.execute(d, "in.a", expect_ok=False, timeout=120)
    check(pa.returncode == 0, "restart file written")
    text = """atom_style sphere
atom_modify map array sort 0 0
newton off
communicate single vel yes
read_restart r.bin
neighbor 0.001 bin
neigh_modify delay 0 every 1 check yes
group fluid type 1
region box block 0 0.04 0 0.04 0 0.04 units box
fix g fluid mpm/fluid cell 0.005 density 1000 pressure eos bulk 1e5 viscosity 1e-3 fill box 1 1 1 type 1
run 1
"""
    with open(os.path.join(d, "in.b"), "w") as f:
        f.write(text)
    p = r.execute(d, "in.b", expect_ok=False, timeout=120)
    err = next((ln for ln in p.stdout.splitlines() if "ERROR" in ln), "")
    check(p.returncode != 0 and "restart file" in err and "not material points" not in err,
          f"restart without the fix's state -> message about the restart file ({err.strip()[:200]})")
    # cell 0.0005 in a 1 m box: 8e9 cells, 2 points per cell = 1.6e10 points, more than any machine's
    # memory and more than LIGGGHTS' int count of a rank's atoms; output redirected to a file
    big = COLUMN.format(pre="", fixargs="", steps=1).replace("region box block 0 0.4 0 0.05 0 0.3", "region box block 0 1 0 1 0 1") \
        .replace("region col block 0 0.1 0 0.05 0 0.2", "region col block 0 1 0 1 0 1").replace("cell 0.025", "cell 0.0005") \
        .replace("fill col 2 2 2", "fill col 2 1 1")
    d = r.fresh("group_messages/too_many_points")
    with open(os.path.join(d, "in.script"), "w") as f:
        f.write(big)
    with open(os.path.join(d, "screen.txt"), "w") as out:
        p = subprocess.run([r.exe, "-in", "in.script", "-echo", "none"], cwd=d, stdout=out, stderr=subprocess.STDOUT, timeout=120)
    screen = open(os.path.join(d, "screen.txt"), errors="replace").read()
    log = open(os.path.join(d, "log.liggghts"), errors="replace").read() if os.path.exists(os.path.join(d, "log.liggghts")) else ""
    err = next((ln for ln in screen.splitlines() if "ERROR" in ln), "")
    check(p.returncode != 0 and "'fill'" in err and "material points" in err and "ERROR" in log,
          f"too many points -> error naming 'fill' and the number, in screen and log ({err.strip()[:200]})")


def case_coupled_restart(r):
    """A coupled run split by write_restart / read_restart equals the uninterrupted run bit for bit
    (no mesh walls; LIGGGHTS restores the grains, the fix its points, its time and the grains'
    last fluid force)."""
    tmpl = CUT.replace("fix grav all gravity", "variable mode index 0\nfix grav all gravity")
    head, tail = tmpl.split("fix grav all gravity", 1)
    body = "fix grav all gravity" + tail.replace("run {steps}", "")
    full = head.replace("variable mode index 0\n", "") + body.format(model="yang2016", steps=100) + "run 200\n"
    d0 = r.fresh("coupled_restart/full")
    p0 = execute_text(r, d0, full)
    first = head.replace("variable mode index 0\n", "") + body.format(model="yang2016", steps=100) + "run 100\nwrite_restart r.bin\n"
    d1 = r.fresh("coupled_restart/split")
    pa = execute_text(r, d1, first)
    second = ("atom_style sphere\natom_modify map array sort 0 0\nnewton off\ncommunicate single vel yes\n"
              "read_restart r.bin\nneighbor 0.001 bin\nneigh_modify delay 0 every 1 check yes\n"
              "group grains type 2\ngroup fluid type 1\n" + body.format(model="yang2016", steps=100)
              .replace("fill box 1 1 1 type 1 ", "").replace("grains.dump", "grains2.dump") + "run 100\n")
    with open(os.path.join(d1, "in.b"), "w") as f:
        f.write(second)
    pb = r.execute(d1, "in.b", expect_ok=False, timeout=300)
    check(p0.returncode == 0 and pa.returncode == 0 and pb.returncode == 0, "the three runs finish")
    if p0.returncode or pa.returncode or pb.returncode:
        return
    a = last_rows(os.path.join(d0, "grains.dump"))
    b = last_rows(os.path.join(d1, "grains2.dump"))
    diff = max(abs(x - y) for ra, rb in zip(a, b) for x, y in zip(ra, rb))
    print(f"  largest difference of grain x, v, fluid force at step 200: {diff:.3e}")
    check(len(a) == len(b) == 5 and a == b, f"split run = uninterrupted run bit for bit (largest difference {diff:.3e})")


def errors_of(p):
    """The ERROR lines of a run's screen."""
    return [ln for ln in p.stdout.splitlines() if "ERROR" in ln]


def case_gate_side(r):
    """A gate at or within round-off of a grid face with the fluid beyond it deleted every point
    (exit 0), a gate whose held side is nearly empty pressed the fluid into a sliver: fluid found
    farther than a cell on the gate's other side at setup is an error naming the gate, the sides
    and the amounts. A gate with the fluid on its held side runs as before."""
    for args, side in (("gate x 1e-300 lower never", "upper"), ("gate x 0.39999999999 upper never", "lower"),
                       ("gate x 0.01 lower never", "upper")):
        p, msg = r.run_script("gate_side/" + args.split()[2], COLUMN.format(pre="", fixargs=args, steps=50))
        check(p.returncode != 0 and "keyword 'gate'" in msg and f"on its {side} side" in msg and "points (mass" in msg,
              f"{args}: error naming the gate, the side and the fluid there (got: {msg.strip()[:220]})")
        check("RESULT" not in p.stdout, f"{args}: no step run")
    d = r.fresh("gate_side/ok")
    p = execute_text(r, d, COLUMN.format(pre="", fixargs="gate x 0.2 lower never", steps=50))
    res = result(p)
    check(p.returncode == 0 and res is not None and res[1] == 512 and res[0] <= 0.2 + 1e-9,
          f"gate x 0.2 lower (fluid at x < 0.1): runs, 512 points, front {res[0] if res else None} <= 0.2")


def case_subcycle_overflow(r):
    """'subcycle yes' with more than 2^31 sub-steps needed (cfl 1e-12) wrapped the count to
    -2147483648 and froze the fluid (exit 0): the count is computed in floating point and refused
    beyond the limit with the usual error."""
    for args, label in (("subcycle yes cfl 1e-12", "eos"), ("pressure projection subcycle yes cfl 1e-15", "projection")):
        text = COLUMN.format(pre="", fixargs=args, steps=5)
        if "projection" in args:
            text = text.replace("bulk 2e5", "")
        p, msg = r.run_script("subcycle_overflow/" + label, text)
        m = re.search(r"would need (\S+) sub-steps", msg)
        check(p.returncode != 0 and m is not None and float(m.group(1)) > 2.0 ** 31,
              f"{label}, {args}: error with the sub-step count > 2^31 (got: {msg.strip()[:200]})")


# sets RLIMIT_FSIZE of the liggghts_mpm process that runs it through 'shell' (its ancestor)
LIMIT_PY = """import os, resource, sys
pid = os.getppid()
while pid > 1:
    with open(f"/proc/{pid}/comm") as f:
        if f.read().strip() == "liggghts_mpm":
            break
    with open(f"/proc/{pid}/stat") as f:
        pid = int(f.read().rsplit(")", 1)[1].split()[1])
n = int(sys.argv[1])
resource.prlimit(pid, resource.RLIMIT_FSIZE, (n, n))
"""


def case_restart_complete(r):
    """On a full disk LIGGGHTS left truncated restart files and exit 0. Restart files are now
    complete or absent: past a file-size limit (set after start-up, the same write failure as a
    full disk: EFBIG instead of ENOSPC) the write_restart command and the restart command stop
    with an error naming the file, in the screen and the log, and leave no file; without the limit
    the same files are written and read back."""
    base = COLUMN.format(pre="", fixargs="", steps=10)
    runs = {"command": base + "write_restart w.bin\n",
            "periodic": base.replace("run 10", "restart 5 r.*\nrestart 3 a.rst b.rst\nrun 10")}
    for label, text in runs.items():
        d = r.fresh(f"restart_complete/{label}_ok")
        p = execute_text(r, d, text)
        names = ["w.bin"] if label == "command" else ["r.5", "r.10", "a.rst", "b.rst"]
        check(p.returncode == 0 and all(os.path.exists(os.path.join(d, n)) for n in names),
              f"{label}: no limit: {names} written (exit {p.returncode})")
        check(sorted(os.listdir(d)) == sorted(names + ["in.script", "log.liggghts", "output.txt"]),
              f"{label}: no other file left ({sorted(os.listdir(d))})")
        back = """atom_style sphere
atom_modify map array sort 0 0
read_restart {}
print "ATOMS $(atoms)"
""".format(names[0])
        with open(os.path.join(d, "in.back"), "w") as f:
            f.write(back)
        pb = r.execute(d, "in.back", expect_ok=False, timeout=60)
        check("ATOMS 512" in pb.stdout, f"{label}: {names[0]} read back with its 512 points")
        d = r.fresh(f"restart_complete/{label}_limit")
        with open(os.path.join(d, "limit.py"), "w") as f:
            f.write(LIMIT_PY)
        limited = text.replace("run 10", f"shell {sys.executable} limit.py 100000\nrun 10")
        p = execute_text(r, d, limited)
        log = open(os.path.join(d, "log.liggghts"), errors="replace").read()
        err = next((ln for ln in p.stdout.splitlines() if "ERROR" in ln), "")
        first = names[0] if label == "command" else "a.rst"
        check(p.returncode != 0 and f"restart file '{first}' could not be written completely" in err
              and "File too large" in err, f"{label}: limit 100000 bytes: error naming the file and the cause ({err.strip()[:200]})")
        check(err.strip() != "" and err.strip() in log, f"{label}: the error is in the log file too")
        left = [n for n in os.listdir(d) if n not in ("in.script", "log.liggghts", "output.txt", "limit.py")]
        check(left == [], f"{label}: limit: no restart file, partial copy or FIFO left ({left})")


def case_mesh_wall_side(r):
    """A mesh wall whose given side is opposite to the fluid froze it (kinetic energy 3e-28, exit
    0): at setup, more points near its faces on the other side than on the given one is an error
    naming the wall, the side and the counts. The right side runs."""
    data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")
    for fside, ok in (("normal", False), ("opposite", True)):
        d = r.fresh(f"mesh_wall_side/{fside}")
        for f in ("in.mesh_walls_box", "box.stl"):
            shutil.copy(os.path.join(data, f), d)
        p = r.execute(d, "in.mesh_walls_box", {"fside": fside, "steps": 20}, expect_ok=False, timeout=120)
        err = next((ln for ln in p.stdout.splitlines() if "ERROR" in ln), "")
        if ok:
            check(p.returncode == 0, f"side {fside} (box.stl normals point out, fluid inside): runs")
        else:
            check(p.returncode != 0 and "fix ID 'walls'" in err and "side normal" in err and "on the other side" in err,
                  f"side {fside}: error naming the wall, the side and the counts ({err.strip()[:240]})")
            m = re.search(r"but (\d+) of the (\d+) material points", err)
            check(m is not None and int(m.group(1)) == int(m.group(2)) > 0,
                  f"side {fside}: all points near the faces are on the other side ({m.groups() if m else None})")


PROJ = COLUMN.replace("bulk 2e5 ", "")


def case_max_iterations(r):
    """max_iterations 2147483647 ended in MPI_ABORT without an ERROR line (hypre sizes its residual
    history by it) and 1000000000 ran no step in 20 s: refused above 1000000 with the range; the
    largest accepted value runs."""
    for v in ("2147483647", "1000000000", "1000001"):
        p, msg = r.run_script(f"max_iterations/{v}", PROJ.format(pre="", fixargs=f"pressure projection max_iterations {v}", steps=5))
        check(p.returncode != 0 and "keyword 'max_iterations' expects an integer in [1, 1000000]" in msg and v in msg,
              f"max_iterations {v}: refused with the range (got: {msg.strip()[:160]})")
    d = r.fresh("max_iterations/1000000")
    p = execute_text(r, d, PROJ.format(pre="", fixargs="pressure projection max_iterations 1000000", steps=5))
    check(p.returncode == 0 and result(p) is not None, "max_iterations 1000000: runs")


def case_lost_messages(r):
    """A LIGGGHTS core error printed only the MPI_ABORT banner when the screen was a pipe or a
    file, and the log stayed empty: every error reaches both (screen to a pipe and to a file;
    an error of LIGGGHTS' error->one, of error->all and of the fix)."""
    scripts = {
        "core_one": "atom_style sphere\nregion box block 0 1 0 1 0 1 units box\ncreate_box 1 box\n"
                    "create_atoms 1 random 10 -5 NULL\n",
        "core_all": "atom_style sphere\nbogus_command 1\n",
        "fix": COLUMN.format(pre="", fixargs="cfl 2", steps=1),
    }
    needles = {"core_one": "random seed", "core_all": "bogus_command", "fix": "keyword 'cfl'"}
    for name, text in scripts.items():
        for mode in ("pipe", "file"):
            d = r.fresh(f"lost_messages/{name}_{mode}")
            with open(os.path.join(d, "in.script"), "w") as f:
                f.write(text)
            cmd = [r.exe, "-in", "in.script", "-echo", "none"]
            if mode == "pipe":
                screen = subprocess.run(cmd, cwd=d, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                        timeout=60).stdout.decode(errors="replace")
            else:
                with open(os.path.join(d, "screen.txt"), "w") as f:
                    subprocess.run(cmd, cwd=d, stdout=f, stderr=subprocess.STDOUT, timeout=60)
                screen = open(os.path.join(d, "screen.txt"), errors="replace").read()
            logp = os.path.join(d, "log.liggghts")
            log = open(logp, errors="replace").read() if os.path.exists(logp) else ""
            s_err = [ln for ln in screen.splitlines() if "ERROR" in ln and needles[name] in ln]
            l_err = [ln for ln in log.splitlines() if "ERROR" in ln and needles[name] in ln]
            check(len(s_err) == 1 and len(l_err) == 1,
                  f"{name}, screen to a {mode}: the error once in the screen ({len(s_err)}) and once in the log ({len(l_err)})")
            extra = joke_lines(screen) + joke_lines(log)
            check(not extra, f"{name}, screen to a {mode}: nothing after the error (got {extra[:2]})")
    # LIGGGHTS appends its joke to one error in five, chosen by rand() seeded with the second: the
    # same error in five different seconds
    for k in range(5):
        time.sleep(1.05)
        d = r.fresh(f"lost_messages/seconds_{k}")
        with open(os.path.join(d, "in.script"), "w") as f:
            f.write(scripts["core_all"])
        screen = subprocess.run([r.exe, "-in", "in.script", "-echo", "none"], cwd=d, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, timeout=60).stdout.decode(errors="replace")
        log = open(os.path.join(d, "log.liggghts"), errors="replace").read()
        extra = joke_lines(screen) + joke_lines(log)
        check(not extra, f"bogus_command, run {k + 1} of 5: nothing after the error (got {extra[:2]})")


def case_screen_none(r):
    """'-screen none' crashed LIGGGHTS 3.8's STL import of fix mesh/surface (a segmentation fault:
    it writes to the screen unconditionally): a mesh scene runs to its end with it, and an error
    reaches the log."""
    data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")
    d = r.fresh("screen_none/mesh")
    for f in ("in.mesh_walls_box", "box.stl"):
        shutil.copy(os.path.join(data, f), d)
    cmd = [r.exe, "-in", "in.mesh_walls_box", "-echo", "none", "-screen", "none", "-log", "log.txt",
           "-var", "fside", "opposite", "-var", "steps", "20"]
    p = subprocess.run(cmd, cwd=d, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)
    log = open(os.path.join(d, "log.txt"), errors="replace").read() if os.path.exists(os.path.join(d, "log.txt")) else ""
    check(p.returncode == 0 and "Loop time of" in log,
          f"mesh scene with -screen none: exit 0 and the run in the log (exit {p.returncode})")
    d = r.fresh("screen_none/error")
    with open(os.path.join(d, "in.script"), "w") as f:
        f.write(COLUMN.format(pre="", fixargs="cfl 2", steps=1))
    p = subprocess.run([r.exe, "-in", "in.script", "-echo", "none", "-screen", "none", "-log", "log.txt"], cwd=d,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60)
    log = open(os.path.join(d, "log.txt"), errors="replace").read() if os.path.exists(os.path.join(d, "log.txt")) else ""
    l_err = [ln for ln in log.splitlines() if "ERROR" in ln and "keyword 'cfl'" in ln]
    check(p.returncode != 0 and len(l_err) == 1, f"error with -screen none: once in the log ({len(l_err)}), exit {p.returncode}")


def case_units(r):
    """An input without 'units si' (LIGGGHTS' default is lj) ran with the fix's SI defaults read in
    other units: refused at the fix command, naming the unit style given; si runs."""
    base = COLUMN.format(pre="", fixargs="", steps=2)
    for style, text in (("lj", base.replace("units si\n", "")), ("cgs", base.replace("units si", "units cgs"))):
        p, msg = r.run_script(f"units/{style}", text)
        check(p.returncode != 0 and "requires 'units si'" in msg and f"'units {style}'" in msg,
              f"units {style}: refused naming 'units si' and the style given (got: {msg.strip()[:200]})")
        check(not re.search(r"^\s+Step\s", p.stdout, re.M), f"units {style}: before any step")
    d = r.fresh("units/si")
    p = execute_text(r, d, base)
    check(p.returncode == 0 and result(p) is not None, "units si: runs")


def case_grain_walls(r):
    """A drum whose mesh walls the beads (fix wall/gran) but was not given to the fluid as a
    mesh_wall ran without a word while the water passed through it: a warning at setup names the
    mesh. None with the mesh_wall given, nor for a mesh on the grid's faces (the grid faces hold the
    water there: tests/data/in.every_bed)."""
    top = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    data = os.path.join(top, "tests", "data")
    drum = open(os.path.join(r.inputs, "drum", "in.drum")).read()
    line = "                mesh_wall drum ${wallkw} ${walla} ${wallb} side opposite &\n"
    check(line in drum, "inputs/drum/in.drum gives the drum to the fluid as a mesh_wall")
    short = {"nbeads": 50, "cells": 16, "ppc": 1, "tdry": 0.002, "tsettle": 0.002, "turns": 0.002, "tsnap": 0}
    needle = "the mesh of fix drum is a wall of the grains (fix wall/gran) but not of the fluid"
    for name, text in (("without", drum.replace(line, "                &\n")), ("with", drum)):
        d = r.fresh(f"grain_walls/drum_{name}")
        with open(os.path.join(d, "in.drum"), "w") as f:
            f.write(text)
        subprocess.run([sys.executable, os.path.join(top, "tools", "make_drum_stl.py"), "drum.stl"], cwd=d,
                       check=True, stdout=subprocess.DEVNULL)
        p = r.execute(d, "in.drum", short, expect_ok=False, timeout=300)
        log = open(os.path.join(d, "log.liggghts"), errors="replace").read()
        n_screen = sum(needle in ln for ln in p.stdout.splitlines() if "WARNING" in ln)
        n_log = sum(needle in ln for ln in log.splitlines() if "WARNING" in ln)
        want = 1 if name == "without" else 0
        check(p.returncode == 0 and n_screen == want and n_log == want,
              f"drum {name} its mesh_wall: runs, the warning naming the mesh {want} time(s) in screen and log "
              f"(screen {n_screen}, log {n_log}, exit {p.returncode})")
    d = r.fresh("grain_walls/every_bed")
    text = open(os.path.join(data, "in.every_bed")).read()
    text = text.replace("variable nsettle equal 20000", "variable nsettle equal 40").replace(
        "variable nmeas  equal 10000", "variable nmeas  equal 40")
    with open(os.path.join(d, "in.every_bed"), "w") as f:
        f.write(text)
    shutil.copy(os.path.join(data, "box.stl"), d)
    p = r.execute(d, "in.every_bed", {}, expect_ok=False, timeout=300)
    check(p.returncode == 0 and "wall of the grains" not in p.stdout,
          f"a mesh box on the grid's faces, walls of the grains only: runs without the warning (exit {p.returncode})")


def case_uncoupled(r):
    """Grains in the water without 'couple' (or outside its group) fell through it as through air
    without a word: a warning at setup gives their count; none with them coupled. The coupled grains
    at rest in water without gravity: no warning at all (the weakly compressible range warning read
    the equation of state's round-off, 2e-11 Pa, against a scene scale of 4e-31 Pa)."""
    base = GRAINS.format(d="0.002", fixargs="", steps=5)
    cases_ = (("coupled", base, None),
              ("no_couple", base.replace(" couple grains", ""), "2 atoms that are no material points"),
              ("subgroup", base.replace("group fluid type 1", "group fluid type 1\ngroup one id 1").replace("couple grains", "couple one"),
               "1 atom that is no material point"))
    for name, text, needle in cases_:
        d = r.fresh(f"uncoupled/{name}")
        p = execute_text(r, d, text)
        warns = [ln for ln in p.stdout.splitlines() if "WARNING" in ln]
        if needle is None:
            check(p.returncode == 0 and not warns, f"{name}: runs without a warning (got {[w[:120] for w in warns]})")
        else:
            hit = [w for w in warns if needle in w and "feel no fluid force" in w]
            check(p.returncode == 0 and len(hit) == 1, f"{name}: one warning with the count ({[w[:160] for w in warns]})")


REST_EOS = cases.PREAMBLE + """region box block 0 0.1 0 0.1 0 0.2 units box
create_box 1 box
neighbor 0.005 bin
neigh_modify delay 0 every 1 check yes
region water block 0 0.1 0 0.1 0 0.1 units box
fix fluid all mpm/fluid cell 0.01 density 1000 pressure eos bulk 2e5 viscosity 1e-3 boundary all freeslip &
    fill water 2 2 2 type 1 hydrostatic z 0.1 9.81 damping 20
fix grav all gravity 9.81 vector 0 0 -1
timestep 1e-4
run 100
run 100
run 0 post no
"""


def case_range_rest(r):
    """The weakly compressible range warning read the pressure scale at each run's setup, where the
    points' forces lack those of fixes set up after fix mpm/fluid (fix gravity after it): water at
    rest in a tank (hydrostatic pressure 980 Pa) warned that its pressure exceeded 5 times a scale of
    a few Pa at the start of every run after the first. No warning now; a column that is in fact
    out of range still warns (reliability_density_warning)."""
    d = r.fresh("range_rest")
    p = execute_text(r, d, REST_EOS)
    warns = [ln for ln in p.stdout.splitlines() if "outside its range" in ln]
    check(p.returncode == 0 and not warns, f"water at rest, three runs: no range warning (got {[w[:160] for w in warns]})")


# fix fa: water in region a; {fb}: optionally a second fluid (SECOND_FLUID, region b)
FLUIDS = cases.PREAMBLE + """region box block 0 0.4 0 0.05 0 0.3 units box
create_box 2 box
neighbor 0.005 bin
neigh_modify delay 0 every 1 check yes
region a block {a} units box
group f1 type 1
group f2 type 2
fix fa f1 mpm/fluid cell 0.025 density 1000 viscosity 1e-3 boundary all freeslip fill a 2 2 2 type 1 {grid}
{fb}
fix grav all gravity 9.81 vector 0 0 -1
timestep 2e-4
run 20
"""
SECOND_FLUID = """region b block {b} 0 0.05 0 0.2 units box
fix fb f2 mpm/fluid cell 0.025 density 800 viscosity 1e-3 boundary all freeslip fill b 2 2 2 type 2 {grid2}"""


def case_two_fluids(r):
    """Two fix mpm/fluid in one box are two fluids that pass through each other (a water column and
    an oil column collapsed through one another without a word): a warning names both fixes when
    their grids overlap, once; none when their grids are apart. The other fluid's points are not
    counted as uncoupled grains."""
    for name, b, grid, grid2, want in (("overlap", "0.05 0.15", "", "", 1),
                                       ("apart", "0.3 0.4", "grid 0 0.2 0 0.05 0 0.3", "grid 0.2 0.4 0 0.05 0 0.3", 0)):
        d = r.fresh(f"two_fluids/{name}")
        p = execute_text(r, d, FLUIDS.format(a="0 0.1 0 0.05 0 0.2", grid=grid, fb=SECOND_FLUID.format(b=b, grid2=grid2)))
        warns = [ln for ln in p.stdout.splitlines() if "WARNING" in ln]
        hit = [w for w in warns if "the grids of fix fa and fix fb overlap" in w]
        check(p.returncode == 0 and len(hit) == want and len(warns) == want,
              f"{name}: {want} warning(s) naming both fixes, no other (got {[w[:140] for w in warns]}, exit {p.returncode})")


def case_fill_beyond(r):
    """A fill region reaching beyond the grid was cut at the grid's face without a word (a column
    0.3 m long in a grid 0.2 m long held 2 kg of water, not 3): a warning names the region, the axis
    and both extents. None for a region with an unbounded side (INF) or inside the grid."""
    for name, region, want in (("beyond", "0 0.3 0 0.05 0 0.2", 1), ("inf", "INF INF INF INF INF 0.2", 0), ("inside", "0 0.1 0 0.05 0 0.2", 0)):
        d = r.fresh(f"fill_beyond/{name}")
        p = execute_text(r, d, FLUIDS.format(a=region, grid="grid 0 0.2 0 0.05 0 0.3", fb=""))
        warns = [ln for ln in p.stdout.splitlines() if "WARNING" in ln]
        hit = [w for w in warns if "the fill region 'a' reaches beyond the grid along x" in w and "0 .. 0.3 m" in w]
        check(p.returncode == 0 and len(hit) == want and len(warns) == want,
              f"region {region}: {want} warning(s) naming the region, the axis and the extents (got {[w[:150] for w in warns]}, exit {p.returncode})")


def joke_lines(text):
    """Lines that LIGGGHTS' error->all or error->one print after the ERROR line when its version
    string says PUBLIC: a 'comment from the off' or a 'tip of the day', read from a destroyed
    std::string, so often bytes that are no text at all (any character outside printable ASCII
    counts: the runs here print none)."""
    return [ln for ln in text.splitlines()
            if "Comment from the off" in ln or "Tip of the day" in ln
            or any(not (32 <= ord(c) < 127 or c == "\t") for c in ln)]


GRAINS_PROJ = GRAINS.replace("bulk 1e5 ", "")


def case_late_errors(r):
    """Values that failed late (inside hypre at step 1, 'fluid state is not finite', 'reduce the
    timestep') or with a bare 'Illegal fix_modify command': refused at the command, naming the
    keyword and its range, before any step."""
    cases = [
        ("density_projection", PROJ.format(pre="", fixargs="pressure projection", steps=5).replace("density 1000", "density 1e308"),
         ("keyword 'density'", "[1e-150, 1e150]")),
        ("viscosity_couple", GRAINS_PROJ.format(fixargs="pressure projection", d="0.002", steps=5).replace("viscosity 1e-3", "viscosity 1e308"),
         ("'viscosity'", "normal number")),
        ("pmin", COLUMN.format(pre="", fixargs="pmin 1e300", steps=5), ("keyword 'pmin'", "<= 0")),
        ("tait", COLUMN.format(pre="", fixargs="eos tait 1e300", steps=5), ("keyword 'eos'", "twice the reference density")),
    ]
    for word in ("tolerance 1e-3", "cell 0.05", "pressure projection", "mesh_wall w freeslip", "couple all", "colour red"):
        kw = word.split()[0]
        text = COLUMN.format(pre="", fixargs="", steps=5).replace("run 5", f"fix_modify fluid {word}\nrun 5")
        cases.append(("fix_modify_" + kw, text, (f"'{kw}'", "fix_modify", "it changes", "damping", "cfl")))
    for name, text, needles in cases:
        p, msg = r.run_script("late_errors/" + name, text)
        check(p.returncode != 0 and all(n in msg for n in needles), f"{name}: refused naming {needles} (got: {msg.strip()[:200]})")
        check(not re.search(r"^\s+Step\s", p.stdout, re.M), f"{name}: before any step")


def case_inert_keywords(r):
    """Keywords that another choice makes inert, or values that make them do nothing, were
    accepted silently: each is an error naming the keyword and why, in the fix command and
    through fix_modify. The same keywords where they act are accepted."""
    base = COLUMN.format(pre="", fixargs="{x}", steps=2)
    cases = [
        ("height", base.replace("{x}", "height z x -1"), ("keyword 'height'", "inside the grid")),
        ("output", base.replace("{x}", "output 10 name points"), ("keyword 'output'", "at least one field")),
        ("drag", base.replace("{x}", "drag stokes"), ("keyword 'drag'", "'couple'")),
        ("theta_smooth", base.replace("{x}", "theta_smooth 0.01"), ("keyword 'theta_smooth'", "'couple'")),
        ("theta_min", base.replace("{x}", "theta_min 0.5"), ("keyword 'theta_min'", "'couple'")),
        ("cell_check", base.replace("{x}", "cell_check no"), ("keyword 'cell_check'", "'couple'")),
        ("shear", base.replace("{x}", "boundary xlo shear 0.001").replace("viscosity 1e-3 ", ""),
         ("keyword 'boundary'", "viscosity")),
        ("fix_modify_cell_check", base.replace("{x}", "").replace("run 2", "fix_modify fluid cell_check yes\nrun 2"),
         ("fix_modify keyword 'cell_check'", "'couple'")),
    ]
    for name, text, needles in cases:
        p, msg = r.run_script("inert/" + name, text)
        check(p.returncode != 0 and all(n in msg for n in needles), f"{name}: error naming {needles} (got: {msg.strip()[:200]})")
    ok = GRAINS.format(fixargs="drag stokes theta_smooth 0.005 theta_min 0.4 cell_check yes output 2 o points v",
                       d="0.002", steps=2) + "fix_modify f cell_check no\nrun 2\n"
    d = r.fresh("inert/coupled_ok")
    p = execute_text(r, d, ok)
    check(p.returncode == 0, f"with couple: drag, theta_smooth, theta_min, cell_check, fix_modify cell_check accepted (exit {p.returncode})")


def case_fuzz_quick(r):
    """The reduced form of tools/fuzz_mpm_fluid.py: a sample of bad values for every keyword of
    fix mpm/fluid and fix balance/mpm (and through fix_modify): no crash, no hang, no silent
    acceptance, every error naming the keyword."""
    tool = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "fuzz_mpm_fluid.py")
    d = r.fresh("fuzz_quick")
    p = subprocess.run([sys.executable, tool, "--exe", r.exe, "--work", d, "--quick"], stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True, errors="replace", timeout=600)
    print(p.stdout[-3000:])
    m = re.search(r"cases (\d+) named (\d+) unnamed (\d+) crashes (\d+) hangs (\d+) silent (\d+)", p.stdout)
    check(m is not None and int(m.group(1)) > 100, f"fuzz: summary line with more than 100 cases ({m.group(0) if m else None})")
    if m:
        n, named, unnamed, crash, hang, silent = map(int, m.groups())
        check(crash == 0 and hang == 0 and silent == 0 and unnamed == 0 and named == n,
              f"fuzz: every case an error naming its keyword ({m.group(0)})")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
