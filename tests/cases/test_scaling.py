#!/usr/bin/env python3
"""tools/scaling.py on a tiny wavetank (inputs/bench/in.wavetank, n 8: 5,120 points) at 1 and 2
ranks, both pressure models, and the consistency of fix mpm/fluid's halo-exchange statistics.

    test_scaling.py stats --exe build/liggghts_mpm --inputs inputs --work DIR --mpirun "mpirun ..."

Checks: every run ends; over the ranks, the messages and bytes sent equal those received; every
rank takes part in every exchange, and the exchanges per step are the same at 1 and 2 ranks (the
halo exchanges follow the algorithm, not the cuts); one rank (no periodic dimension) sends no
message and no byte and waits 0 s, its patch is its owned box and holds every point; at 2 ranks
each rank sends one message per exchange and the patch holds more nodes than the owned box (the
halo); the points per rank add up to the run's total; the two ranks' owned nodes add up to the one
rank's. The checker of tools/scaling.py first runs on the same results with a planted fault
(a byte less received, a message at one rank) and must fail, so a checker that finds nothing
cannot pass. Runs tools/scaling.py in tools/python (the project's environment).
"""
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.path.join(HERE, "..", "..", "tools")
sys.path.insert(0, HERE)
sys.path.insert(0, TOOLS)
import cases  # noqa: E402
from cases import check  # noqa: E402
import scaling  # noqa: E402  (parsing only: no numpy or matplotlib at import)


def case_stats(r):
    d = r.fresh("scaling_stats")
    py = os.path.join(TOOLS, "python")
    cmd = [py, os.path.join(TOOLS, "scaling.py"), "run", "--np", "1", "2", "--n", "8", "--steps-eos", "4",
           "--steps-projection", "3", "--warm", "1", "--exe", r.exe, "--mpirun", " ".join(r.mpirun), "--out", d, "--check"]
    q = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
    print(q.stdout[-4000:])
    check(q.returncode == 0, "tools/scaling.py run --check exits 0 (got %d)" % q.returncode)
    res = os.path.join(d, "scaling.txt")
    runs = scaling.read_results([res])
    check(len(runs) == 4, "4 runs (eos, projection at 1 and 2 ranks), got %d" % len(runs))
    check(os.path.exists(os.path.join(d, "scaling_efficiency.png")), "the efficiency plot is written")
    by = {(x["model"], x["np"]): x for x in runs}
    for model in ("eos", "projection"):
        one, two = by.get((model, 1)), by.get((model, 2))
        if not one or not two or "exchanges" not in one or "exchanges" not in two:
            check(False, "%s: runs at 1 and 2 ranks with statistics" % model)
            continue
        check(one["msgs_sent"] == 0 and one["bytes_sent"] == 0 and one["wait_per_x"][2] == 0.0,
              "%s np 1: no message, no byte, no wait (%d, %d, %g)" % (model, one["msgs_sent"], one["bytes_sent"],
                                                                      one["wait_per_x"][2]))
        check(one["patch"][0] == one["owned"][0] and one["points"][0] == one["npoints"],
              "%s np 1: patch = owned nodes (%g, %g), all %g points on the rank" % (
                  model, one["patch"][0], one["owned"][0], one["npoints"]))
        check(two["msgs_sent"] == two["msgs_recv"] and two["bytes_sent"] == two["bytes_recv"],
              "%s np 2: messages sent %d = received %d, bytes sent %d = received %d" % (
                  model, two["msgs_sent"], two["msgs_recv"], two["bytes_sent"], two["bytes_recv"]))
        check(two["msgs_per_x"] == [1.0, 1.0, 1.0] and two["bytes_per_x"][0] > 0,
              "%s np 2: one message per exchange and rank (%s), bytes > 0 (%s)" % (model, two["msgs_per_x"],
                                                                                  two["bytes_per_x"]))
        check(two["msgs_sent"] == 2 * two["exchanges"][0],
              "%s np 2: messages over the run = 2 x exchanges (%d, %g)" % (model, two["msgs_sent"], two["exchanges"][0]))
        x1, x2 = one["exchanges"][0] / one["steps"], two["exchanges"][0] / two["steps"]
        check(x1 == x2 and x1 > 0, "%s: exchanges per step at 1 and 2 ranks %g, %g" % (model, x1, x2))
        check(two["patch"][0] > two["owned"][0], "%s np 2: patch %s > owned %s nodes" % (model, two["patch"], two["owned"]))
        check(abs(2 * two["points"][1] - two["npoints"]) < 0.5 and abs(2 * two["owned"][1] - one["owned"][0]) < 0.5,
              "%s np 2: points %s add up to %g, owned nodes %s to the one rank's %g" % (
                  model, two["points"], two["npoints"], two["owned"], one["owned"][0]))
    # the checker must find planted faults
    with open(res) as f:
        text = f.read()
    planted = text.replace("bytes sent %d received %d" % (by[("eos", 2)]["bytes_sent"], by[("eos", 2)]["bytes_recv"]),
                           "bytes sent %d received %d" % (by[("eos", 2)]["bytes_sent"], by[("eos", 2)]["bytes_recv"] - 1))
    planted = planted.replace("all ranks: messages sent 0 received 0", "all ranks: messages sent 1 received 1", 1)
    bad = scaling.check(scaling.read_results_text(planted))
    check(planted != text and len(bad) == 2, "the checker finds the 2 planted faults: %s" % bad)


if __name__ == "__main__":
    sys.exit(cases.driver_main(globals()))
