#!/usr/bin/env python3
"""Communication volume of fix mpm/fluid's grid halo exchange per rank and sub-step.

Counts, like mpm::LocalGrid::setup (liggghts_mpm/mpm/grid.cpp), each rank's owned node box (nodes
whose position lies in its subdomain; padding nodes go to the ranks at the faces) and its patch
(owned box widened by the halo, clipped to the grid), then the nodes exchanged with every other
rank: reverse_sum sends my patch nodes owned by others, forward sends my owned nodes held in
others' patches. Per sub-step fix mpm/fluid does (see docs/design.md) reverse_sum of 7 + 3 + 4
doubles per node and forward of 6 + 3 + 4 (no grains); with `couple` also reverse 3 + 12 and
forward 6 + 12.

  tools/python tools/halo_volume.py [--halo 5]

Prints a Markdown table (docs/guide/mpi.md): uniform cuts, non-periodic grid, bspline2 (pad 1).
"""
import argparse
import itertools


def owned_1d(n, p, k, pad):
    """Owned node range of slab k of p along a dimension of n cells (uniform cuts)."""
    lo = -pad if k == 0 else -(-n * k // p)   # first node at or above the cut k n / p
    hi = n + pad if k == p - 1 else -(-n * (k + 1) // p) - 1
    return lo, hi


def box_count(a, b):
    c = 1
    for (alo, ahi), (blo, bhi) in zip(a, b):
        c *= max(0, min(ahi, bhi) - max(alo, blo) + 1)
    return c


def volumes(ncell, procs, halo, pad=1):
    """Per rank: (owned nodes, nodes sent in reverse, nodes sent in forward, peers)."""
    ranks = list(itertools.product(*[range(p) for p in procs]))
    owned = {r: [owned_1d(ncell[d], procs[d], r[d], pad) for d in range(3)] for r in ranks}
    patch = {r: [(max(-pad, lo - halo), min(ncell[d] + pad, hi + halo)) for d, (lo, hi) in enumerate(owned[r])]
             for r in ranks}
    out = {}
    for r in ranks:
        rev = fwd = peers = 0
        for q in ranks:
            if q == r:
                continue
            a, b = box_count(patch[r], owned[q]), box_count(patch[q], owned[r])
            rev += a
            fwd += b
            peers += 1 if (a or b) else 0
        out[r] = (box_count(owned[r], owned[r]), rev, fwd, peers)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--halo", type=int, default=5, help="halo layers: support 3 + ceil(skin/dx) + 1 = 5 for "
                    "bspline2 and skin 0.2 dx")
    a = ap.parse_args()
    cases = [("3-D dam break 100k points, 2 slabs in x", (69, 46, 25), (2, 1, 1)),
             ("same, 4 slabs in x", (69, 46, 25), (4, 1, 1)),
             ("same, 2 x 2 x 1", (69, 46, 25), (2, 2, 1))]
    for n in (8, 16, 32, 64):
        cases.append(("cube subdomains %d^3 cells, 3x3x3 ranks (centre rank)" % n, (3 * n,) * 3, (3, 3, 3)))
    print("| case | owned nodes | halo nodes sent (reverse / forward) | peers | MB per sub-step sent, fluid only "
          "| with `couple` | sent bytes per owned node |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for name, ncell, procs in cases:
        v = volumes(ncell, procs, a.halo)
        r = max(v, key=lambda k: v[k][1] + v[k][2])  # the busiest rank
        own, rev, fwd, peers = v[r]
        fluid = 8 * (14 * rev + 13 * fwd)
        coupled = fluid + 8 * (15 * rev + 18 * fwd)
        print("| %s | %d | %d / %d | %d | %.3f | %.3f | %.0f |" %
              (name, own, rev, fwd, peers, fluid / 1e6, coupled / 1e6, fluid / own))


if __name__ == "__main__":
    main()
