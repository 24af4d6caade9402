#!/usr/bin/env python3
"""The figures of docs/validation/model_table.md: each example input of the fluid and coupled cases run with
the fix's defaults (`pressure projection`) and with `pressure eos` (the input's bulk), measured
against the case's reference (CASES.md), with the wall time of each run.

    tools/python tools/model_table.py ROW [ROW ...] [--exe build/liggghts_mpm] [--work /tmp/model_table]
                                         [--models projection eos] [--json rows.jsonl]

ROW: f1 f2 f3 f4 c1 c1var (C1 with the fluid damped while the grain is held) c2 c5 c5wall c5tilt
c6 porewave transfer (the coupled rows again with transfer apic) damping (C5 undamped while settling,
C6 damped while held) f3var (F3 with the other transfer) f3fine (F3 at Grid80) f4fine (F4 at 80 cells) fluidapic (F2 MPM32, F4 with transfer apic),
c3 (C3 tank, quick size, 0.26 s) c3full (C3 at full size) c4 (C4 jar, full size, C4_TURNS turns, default 1) starter (quick and default size), or all. Each run prints one line: row, model, settings, figures, wall time (s).
"""
import argparse
import inspect
import json
import math
import os
import re
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(TOP, "tests", "cases"))
sys.path.insert(0, HERE)
import cases  # noqa: E402
from cases import pressure_errors, read_csv, rms_vs_martin_moyce, schiller_naumann_settling  # noqa: E402

OUT = []


class Args:
    pass


def runner(a):
    ns = Args()
    ns.exe, ns.inputs, ns.work, ns.mpirun = a.exe, os.path.join(TOP, "inputs"), a.work, "mpirun"
    return cases.Runner(ns)


def timed(r, case, inp, v):
    t0 = time.time()
    d, p = r.run(case, os.path.join(r.inputs, inp), v)
    return d, p, time.time() - t0


def emit(row, model, settings, figs, wall):
    rec = {"row": row, "model": model, "settings": settings, "figures": figs, "wall_s": round(wall, 1)}
    OUT.append(rec)
    f = ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in figs.items())
    print(f"{row} | {model} | {settings} | {f} | {wall:.1f} s", flush=True)


def row_f1(r, models, cells=16, undamped=True):
    """F1 hydrostatic column, `cells` cells (16), 0.4 s (eos: its damping 20 1/s; also without, if undamped)."""
    for m in models:
        runs = [("", {})] + ([("no damping", {"extra": "damping 0"})] if m == "eos" and undamped else [])
        for label, v in runs:
            d, p, w = timed(r, f"f1/{m}_c{cells}{label.replace(' ', '_')}", "hydrostatic/in.hydrostatic",
                            dict({"cells": cells, "pressure": m}, **v))
            e_all, e_in, s = pressure_errors(d)
            emit("F1", m, f"cells {cells}, 0.4 s" + (", " + label if label else ""),
                 {"L2_all": e_all, "L2_interior": e_in, "mass_exact": s["mass"][0] == s["mass0"][0],
                  "crossings": int(s["crossings"][0]), "ke_end_J": s["ke"][0]}, w)


def row_f2(r, models, cells=(16, 32), extra=""):
    """F2 dam break, no-slip floor, to T = 3, RMS front and height errors against Martin & Moyce."""
    for m in models:
        for c in cells:
            v = {"cells": c, "pressure": m, "tend": 3.0}
            if extra:
                v["extra"] = extra
            d, p, w = timed(r, f"f2/{m}_c{c}{extra.replace(' ', '_')}", "dambreak/in.dambreak", v)
            ef, eh = rms_vs_martin_moyce(os.path.join(d, "front.csv"))
            s = read_csv(os.path.join(d, "summary.csv"))
            emit("F2", m, f"MPM{c}, no-slip floor, T = 3" + (", " + extra if extra else ""), {"front_rms_a": ef, "height_rms_a": eh,
                                                             "mass_exact": s["mass"][0] == s["mass0"][0]}, w)


def row_f3(r, models, cells=(20, 40), extra="", dt=None):
    """F3 released column (free-slip walls): kinetic energy / inviscid at 0.01 and 0.02 s.
    dt: {model: time step} where the input's automatic step does not hold (None: the input's)."""
    from test_projection import inviscid_column_ke_rate
    rate = inviscid_column_ke_rate(0.05, 0.1, 0.1)
    for m in models:
        for c in cells:
            v = {"cells": c, "pressure": m, "wallkind": "freeslip"}
            if extra:
                v["extra"] = extra
            if dt and m in dt:
                v["dt"] = dt[m]
            d, p, w = timed(r, f"f3/{m}_g{c}{extra.replace(' ', '_')}", "tank/in.column", v)
            s = read_csv(os.path.join(d, "column.csv"))
            f = {}
            for t in (0.01, 0.02):
                i = min(range(len(s["t"])), key=lambda j: abs(s["t"][j] - t))
                f[f"ke_ratio_{t}s"] = s["ke"][i] / (rate * s["t"][i] ** 2)
            f["ke_0.01s_J"] = rate * 0.01 ** 2
            emit("F3", m, f"Grid{c}, free-slip" + (", " + extra if extra else ""), f, w)


def row_f4(r, models, cells=(20, 40), extra=""):
    """F4 standing wave (in.wave, h 0.25, L 1, amplitude 2 % h, three periods)."""
    import sloshing
    for m in models:
        for c in cells:
            v = {"cells": c, "pressure": m}
            if extra:
                v["extra"] = extra
            d, p, w = timed(r, f"f4/{m}_c{c}{extra.replace(' ', '_')}", "sloshing/in.wave", v)
            f = sloshing.fit(os.path.join(d, "wave.csv"))
            emit("F4", m, f"{c} cells, 3 periods" + (", " + extra if extra else ""), {"w_ratio": f["w_ratio"], "amp_end_ratio": f["amp_ratio_end"],
                                                   "amp0_ratio": f["b_ratio"]}, w)


def row_c1(r, models, extra="", **more):
    """C1 one sphere settling: terminal velocity against Schiller-Naumann."""
    for m in models:
        v = dict({"pressure": m}, **more)
        if extra:
            v["extra"] = extra
        tag = extra + "".join(f" {k} {x}" for k, x in more.items())
        d, p, w = timed(r, f"c1/{m}{tag.replace(' ', '_')}", "settling/in.settling", v)
        sim = read_csv(os.path.join(d, "settling.csv"))
        curve, vt = schiller_naumann_settling(1e-4, 3000.0, 10.0, 1e-5, 9.81, sim["t"][-1])
        vs = [-x for x in sim["v_z"]]
        tc, vc = [c[0] for c in curve], [c[1] for c in curve]
        dev = max(abs(x - cases.interp(t, tc, vc)) for t, x in zip(sim["t"], vs)) / vt
        emit("C1", m, f"d 0.1 mm, cell {1e3 * more.get('cell', 3e-3):g} mm, 0.1 s" + (", " + tag.strip() if tag else ""),
             {"vt_ratio": vs[-1] / vt, "vt_SN": vt, "curve_dev_vt": dev,
              "end_over_curve": vs[-1] / cases.interp(sim["t"][-1], tc, vc)}, w)


def row_c2(r, models):
    """C2 Ergun: periodic simple-cubic bed driven by dp/L; U reached against Ergun."""
    eps, mu, d, rho = 1.0 - math.pi / 6.0, 1.5e-3, 1e-3, 10.0
    A = 150.0 * (1 - eps) ** 2 / eps ** 3 * mu / d ** 2
    B = 1.75 * (1 - eps) / eps ** 3 * rho / d
    for m in models:
        for U in (0.002, 0.02):
            G = A * U + B * U * U
            dd, p, w = timed(r, f"c2/{m}_U{U}", "ergun/in.ergun", {"G": G, "pressure": m})
            f = read_csv(os.path.join(dd, "ergun.csv"))
            Us = f["U"][-1]
            emit("C2", m, f"U {U} m/s", {"dp_rel_err": (A * Us + B * Us * Us) / G - 1.0}, w)


def bed(r, case, **v):
    base = {"nbeads": 150, "tsettle": 0.05, "tavg": 0.01}
    d, p, w = timed(r, case, "archimedes/in.bed", dict(base, **v))
    m = re.search(r"RESULT ratio (\S+) grains (\S+).* side (\S+)", p.stdout)
    return float(m.group(1)), int(float(m.group(2))), float(m.group(3)), w


def row_c5(r, models, extra="", **more):
    """C5 random held bed (150 grains of 2 mm, phi 0.3, cell 1.5 d): mid-depth and on the floor."""
    for m in models:
        for where, fl in (("mid-depth", 0), ("floor", 1)):
            v = dict({"pressure": m, "floor": fl}, **more)
            if extra:
                v["extra"] = extra
            tag = extra + "".join(f" {k} {x}" for k, x in more.items())
            q, n, side, w = bed(r, f"c5/{m}_{fl}{tag.replace(' ', '_')}", **v)
            emit("C5", m, f"{where}, cell {more.get('cellf', 1.5):g} d, {n} grains" + (", " + tag.strip() if tag else ""),
                 {"archimedes_ratio": q}, w)


def row_c5wall(r, models, extra=""):
    """C5 beside a plane mesh wall (meshwall 1), cell 1.5 d, mid-depth; sideways force from the log."""
    for m in models:
        for cellf in (1.5, 3):
            v = {"pressure": m, "meshwall": 1, "cellf": cellf}
            if cellf == 3:
                v["nbeads"] = 600
            if extra:
                v["extra"] = extra
            q, n, side, w = bed(r, f"c5wall/{m}_c{cellf}{extra.replace(' ', '_')}", **v)
            emit("C5 mesh wall", m, f"plane mesh wall, cell {cellf} d, {n} grains" + (", " + extra if extra else ""),
                 {"archimedes_ratio": q, "side_over_buoyancy": side}, w)


def row_c5tilt(r, models):
    """C5 beside a mesh wall inclined 20 degrees over the water (meshwall 1, tilt 20), mid-depth."""
    for m in models:
        for cellf in (1.5, 3):
            v = {"pressure": m, "meshwall": 1, "tilt": 20, "cellf": cellf}
            if cellf == 3:
                v["nbeads"] = 600
            q, n, side, w = bed(r, f"c5tilt/{m}_c{cellf}", **v)
            emit("C5 inclined mesh wall", m, f"mesh wall inclined 20 deg, cell {cellf} d, {n} grains",
                 {"archimedes_ratio": q, "side_over_buoyancy": side}, w)


def row_c6(r, models, extra="", phis=(0.1, 0.2, 0.3), **more):
    """C6 hindered settling (reduced: 4 x 4 x 12 cells of 2 mm, 0.15 s): v / reference (tools/suspension.py)."""
    import suspension
    for m in models:
        for phi in phis:
            v = dict({"nxy": 4, "nsus": 12, "tend": 0.15, "phi": phi, "pressure": m}, **more)
            if extra:
                v["extra"] = extra
            tag = extra + "".join(f" {k} {x}" for k, x in more.items())
            d, p, w = timed(r, f"c6/{m}_{phi}{tag.replace(' ', '_')}", "suspension/in.suspension", v)
            info = suspension.result_line(p.stdout)
            csv = os.path.join(d, "suspension.csv")
            res = suspension.analyse(csv, 1.0, t1=0.08)
            ph = suspension.phi_mid(res, info)
            vref = suspension.reference(ph)[0]
            res = suspension.analyse(csv, vref, t1=0.08)
            emit("C6", m, f"phi {phi} (middle {ph:.3f}), reduced" + (", " + tag.strip() if tag else ""),
                 {"v_ratio": res["ratio"], "ringing": res["ring"], "p_ringing": res["pring"]}, w)


def row_porewave(r, models):
    """Pore-pressure wave: a dense free lattice perturbed at random, dt 1e-5, 1000 steps: decays?"""
    for m in models:
        d, p, w = timed(r, f"porewave/{m}", "porewave/in.porewave", {"pressure": m, "nsteps": 1000, "nout": 50,
                                                                      "dt": 1e-5})
        c = read_csv(os.path.join(d, "porewave.csv"))
        amp = [max(abs(a), abs(b)) for a, b in zip(c["pmax"], c["pmin"])]
        late = max(amp[3 * len(amp) // 4:])
        emit("porewave", m, "random displacement 1e-5 m, dt 1e-5, 1000 steps",
             {"p_max_Pa": max(amp), "p_last_quarter_Pa": late, "grain_ke_max_J": max(c["keg"])}, w)
        d, p, w = timed(r, f"porewave/{m}_wave", "porewave/in.porewave",
                        {"pressure": m, "nsteps": 1000, "nout": 50, "dt": 1e-5, "amp": 0.01, "lam": 0.02, "disp": 0.0})
        c = read_csv(os.path.join(d, "porewave.csv"))
        amp = [max(abs(a), abs(b)) for a, b in zip(c["pmax"], c["pmin"])]
        emit("porewave", m, "grain velocity wave 0.01 m/s, wavelength 0.02 m, dt 1e-5, 1000 steps",
             {"p_max_Pa": max(amp), "grain_ke_end_over_max": c["keg"][-1] / max(c["keg"]),
              "grain_ke_max_J": max(c["keg"])}, w)


def row_c1var(r, models):
    """C1 with the fluid damped (100 1/s) while the grain is held, flip and apic."""
    row_c1(r, models, damp=100.0)
    row_c1(r, models, extra="transfer apic", damp=100.0)


def row_damping(r, models):
    """C5 without the damping while settling (in.bed damps with eos), C6 (phi 0.3) with 200 1/s."""
    row_c5(r, models, damp=0.0)
    row_c6(r, models, phis=(0.3,), damp=200.0)


def row_f4fine(r, models):
    """F4 at 80 cells along the tank."""
    row_f4(r, models, cells=(80,))


def row_fluidapic(r, models):
    """F2 MPM32 and F4 (20, 40 cells) with transfer apic instead of the default flip 1."""
    row_f4(r, models, extra="transfer apic")
    row_f2(r, models, cells=(32,), extra="transfer apic")


def row_f3fine(r, models):
    """F3 at Grid80 (256,000 points) with both transfers; eos at 8e-6 s, under its acoustic limit
    8.43e-6 s there (the input's 1e-5 s is refused)."""
    row_f3(r, models, cells=(80,), dt={"eos": 8e-6})
    row_f3(r, [m for m in models if m == "projection"], cells=(80,), extra="transfer flip 1")


def row_f3var(r, models):
    """F3 with the other transfer: flip 1 for the projection (in.column sets apic), apic for eos."""
    other = {"projection": "transfer flip 1", "eos": "transfer apic"}
    for m in models:
        row_f3(r, [m], extra=other[m])


def row_transfer(r, models):
    """The coupled rows with transfer apic instead of the default flip 1."""
    row_c1(r, models, extra="transfer apic")
    row_c5(r, models, extra="transfer apic")
    row_c6(r, models, extra="transfer apic", phis=(0.3,))


def row_c3(r, models, extra="", quick=True):
    """C3 tank, quick size (Grid20, 1 point per cell, 2000 beads; quick=False: the input's full size,
    Grid40 x 8 points, 7762 beads) to 0.26 s after the start of the lift
    (past the water's impact on the far wall), fronts.csv every 2 ms: the time the water reaches
    0.19 m, the fronts at 0.05-0.2 s, the largest point pressure against rho g h + rho U_gate^2, the
    highest bead against the highest water point, the fluid mass."""
    bound = 1000.0 * 9.81 * 0.1 + 1000.0 * 0.68 ** 2
    size = "quick (Grid20 x 1, 2000 beads)" if quick else "full size (Grid40 x 8, 7762 beads)"
    for m in models:
        v = {"quick": 1 if quick else 0, "tend": 0.26, "tfront": 0.002, "pressure": m}
        if extra:
            v["extra"] = extra  # after the input's own keywords: a repeated one (e.g. every) takes this value
        d, p, w = timed(r, f"c3{'' if quick else 'full'}/{m}{extra.replace(' ', '_')}", "tank/in.tank", v)
        f = read_csv(os.path.join(d, "fronts.csv"))
        t = f["t"]

        def at(k, tt):
            return f[k][min(range(len(t)), key=lambda j: abs(t[j] - tt))]
        reach = next((t[i] for i in range(len(t)) if f["x_water"][i] >= 0.19), float("nan"))
        gap = max(zb - zw for zb, zw in zip(f["z_beads"], f["z_water"]))
        figs = {"t_water_0.19m_s": reach}
        for tt in (0.05, 0.1, 0.15, 0.2):
            figs[f"x_water_{tt}s"] = at("x_water", tt)
            figs[f"x_beads_{tt}s"] = at("x_beads", tt)
        figs.update({"pmax_over_rhogh_rhoU2": max(f["pmax"]) / bound, "bead_above_water_mm": 1e3 * gap,
                     "v_beads_max": max(f["v_beads"]), "v_water_max": max(f["v_water"]),
                     "bed_rise_to_0.2s_mm": 1e3 * (max(z for z, tt in zip(f["z_beads"], t) if tt <= 0.2 + 1e-9)
                                                   - f["z_beads"][0]),
                     "mass_exact": max(f["mass"]) == min(f["mass"])})
        emit("C3", m, size + ", 0.26 s" + (f", {extra}" if extra else ""), figs, w)


def row_c3full(r, models):
    """C3 at the input's full size (about 20 minutes of one core with the projection)."""
    row_c3(r, models, quick=False)


def row_c4(r, models, turns=float(os.environ.get("C4_TURNS", "1"))):
    """C4 jar, full size (7755 beads, cells 18 x 1 point), C4_TURNS turns (default 1), dumps every
    0.05 s: bed altitude (tools/jar_altitude.py, from turn 0.3) against 62.18 +- 1.71 mm, the fluid
    mass, the largest point pressure from turn 0.3 against rho g D + rho (omega R)^2."""
    import shutil
    import subprocess
    import numpy as np
    import jar_altitude
    omega_r = 2.0 * math.pi * 104.0 / 60.0 * 0.05
    bound = 1000.0 * 9.81 * 0.1 + 1000.0 * omega_r ** 2
    for m in models:
        d = r.fresh(f"c4/{m}")
        shutil.copy(os.path.join(r.inputs, "jar", "in.jar"), d)
        subprocess.run([sys.executable, os.path.join(HERE, "make_jar_stl.py"), "jar.stl", "--axis", "y",
                        "--centre", "0.05", "0.05", "0.05"], cwd=d, check=True, stdout=subprocess.DEVNULL)
        t0 = time.time()
        r.execute(d, "in.jar", {"pressure": m, "turns": turns, "tsnap": 0.05, "trestart": 0}, timeout=86400)
        w = time.time() - t0
        info, rows = jar_altitude.analyse(d, 3, 1.2)
        alt = np.array([a for (t, tu, a, z, n) in rows if tu >= 0.3])
        c = read_csv(os.path.join(d, "jar.csv"))
        p = [x for x, tu in zip(c["pmax"], c["turn"]) if tu >= 0.3]
        emit("C4", m, f"7755 beads, cells 18 x 1, {turns} turns",
             {"altitude_mm": float(alt.mean()) if len(alt) else float("nan"),
              "altitude_std_mm": float(alt.std()) if len(alt) else float("nan"), "dumps": len(alt),
              "pmax_median_Pa": float(np.median(p)) if p else float("nan"), "pmax_Pa": max(p) if p else float("nan"),
              "pmax_over_rhogD_rhowR2": (max(p) / bound) if p else float("nan"),
              "mass_exact": max(c["mass"]) == min(c["mass"]), "mass_kg": c["mass"][0]}, w)


def row_starter(r, models):
    """Starter scene, quick (300 beads, cell 10 mm) and default size (800 beads, cell 5 mm): the
    largest point pressure against rho g h + rho U^2, U = sqrt(2 g h) of the 0.06 m column. The starter
    input runs the fix's defaults and `every auto` only (no eos branch): other models are skipped."""
    sys.path.insert(0, os.path.join(TOP, "tests", "cases"))
    from test_starter import thermo_blocks
    bound = 1000.0 * 9.81 * 0.06 * 3.0
    for m in models:
        if m != "projection":
            print(f"starter | {m} | skipped: in.pour_and_collapse runs the fix's defaults only", flush=True)
            continue
        for size, v in (("quick", {"quick": 1}), ("default size", {})):
            d, p, w = timed(r, f"starter/{size.split()[0]}", "starter/in.pour_and_collapse", v)
            b = thermo_blocks(p.stdout)
            pm = max(row[h.index("fluid[10")] for h, rows in b[1:] for row in rows)
            mass = [row[h.index("fluid[1]")] for h, rows in b[1:] for row in rows]
            fh, fl = b[2]
            emit("starter", m, size, {"pmax_Pa": pm, "pmax_over_rhogh_rhoU2": pm / bound,
                                      "front_end_m": fl[-1][fh.index("fluid[4]")],
                                      "mass_exact": max(mass) == min(mass)}, w)


ROWS = {"f1": row_f1, "f2": row_f2, "f3": row_f3, "f4": row_f4, "c1": row_c1, "c2": row_c2, "c5": row_c5,
        "c5wall": row_c5wall, "c1var": row_c1var, "damping": row_damping, "f3var": row_f3var, "f3fine": row_f3fine, "f4fine": row_f4fine, "fluidapic": row_fluidapic, "c5tilt": row_c5tilt, "c6": row_c6, "porewave": row_porewave, "transfer": row_transfer,
        "c3": row_c3, "c3full": row_c3full, "c4": row_c4, "starter": row_starter}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("rows", nargs="+")
    ap.add_argument("--exe", default=os.path.join(TOP, "build", "liggghts_mpm"))
    ap.add_argument("--work", default="/tmp/model_table")
    ap.add_argument("--models", nargs="+", default=["projection", "eos"])
    ap.add_argument("--json", default=None, help="append one JSON line per run to this file")
    ap.add_argument("--extra", default="", help="more fix mpm/fluid keywords for the rows that take them "
                    "(c1, c5, ...: their function has an 'extra' argument), e.g. 'every auto'")
    a = ap.parse_args()
    a.exe, a.work = os.path.abspath(a.exe), os.path.abspath(a.work)
    r = runner(a)
    names = sorted(ROWS) if a.rows == ["all"] else a.rows
    for n in names:
        if a.extra and "extra" not in inspect.signature(ROWS[n]).parameters:
            sys.exit(f"model_table.py: row {n} takes no --extra keywords")
        ROWS[n](r, a.models, **({"extra": a.extra} if a.extra else {}))
    if a.json:
        with open(a.json, "a") as f:
            for rec in OUT:
                f.write(json.dumps(rec) + "\n")


if __name__ == "__main__":
    main()
