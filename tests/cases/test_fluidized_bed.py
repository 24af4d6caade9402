#!/usr/bin/env python3
"""The fluidized bed of C8 at reduced size (inputs/fluidized_bed/in.fluidized_bed,
docs/validation/fluidized_bed.md; analysis by tools/fluidized_bed.py).

    test_fluidized_bed.py quick --exe build/liggghts_mpm --inputs inputs --work DIR

quick: a bed 20 mm high (about 480 beads of 3 mm) in a box 60 mm tall, two stages: U = 0.02 m/s
(below Wen-Yu's U_mf = 0.0327 m/s: a fixed bed) and U = 0.05 m/s (fluidized). Checks, each a bound
computed from the inputs and the bed at rest alone:
  * the water's superficial velocity equals the target at every output (round-off) and its mass is
    the same number throughout;
  * fixed bed: the bed does not expand (height within 1 %) and dP lies between 0.7 and 1 times
    Ergun at the bed's voidage at rest: the coupling's fluid fraction is a field filtered over about
    a cell, which at the bed's top and bottom spreads the beads' volume into the clear water and
    lowers the drag of a bed a few cells high (measured 0.81 here, 0.88 to 0.96 at the example's size;
    docs/validation/fluidized_bed.md, "The fixed bed below Ergun");
  * the water's momentum along the flow: at every output of a held target G V_box = M_f g + F_beads
    (the drive carries the water's weight and the force it gives the beads) to 1e-9 of the buoyant
    weight;
  * fluidized: the bed has lifted (height above 1.05 H0) and dP over the second half of the stage
    lies between 0.85 and 1.02 times the beads' buoyant weight per area: not above it (the
    distributor can only push the beads up), and below it by the share of the weight that the
    bottom layer of beads, which stays on the distributor for the same reason, rests there
    (measured 0.90, the distributor's share 0.10 by the balance above).
"""
import os
import shutil
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools"))
from cases import check, driver_main, read_csv  # noqa: E402
import fluidized_bed as fb  # noqa: E402

QUICK = {"Ulist": "0.02 0.05", "thold": 0.6, "cellf": 2.0, "nxy": 3, "nz": 10, "H0": 0.03, "tsettle": 0.2}


def case_quick(r):
    work = r.fresh("fluidized_bed/quick")
    fb.run(r.exe, work, list(QUICK.items()))
    res = fb.analyse(work)
    cols = read_csv(os.path.join(work, "fluidized_bed.csv"))
    flux = max(abs(u - t) / t for u, t in zip(cols["U"], cols["Ut"]))
    check(flux < 1e-12, f"superficial velocity = target at every output ({flux:.1e})")
    check(all(m == cols["mass"][0] for m in cols["mass"]), "water mass the same number at every output")
    st = res["stages"]
    check(len(st) == 2, f"two stages ({len(st)})")
    if len(st) != 2:
        return
    W, H0 = res["W"], res["H0"]
    lo, hi = st
    p = res["inputs"]
    erg = fb.ergun_dp(lo["U"], res["eps0"], H0, p["d"], p["rho"], p["mu"])
    print(f"  U = {lo['U']}: H/H0 = {lo['H'] / H0:.4f}, dP = {lo['dP']:.2f} Pa, Ergun at eps0 {erg:.2f} Pa "
          f"({lo['dP'] / erg - 1:+.3f}); U = {hi['U']}: H/H0 = {hi['H'] / H0:.4f}, dP / (W/A) = {hi['dP'] / W:.4f}")
    check(abs(lo["H"] / H0 - 1.0) < 0.01, "U = 0.02: the bed stays at rest (height within 1 %)")
    check(0.7 < lo["dP"] / erg < 1.0, "U = 0.02: dP between 0.7 and 1 times Ergun at the bed's voidage at rest")
    check(hi["H"] / H0 > 1.05, "U = 0.05: the bed has expanded")
    # The fluid's momentum along the periodic axis: where the target flux is held (not ramped), every
    # fluid step the drive G on the box volume balances the water's weight and the force it gives the
    # beads, G V_box = M_f g + F_beads (F_beads = f_ID[13], with the drive's share G V_k). Exact with
    # the projection's exact exchange (measured 1e-15 N at 0.02 and 0.05 m/s; during a ramp the
    # residual is rho V_box dU/dt, 1.944e-3 N at 0.1 m/s2); 5.85 % of the buoyant weight off without it.
    A = p["L"] * p["L"]
    held = [i for i in range(1, len(cols["t"])) if cols["Ut"][i] == cols["Ut"][i - 1]]
    res_max = max(abs(cols["G"][i] * A * p["Lz"] - cols["mass"][i] * p["g"] - cols["fgz"][i]) for i in held)
    check(len(held) > 10 and res_max < 1e-9 * W * A, f"the water's momentum balance G V_box = M_f g + F_beads at "
          f"the {len(held)} outputs of a held target ({res_max / (W * A):.1e} of the buoyant weight)")
    # the plateau is the buoyant weight less what the distributor carries (the bottom layer and what
    # rests on it: measured 0.90 with 10 % on the distributor)
    check(0.85 < hi["dP"] / W < 1.02, "U = 0.05: dP between 0.85 and 1.02 times the buoyant weight per area")


def case_open_quick(r):
    """The same bed fed through the floor and drained at the top (inputs/fluidized_bed/
    in.fluidized_bed_open, boundary zlo inflow U / zhi outflow), at the reduced size of 'quick': the
    water's mass = the fill's + in - out at every output to 1e-12; over the second half of each stage
    the mass in the box within 1.1 layers of points across the inflow (measured 1.000 and 1.041: the
    points that leave the bed carry the mass the beads' volume left them, the new ones a full
    layer's); the fixed bed at rest (height within 1 %); the fluidized bed's dP from the two probes
    between 0.85 and 1.02 times the buoyant weight per area (measured 0.911) and the bed expanded."""
    work = r.fresh("fluidized_bed/open_quick")
    shutil.copy(os.path.join(r.inputs, "fluidized_bed", "in.fluidized_bed_open"), work)
    r.execute(work, "in.fluidized_bed_open", dict(QUICK, nz=11), timeout=900)
    shutil.copy(os.path.join(work, "output.txt"), os.path.join(work, "log.txt"))
    res = fb.analyse_open(work)
    check(res["balance"] < 1e-12, f"water mass = fill + in - out at every output ({res['balance']:.1e})")
    st = res["stages"]
    check(len(st) == 2, f"two stages ({len(st)})")
    if len(st) != 2:
        return
    lo, hi = st
    check(all(x["range"] < 1.1 for x in st), "the mass in the box within 1.1 layers over each stage's second half")
    check(abs(lo["H"] / res["H0"] - 1.0) < 0.01, "U = 0.02: the bed stays at rest (height within 1 %)")
    check(hi["H"] / res["H0"] > 1.05, "U = 0.05: the bed has expanded")
    check(0.85 < hi["dP"] / res["W"] < 1.02, "U = 0.05: dP between 0.85 and 1.02 times the buoyant weight per area")


if __name__ == "__main__":
    sys.exit(driver_main(globals()))
