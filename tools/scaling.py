#!/usr/bin/env python3
"""Strong scaling of fix mpm/fluid on the wavetank scene (inputs/bench/in.wavetank; docs/scaling.md).

  tools/python tools/scaling.py run [--np 1 2 4 8 16] [--oversubscribe] [--n 24] [--models eos projection]
        [--steps-eos 50] [--steps-projection 30] [--warm 5] [--balance 1] [--exe build/liggghts_mpm]
        [--mpirun mpirun] [--out scaling-out] [--fit FIT.json] [--check]
  tools/python tools/scaling.py report RESULTS.txt ... [--out DIR] [--fit FIT.json] [--check]
  tools/python tools/scaling.py fit RESULTS.txt ... --json FIT.json
  tools/python tools/scaling.py merge TIMES.txt COUNTS.txt > MERGED.txt
  tools/python tools/scaling.py predict --fit FIT.json --counts RESULTS.txt ... [--ceiling 16 0.77]
        [--measured eos 21.13 0.87 0.73 0.57 0.45] [--out DIR]

run: runs the scene with mpirun at each rank count, both pressure models, `-var n N`, balanced cuts
(fix balance/mpm dim x) unless --balance 0, and writes RESULTS lines to OUT/scaling.txt (the format
of tools/scaling_device.sh, which runs the same on a bare many-core machine), then reports them.
RESULTS lines: `MODEL np P rc RC loop T RESULT ...` per run, and `MODEL np P STAT <line>` for
fix mpm/fluid's end-of-run lines of the timed run (wall time; halo exchanges; work per rank).

report: one table per model (ranks, loop time, efficiency t1 / (P tP), point-steps per second per
core, peak memory per rank, exchanges per step, messages / bytes / wait per exchange (largest
rank), points and patch nodes on the largest rank) and a plot of efficiency against ranks
(OUT/scaling_efficiency.png), with the model's prediction when --fit is given.

fit: the model's constants (docs/scaling.md) from runs at 1 and 2 ranks (balanced and uniform cuts):
per point and per patch node cost of the fluid's work per step, the rest of the step (LIGGGHTS) per
point, message latency and bandwidth. merge: the runs of TIMES with the counts of the runs of COUNTS
with the same model and ranks (a build or machine that printed no counts). predict: the efficiency curve of the model for the counts of RESULTS runs
(oversubscribed runs count the same as runs on real cores), against measured efficiencies.

--check: the statistics must be consistent (bytes and messages sent summed over the ranks equal
those received; no message and no byte at one rank without periodic dimensions; every rank sends
at 2 ranks); exit 1 with the failures otherwise.
"""
import argparse
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.normpath(os.path.join(HERE, ".."))
INPUT = os.path.join(TOP, "inputs", "bench", "in.wavetank")

NUM = r"([-+0-9.eE]+|nan|inf)"
TRIPLE = NUM + "/" + NUM + "/" + NUM
RE_HALO = re.compile(r"halo exchanges in this run \(min/mean/max over (\d+) ranks\): exchanges " + TRIPLE +
                     r"; per exchange: messages sent " + TRIPLE + r", bytes sent " + TRIPLE + r", wait " + TRIPLE +
                     r" s; all ranks: messages sent (\d+) received (\d+), bytes sent (\d+) received (\d+)")
RE_WORK = re.compile(r"work per rank \(min/mean/max over (\d+) ranks\): points " + TRIPLE + r", owned nodes " + TRIPLE +
                     r", patch nodes " + TRIPLE + r"; peak memory \(ru_maxrss\) max " + NUM + r" MiB per rank, sum " +
                     NUM + " MiB")
RE_WALL = re.compile(r"wall time in this run: fluid " + NUM + r" s")
RE_BUSY = re.compile(r"per rank: busy " + NUM + " to " + NUM + r" s \(max/mean " + NUM + r"\), waits for halo messages " +
                     NUM + " to " + NUM + " s")
RE_RUN = re.compile(r"^(\w+) np (\d+) rc (\S+) loop (\S*) ?(.*)$")
RE_STAT = re.compile(r"^(\w+) np (\d+) STAT (.*)$")


def triple(m, i):
    return [float(m.group(i)), float(m.group(i + 1)), float(m.group(i + 2))]


def parse_stat(rec, line):
    """The end-of-run lines of fix mpm/fluid into rec (a dict)."""
    m = RE_HALO.search(line)
    if m:
        rec["ranks_stat"] = int(m.group(1))
        rec["exchanges"] = triple(m, 2)
        rec["msgs_per_x"] = triple(m, 5)
        rec["bytes_per_x"] = triple(m, 8)
        rec["wait_per_x"] = triple(m, 11)
        rec["msgs_sent"], rec["msgs_recv"], rec["bytes_sent"], rec["bytes_recv"] = (int(m.group(i)) for i in range(14, 18))
    m = RE_WORK.search(line)
    if m:
        rec["points"] = triple(m, 2)
        rec["owned"] = triple(m, 5)
        rec["patch"] = triple(m, 8)
        rec["mem_max_mib"], rec["mem_sum_mib"] = float(m.group(11)), float(m.group(12))
    m = RE_WALL.search(line)
    if m:
        rec["fluid_s"] = float(m.group(1))
    m = RE_BUSY.search(line)
    if m:
        rec["busy"] = [float(m.group(1)), float(m.group(2))]
        rec["wait"] = [float(m.group(4)), float(m.group(5))]


def read_results_text(text, source="text"):
    """RESULTS lines -> list of run dicts (model, np, rc, loop, steps, npoints, statistics)."""
    runs, by = [], {}
    for line in text.splitlines():
        m = RE_STAT.match(line)
        if m:
            key = (m.group(1), int(m.group(2)))
            if key in by:
                parse_stat(by[key], m.group(3))
            continue
        m = RE_RUN.match(line)
        if not m:
            continue
        rec = {"model": m.group(1), "np": int(m.group(2)), "rc": m.group(3), "source": source}
        rec["loop"] = float(m.group(4)) if m.group(4) else float("nan")
        r = re.search(r"RESULT n (\S+) points (\S+) steps (\S+)", m.group(5))
        if r:
            rec["n"], rec["npoints"], rec["steps"] = float(r.group(1)), float(r.group(2)), int(r.group(3))
        by[(rec["model"], rec["np"])] = rec
        runs.append(rec)
    return runs


def read_results(paths):
    """RESULTS files -> list of run dicts (read_results_text of each)."""
    runs = []
    for p in paths:
        with open(p) as f:
            runs += read_results_text(f.read(), p)
    return runs


def screen_stats(text):
    """The last (timed run's) fix mpm/fluid end-of-run lines of a screen output."""
    out = {}
    for key in ("wall time in this run", "halo exchanges in this run", "work per rank"):
        lines = [ln for ln in text.splitlines() if ln.startswith("fix mpm/fluid: " + key)]
        if lines:
            out[key] = lines[-1]
    return list(out.values())


def do_run(a):
    os.makedirs(a.out, exist_ok=True)
    res = os.path.join(a.out, "scaling.txt")
    with open(res, "w"):
        pass
    for model in a.models:
        steps = a.steps_eos if model == "eos" else a.steps_projection
        for p in a.np:
            d = os.path.join(a.out, "%s-np%d" % (model, p))
            os.makedirs(d, exist_ok=True)
            cmd = a.mpirun.split() + (["--oversubscribe"] if a.oversubscribe else []) + ["-np", str(p), a.exe, "-in", INPUT,
                   "-var", "n", str(a.n), "-var", "pressure", model, "-var", "nsteps", str(steps), "-var", "warm", str(a.warm),
                   "-var", "balance", str(a.balance), "-echo", "none", "-log", "log.txt"]
            q = subprocess.run(cmd, cwd=d, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            with open(os.path.join(d, "screen.txt"), "w") as f:
                f.write(q.stdout)
            loops = re.findall(r"Loop time of (\S+)", q.stdout)
            result = [ln for ln in q.stdout.splitlines() if ln.startswith("RESULT")]
            line = "%s np %d rc %d loop %s %s" % (model, p, q.returncode, loops[-1] if loops else "", result[-1] if result else "")
            with open(res, "a") as f:
                f.write(line + "\n")
                for s in screen_stats(q.stdout):
                    f.write("%s np %d STAT %s\n" % (model, p, s))
            print(line, flush=True)
    a.results = [res]
    return do_report(a)


def efficiency_rows(runs):
    """Per model: rows (np, loop, efficiency, rate per core, run) sorted by np; efficiency against the
    1-rank run of the same model, steps and size (nan without one)."""
    out = {}
    for model in sorted({r["model"] for r in runs}):
        rs = sorted((r for r in runs if r["model"] == model), key=lambda r: r["np"])
        one = [r for r in rs if r["np"] == 1]
        rows = []
        for r in rs:
            t1 = one[0]["loop"] if one and one[0].get("steps") == r.get("steps") else float("nan")
            eff = t1 / (r["np"] * r["loop"]) if r["loop"] > 0 else float("nan")
            rate = r.get("npoints", float("nan")) * r.get("steps", 0) / (r["np"] * r["loop"]) if r["loop"] > 0 else float("nan")
            rows.append((r["np"], r["loop"], eff, rate, r))
        out[model] = rows
    return out


def fmt(v, spec):
    return "-" if v is None or v != v else format(v, spec)


def print_table(runs, pred=None):
    for model, rows in efficiency_rows(runs).items():
        print("\n%s" % model)
        print("| ranks | loop s | efficiency | model | point-steps/s per core | memory MiB/rank (max) | exchanges/step "
              "| messages/exchange (max rank) | bytes/exchange (max rank) | wait ms/exchange (min-max) | points (max rank) "
              "| patch nodes (max rank) |")
        print("|---" * 12 + "|")
        for p, loop, eff, rate, r in rows:
            x = r.get("exchanges", [float("nan")] * 3)[2] / r["steps"] if r.get("steps") else float("nan")
            w = r.get("wait_per_x", [float("nan")] * 3)
            pe = pred.get((model, p)) if pred else None
            print("| %d | %s | %s | %s | %s | %s | %s | %s | %s | %s-%s | %s | %s |" % (
                p, fmt(loop, ".3f"), fmt(eff, ".3f"), fmt(pe, ".3f"), fmt(rate, ".3g"), fmt(r.get("mem_max_mib"), ".0f"),
                fmt(x, ".1f"), fmt(r.get("msgs_per_x", [None] * 3)[2], ".2f"), fmt(r.get("bytes_per_x", [None] * 3)[2], ".4g"),
                fmt(w[0] * 1e3, ".3f"), fmt(w[2] * 1e3, ".3f"), fmt(r.get("points", [None] * 3)[2], ".0f"),
                fmt(r.get("patch", [None] * 3)[2], ".0f")))


def check(runs):
    """Failures of the statistics' consistency (list of strings)."""
    bad = []
    for r in runs:
        tag = "%s np %d" % (r["model"], r["np"])
        if r["rc"] != "0":
            bad.append("%s: exit status %s" % (tag, r["rc"]))
            continue
        if "msgs_sent" not in r or "points" not in r:
            bad.append("%s: no statistics lines" % tag)
            continue
        if r["ranks_stat"] != r["np"]:
            bad.append("%s: statistics over %d ranks" % (tag, r["ranks_stat"]))
        if r["msgs_sent"] != r["msgs_recv"] or r["bytes_sent"] != r["bytes_recv"]:
            bad.append("%s: sent %d messages / %d bytes, received %d / %d" % (tag, r["msgs_sent"], r["bytes_sent"],
                                                                            r["msgs_recv"], r["bytes_recv"]))
        if r["exchanges"][0] <= 0 or r["exchanges"][0] != r["exchanges"][2]:
            bad.append("%s: exchanges %s (every rank takes part in every exchange)" % (tag, r["exchanges"]))
        if abs(r["points"][1] * r["np"] - r.get("npoints", -1)) > 0.5:
            bad.append("%s: points per rank %s do not add up to %s" % (tag, r["points"], r.get("npoints")))
        if r["np"] == 1 and (r["msgs_sent"] != 0 or r["bytes_sent"] != 0 or r["wait_per_x"][2] != 0.0):
            bad.append("%s: %d messages, %d bytes, wait %g at one rank" % (tag, r["msgs_sent"], r["bytes_sent"],
                                                                          r["wait_per_x"][2]))
        if r["np"] == 1 and r["patch"][0] != r["owned"][0]:
            bad.append("%s: patch %g != owned %g nodes at one rank" % (tag, r["patch"][0], r["owned"][0]))
        if r["np"] == 2 and (r["msgs_per_x"][0] <= 0 or r["bytes_per_x"][0] <= 0 or r["msgs_per_x"][2] > 1):
            bad.append("%s: messages per exchange %s, bytes %s (each of 2 ranks sends one message to the other)" % (
                tag, r["msgs_per_x"], r["bytes_per_x"]))
        if r["np"] > 1 and r["patch"][0] <= r["owned"][0]:
            bad.append("%s: patch nodes %s not above owned %s (no halo)" % (tag, r["patch"], r["owned"]))
    return bad


# ---------------------------------------------------------------- the model (docs/scaling.md)

def per_step(r):
    """Counts per time step of one run: points and patch nodes of the largest rank, exchanges, messages
    and bytes per exchange of the largest rank."""
    s = r["steps"]
    return {"pts": r["points"][2], "nodes": r["patch"][2], "owned": r["owned"][2], "x": r["exchanges"][2] / s,
            "m": r["msgs_per_x"][2], "b": r["bytes_per_x"][2]}


def ceiling(p, table):
    """The machine's rate per core with p busy cores: linear in p between the measured points
    (table: {p: factor}, 1: 1.0)."""
    t = dict(table)
    t[1] = 1.0
    pts = sorted(t.items())
    for (p0, f0), (p1, f1) in zip(pts, pts[1:]):
        if p0 <= p <= p1:
            return f0 + (f1 - f0) * (p - p0) / (p1 - p0)
    return pts[-1][1]


def model_time(c, k, p, table):
    """Model time per step (s) of a run with counts k on p ranks, constants c of its model."""
    work = (c["a"] + c["o"]) * k["pts"] + c["b"] * k["nodes"]
    comm = k["x"] * (c["lat"] * k["m"] + k["b"] / c["bw"]) if p > 1 else 0.0
    return work / ceiling(p, table) + comm


def do_fit(a):
    """Constants per model (docs/scaling.md) from runs at 1 and 2 ranks with balanced cuts:
    b (s per patch node and step): the two ranks of a balanced 2-rank run hold the same points and
    different patch nodes: (largest - least busy time per step) / (largest - least patch nodes);
    busy = the fluid's and the coupling's time less the waits for halo messages.
    a (s per point and step): the rest of the 1-rank fluid time per step, (T1 - b G) / N.
    o (s per point and step): the rest of the 1-rank loop (LIGGGHTS: neighbour lists, integration,
    point migration), (loop - fluid) / steps / N.
    lat, bw: the least wait per exchange over the ranks of each uniform-cut 2-rank run (the rank
    with more points is the last to arrive in every phase and waits only for the transfer) against
    its messages and bytes per exchange (fit_comm).
    Several runs of a kind: their mean. Uniform-cut 2-rank runs, if given, are predicted (largest and
    least busy rank) as a check of the constants."""
    import numpy as np
    runs = [r for r in read_results(a.results) if r["rc"] == "0" and "points" in r and "fluid_s" in r]
    out = {}
    # the transfer alone: the 2-rank runs with uniform cuts, where one rank holds more points and is
    # the slower in every phase, so that its wait is the transfer; balanced runs (the ranks take
    # turns being slower, phase by phase) only without uniform ones
    two = [r for r in runs if r["np"] == 2 and "wait" in r and r.get("exchanges")]
    uneven = [r for r in two if r["points"][2] - r["points"][0] >= 1e-3 * r["points"][2]]
    pts = [(r["msgs_per_x"][2], r["bytes_per_x"][2], r["wait"][0] / r["exchanges"][2]) for r in (uneven or two)]
    lat, bw = fit_comm(pts)
    out["comm"] = {"lat": lat, "bw": bw, "from (messages, bytes, least wait per exchange)": pts}
    for model in sorted({r["model"] for r in runs}):
        rs = [q for q in runs if q["model"] == model]
        ones = [q for q in rs if q["np"] == 1]
        bal = [q for q in rs if q["np"] == 2 and "busy" in q and q["points"][2] - q["points"][0] < 1e-3 * q["points"][2]]
        uni = [q for q in rs if q["np"] == 2 and "busy" in q and q not in bal]
        if not ones or not bal:
            continue
        b = float(np.mean([(q["busy"][1] - q["busy"][0]) / q["steps"] / (q["patch"][2] - q["patch"][0]) for q in bal]))
        N, G = ones[0]["points"][0], ones[0]["patch"][0]
        T1 = float(np.mean([q["fluid_s"] / q["steps"] for q in ones]))
        aa = (T1 - b * G) / N
        o = float(np.mean([(q["loop"] - q["fluid_s"]) / q["steps"] / N for q in ones]))
        c = {"a": aa, "b": b, "o": o, "lat": lat, "bw": bw, "N": N, "G": G, "T1_fluid_per_step": T1,
             "from": [q["source"] + ": " + q["model"] + " np " + str(q["np"]) for q in ones + bal]}
        c["uniform_check (busy per step: measured least, largest; model least, largest)"] = [
            [q["busy"][0] / q["steps"], q["busy"][1] / q["steps"], aa * q["points"][0] + b * q["patch"][0],
             aa * q["points"][2] + b * q["patch"][2]] for q in uni]
        out[model] = c
    with open(a.json, "w") as f:
        json.dump(out, f, indent=1)
    print(json.dumps(out, indent=1))
    return 0


def do_merge(a):
    """The runs of TIMES (loop and wall-time lines) with the halo-exchange and work lines of the runs
    of COUNTS of the same model and ranks (the same cuts: the same n and balance), to stdout: counts
    of oversubscribed runs with the times of a build or machine that did not print them."""
    counts, csteps = {}, {}
    with open(a.counts) as f:
        for line in f:
            m = RE_STAT.match(line)
            if m and ("halo exchanges" in line or "work per rank" in line):
                counts.setdefault((m.group(1), int(m.group(2))), []).append(line.rstrip("\n"))
            m = RE_RUN.match(line)
            r = re.search(r"RESULT n \S+ points \S+ steps (\d+)", line)
            if m and r:
                csteps[(m.group(1), int(m.group(2)))] = int(r.group(1))
    with open(a.times) as f:
        for line in f:
            m = RE_STAT.match(line)
            if m and ("halo exchanges" in line or "work per rank" in line):
                continue
            print(line.rstrip("\n"))
            m = RE_RUN.match(line)
            r = re.search(r"RESULT n \S+ points \S+ steps (\d+)", line)
            if m and r:
                key = (m.group(1), int(m.group(2)))
                for c in counts.get(key, []):
                    # the exchanges of the counting run scaled to this run's steps (the same per step)
                    x = re.search(r"exchanges " + TRIPLE, c)
                    if x:
                        f = int(r.group(1)) / csteps[key]
                        c = c.replace(x.group(0), "exchanges %g/%g/%g" % tuple(float(v) * f for v in x.groups()))
                    # the counting run's waits are not this run's
                    c = re.sub(r"wait " + TRIPLE + " s;", "wait nan/nan/nan s;", c)
                    print(c)
    return 0


def fit_comm(pts):
    """latency (s per message) and inverse bandwidth from (messages, bytes, wait) per exchange: least
    squares through the origin; a negative latency is set to 0 and the bandwidth refitted."""
    import numpy as np
    if not pts:
        return 0.0, float("inf")
    A = np.array([[m, b] for m, b, _ in pts], float)
    y = np.array([w for _, _, w in pts], float)
    sol = np.linalg.lstsq(A, y, rcond=None)[0]
    lat, inv = float(sol[0]), float(sol[1])
    if len(pts) < 2 or lat < 0 or inv <= 0:
        lat = 0.0
        inv = float(y.sum() / A[:, 1].sum())
    return lat, (1.0 / inv if inv > 0 else float("inf"))


def predictions(fit, runs, table):
    """(model, P) -> predicted efficiency, for the runs' counts (1-rank run of the same model and n needed)."""
    out = {}
    for r in runs:
        c = fit.get(r["model"])
        one = [q for q in runs if q["model"] == r["model"] and q["np"] == 1 and q.get("n") == r.get("n")]
        if not c or not one or "points" not in r:
            continue
        t1 = model_time(c, per_step(one[0]), 1, table)
        out[(r["model"], r["np"])] = t1 / (r["np"] * model_time(c, per_step(r), r["np"], table))
    return out


def parse_ceiling(vals):
    vals = vals or []
    if len(vals) % 2:
        sys.exit("scaling.py: --ceiling takes pairs P factor, got %s" % vals)
    return {int(vals[i]): float(vals[i + 1]) for i in range(0, len(vals), 2)}


def parse_measured(groups):
    """--measured MODEL t1 e2 e4 ... (efficiencies at 2, 4, 8, ...) -> {(model, P): eff}."""
    out = {}
    for g in groups or []:
        model, t1, effs = g[0], float(g[1]), [float(v) for v in g[2:]]
        out[(model, 1)] = 1.0
        for i, e in enumerate(effs):
            out[(model, 2 ** (i + 1))] = e
        out[(model, "t1")] = t1
    return out


def do_predict(a):
    with open(a.fit) as f:
        fit = json.load(f)
    runs = [r for r in read_results(a.counts) if r["rc"] == "0" and "points" in r]
    table = parse_ceiling(a.ceiling)
    pred = predictions(fit, runs, table)
    meas = parse_measured(a.measured)
    print("ceiling (rate per core with P busy cores):", table)
    print("| model | ranks | points (max rank) | patch nodes (max rank) | exchanges/step | messages/exchange | "
          "bytes/exchange | model s/step | model efficiency | measured |")
    print("|---" * 10 + "|")
    for r in sorted(runs, key=lambda r: (r["model"], r["np"])):
        c = fit[r["model"]]
        k = per_step(r)
        print("| %s | %d | %.0f | %.0f | %.1f | %.2f | %.4g | %.4f | %.3f | %s |" % (
            r["model"], r["np"], k["pts"], k["nodes"], k["x"], k["m"], k["b"], model_time(c, k, r["np"], table),
            pred[(r["model"], r["np"])], fmt(meas.get((r["model"], r["np"])), ".2f")))
    if a.out:
        plot(a.out, pred, meas, "model (%s)" % ", ".join("%d: %.2f" % kv for kv in sorted(table.items())))
    return 0


def plot(out, pred, meas, label, runs_eff=None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(out, exist_ok=True)
    fig, ax = plt.subplots(figsize=(6, 4))
    colors = {"eos": "tab:blue", "projection": "tab:orange"}
    models = sorted({k[0] for k in list(pred) + list(meas) + list(runs_eff or {})})
    for m in models:
        col = colors.get(m, None)
        for data, style, what in ((meas, "o-", "measured (--measured)"), (runs_eff or {}, "s-", "measured (runs)"),
                                  (pred, "x--", label)):
            xs = sorted(k[1] for k in data if k[0] == m and isinstance(k[1], int))
            if xs:
                ax.plot(xs, [data[(m, x)] for x in xs], style, color=col, label="%s, %s" % (m, what))
    ax.set_xscale("log", base=2)
    ax.set_xlabel("ranks")
    ax.set_ylabel("parallel efficiency t1 / (P tP)")
    ax.set_ylim(0, 1.1)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    png = os.path.join(out, "scaling_efficiency.png")
    fig.savefig(png, dpi=110)
    print("wrote", png)


def ceiling_table(paths):
    """`ceiling P K loop T` lines (P independent 1-rank runs, one per core): {P: (mean, slowest)}
    rate of the P runs against the run alone (P = 1)."""
    loops = {}
    for p in paths:
        with open(p) as f:
            for line in f:
                m = re.match(r"ceiling (\d+) (\d+) loop (\S+)", line)
                if m:
                    loops.setdefault(int(m.group(1)), []).append(float(m.group(3)))
    if 1 not in loops:
        return {}
    t1 = loops[1][0]
    return {p: (t1 * len(v) / sum(v), t1 / max(v)) for p, v in sorted(loops.items())}


def do_report(a):
    ceil = ceiling_table(a.results)
    if ceil:
        print("machine ceiling (P independent 1-rank runs, one per core; rate against one alone):")
        print("| P | mean | slowest |\n|---|---|---|")
        for p, (mean, slow) in ceil.items():
            print("| %d | %.3f | %.3f |" % (p, mean, slow))
    runs = read_results(a.results)
    pred = None
    if a.fit:
        with open(a.fit) as f:
            pred = predictions(json.load(f), [r for r in runs if r["rc"] == "0" and "points" in r], parse_ceiling(a.ceiling))
    print_table(runs, pred)
    effs = {(m, p): e for m, rows in efficiency_rows(runs).items() for p, _, e, _, _ in rows}
    if a.out:
        plot(a.out, pred or {}, parse_measured(getattr(a, "measured", None)), "model", effs)
    if a.check:
        bad = check(runs)
        for b in bad:
            print("check failed:", b)
        if bad or not runs:
            print("check: FAILED (%d runs)" % len(runs))
            return 1
        print("check: statistics consistent in %d runs" % len(runs))
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="mode", required=True)
    r = sub.add_parser("run")
    r.add_argument("--np", type=int, nargs="+", default=[1, 2, 4, 8, 16])
    r.add_argument("--oversubscribe", action="store_true")
    r.add_argument("--n", type=int, default=24)
    r.add_argument("--models", nargs="+", default=["eos", "projection"], choices=["eos", "projection"])
    r.add_argument("--steps-eos", type=int, default=50)
    r.add_argument("--steps-projection", type=int, default=30)
    r.add_argument("--warm", type=int, default=5)
    r.add_argument("--balance", type=int, default=1, choices=[0, 1])
    r.add_argument("--exe", default=os.path.join(TOP, "build", "liggghts_mpm"))
    r.add_argument("--mpirun", default="mpirun --allow-run-as-root")
    r.add_argument("--out", default="scaling-out")
    p = sub.add_parser("report")
    p.add_argument("results", nargs="+")
    p.add_argument("--out", default=None)
    p.add_argument("--measured", nargs="+", action="append")
    for q in (r, p):
        q.add_argument("--fit", default=None)
        q.add_argument("--ceiling", nargs="+", default=["16", "0.77"])
        q.add_argument("--check", action="store_true")
    f = sub.add_parser("fit")
    f.add_argument("results", nargs="+")
    f.add_argument("--json", required=True)
    g = sub.add_parser("merge")
    g.add_argument("times")
    g.add_argument("counts")
    d = sub.add_parser("predict")
    d.add_argument("--fit", required=True)
    d.add_argument("--counts", nargs="+", required=True)
    d.add_argument("--ceiling", nargs="+", default=["16", "0.77"])
    d.add_argument("--measured", nargs="+", action="append")
    d.add_argument("--out", default=None)
    a = ap.parse_args()
    if a.mode == "run":
        for v, name in ((a.n, "--n"), (a.steps_eos, "--steps-eos"), (a.steps_projection, "--steps-projection")):
            if v < 1:
                sys.exit("scaling.py: %s must be at least 1, got %d" % (name, v))
        if any(p < 1 for p in a.np):
            sys.exit("scaling.py: --np must be at least 1, got %s" % a.np)
        if not os.path.exists(a.exe):
            sys.exit("scaling.py: --exe %s does not exist" % a.exe)
        return do_run(a)
    if a.mode == "report":
        a.results = a.results
        return do_report(a)
    if a.mode == "fit":
        return do_fit(a)
    if a.mode == "merge":
        return do_merge(a)
    return do_predict(a)


if __name__ == "__main__":
    sys.exit(main())
