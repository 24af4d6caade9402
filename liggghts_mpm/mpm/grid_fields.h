// The records the solver keeps per material point and per grid node, by name.
//
// Node records are rows of doubles, padded to multiples of 4 so that the transfer kernels read and
// write them as 4-wide rows (mpm::Row4, one AVX register): a record's named fields are offsets
// into the row, its N the row length. The fields of one phase sit in one record so a kernel
// touches one contiguous row per node (docs/design.md, docs/validation/performance.md).
#pragma once
#include <cstddef>
#include <vector>

#include "mpm/grid.h"

namespace mpm {

// Columns of a point's state row (also the fix's per-atom array, 1-based in f_ID[n]).
enum Column {
  C_VOL = 0,     // current volume of the point, m3
  C_RHO = 1,     // fluid (micro) density, kg/m3
  C_P = 2,       // pressure, Pa
  C_TAU = 3,     // deviatoric stress xx yy zz yz xz xy (6), Pa
  C_AFF = 9,     // APIC affine velocity / velocity gradient, row-major (9), 1/s
  C_THETA = 18,  // fluid volume fraction at the point
  C_FLAG = 19,   // 1 for a point set up by this fix (kPointGone: left through an outflow face)
  C_FGRAIN = 20, // on a grain of the coupled group: force of the fluid on it (3), N
  NCOL = 23
};

// C_FLAG of a point that left through an outflow face: no longer fluid, removed by the host at
// its next exchange of atoms (FixMpmFluid::flow_exchange)
constexpr double kPointGone = 2.0;

// P2G: mass, momentum (3) | force (3), pad
struct P2gRec { enum { M = 0, MV = 1, F = 4, N = 8 }; };
// grid update: new velocity (3), pad | old velocity (3), pad
struct VelRec { enum { V_NEW = 0, V_OLD = 4, N = 8 }; };
// MUSL remap: momentum, then velocity, of the updated points (3), pad
struct AuxRec { enum { U = 0, N = 4 }; };
// anti-locking, per cell keyed by its low node: V, V div u, theta V, m
struct CellRec { enum { V = 0, VDIV = 1, THV = 2, M = 3, N = 4 }; };
// coupling, moments of the points' pressure for the node's linear fit: r (4), normal matrix (4 x 4)
struct PfitRec { enum { R = 0, MAT = 4, N = 20 }; };
// coupling, what a grain reads (forwarded): fluid velocity (3), 1 if the node holds fluid;
// fitted grad p (3), 1 if the fit is determined; theta, p, fluid mass, pad
struct StRec { enum { U = 0, FIT = 4, TH = 8, P = 9, M = 10, N = 12 }; };
// coupling, the grains' share of a node: sum S K, sum S K v (3) (after the exchange: the impulse
// per unit K (3)); sum S m, pressure reaction (3); sum S K a (3), sum S K of fixed grains
struct DrRec { enum { K = 0, KV = 1, J = 1, M = 4, FP = 5, KA = 8, KFIX = 11, N = 12 }; };
// coupling, grad_p weak: the points' volume and external force at the node, sum S V, sum S f (3)
struct WkRec { enum { V = 0, F = 1, N = 4 }; };

// The node arrays of the rank's grid patch (flat index n, record of length R::N at R::N * n).
struct GridFields {
  std::vector<double> p2g, vel, aux, cell;
  // coupling (keyword couple)
  std::vector<double> pfit, st, dr;
  std::vector<double> sol;      // solid volume of the grains (reverse-summed, smoothed)
  std::vector<double> th;       // fluid fraction (forwarded)
  std::vector<double> need;     // > 0 where a grain's shape functions reach (reverse-summed)
  std::vector<double> rx;       // force of the grains on the fluid (3), owned nodes
  std::vector<double> phi, phi_new;  // smoothing work arrays
  std::vector<double> vnode;    // smoothing: node volume (solid_node_volume, forwarded), filled on first use
  bool vnode_ready = false;     // (a flag, not vnode.empty(): a rank may have no node, and filling is collective)
  std::vector<double> wk;       // grad_p weak: WkRec (reverse-summed)
  std::vector<double> gw;       // grad_p weak: the fluid's pressure gradient (3), every patch node
  std::vector<double> rp, rq;   // reaction points: the grains' pressure reaction, its density (3)
  // the owned nodes outside which rx (and, with the projection, rp) are 0 (drag_exchange)
  IndexBox xbox;
  // fluid_fraction: per owned node the node whose solid volume gives its fraction (its mirror inside
  // the box walls, or itself) and that node's volume; they depend on the patch only (filled on first use)
  std::vector<std::size_t> th_src;
  std::vector<double> th_vol;

  // cells: anti-locking (pressure eos); fit: the grains' pressure from the points' least-squares
  // fit (the text's coupling, model yang2016)
  void assign(std::size_t nodes, bool musl, bool cells, bool coupled, bool fit) {
    p2g.assign(nodes * P2gRec::N, 0.0);
    vel.assign(nodes * VelRec::N, 0.0);
    if (cells) cell.assign(nodes * CellRec::N, 0.0);
    if (musl) aux.assign(nodes * AuxRec::N, 0.0);
    if (coupled) {
      if (fit) pfit.assign(nodes * PfitRec::N, 0.0);
      sol.assign(nodes, 0.0);
      need.assign(nodes, 0.0);
      th.assign(nodes, 1.0);
      st.assign(nodes * StRec::N, 0.0);
      rx.assign(nodes * 3, 0.0);
      dr.assign(nodes * DrRec::N, 0.0);
      wk.assign(nodes * WkRec::N, 0.0);
      gw.assign(nodes * 3, 0.0);
      rp.assign(nodes * 3, 0.0);
      rq.assign(nodes * 3, 0.0);
      xbox = IndexBox();
      vnode.clear();
      vnode_ready = false;
      th_src.clear();
      th_vol.clear();
    }
  }
};

}  // namespace mpm
