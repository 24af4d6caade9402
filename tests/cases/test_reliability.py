#!/usr/bin/env python3
"""Inputs that once gave silent wrong results, crashes or unhelpful messages (issue #15), each as a
case that must now either run correctly or stop with a message naming the keyword or quantity.

    test_reliability.py CASE --exe build/liggghts_mpm --inputs inputs --work DIR --mpirun "mpirun ..."
"""
import math
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import check, driver_main, read_csv  # noqa: E402

# A water column on the floor of a box; grains of type 2 may be added; granular contacts between
# grains (pair gran); {pre} before the fix (exclusion lines), {fixargs} more keywords.
COLUMN = """atom_style sphere
atom_modify map array sort 0 0
boundary f f f
newton off
communicate single vel yes
units si
region box block 0 0.4 0 0.05 0 0.3 units box
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
GRAINS = """atom_style sphere
atom_modify map array sort 0 0
boundary f f f
newton off
communicate single vel yes
units si
region box block 0 0.04 0 0.04 0 0.04 units box
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
# under gravity; {gradp}: the coupling option; per-grain position, velocity and fluid force dumped.
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
    full = head.replace("variable mode index 0\n", "") + body.format(gradp="fit", steps=100) + "run 200\n"
    d0 = r.fresh("coupled_restart/full")
    p0 = execute_text(r, d0, full)
    first = head.replace("variable mode index 0\n", "") + body.format(gradp="fit", steps=100) + "run 100\nwrite_restart r.bin\n"
    d1 = r.fresh("coupled_restart/split")
    pa = execute_text(r, d1, first)
    second = ("atom_style sphere\natom_modify map array sort 0 0\nnewton off\ncommunicate single vel yes\n"
              "read_restart r.bin\nneighbor 0.001 bin\nneigh_modify delay 0 every 1 check yes\n"
              "group grains type 2\ngroup fluid type 1\n" + body.format(gradp="fit", steps=100)
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


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
