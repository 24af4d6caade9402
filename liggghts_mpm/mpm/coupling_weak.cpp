// grad_p weak's nodal pressure gradient, the part of the coupling phases (coupling.cpp) that does
// not depend on the stencil: the fluid's own weak gradient at the nodes and its copy to the face
// and padding nodes.
#include <algorithm>

#include "mpm/solver.h"

namespace mpm {

/* grad_p weak: the pressure gradient the fluid itself feels at node i, -(internal force + wall
   traction) / sum_p S_ip V_p: the P2G force less the points' external forces. At rest every free
   node balances it with the weight of its fluid and the grains' reaction, so a grain reads
   exactly rho g there, whatever the packing and next to a floor, where the anti-locked cell
   pressure has its staircase (docs/theory/well_balanced.md). Nodes on a grid face and padding
   nodes (their velocity is the wall's) take the value of the nearest node off the faces. */
void FluidSolver::weak_pressure_gradient() {
  const GridSpec &gs = opt.grid;
  const double vmin = 1e-12 * gs.dx * gs.dx * gs.dx, vhalf = 0.5 * gs.dx * gs.dx * gs.dx;
  std::fill(g_.gw.begin(), g_.gw.end(), 0.0);
  grid_.for_owned([&](int, int, int, std::size_t n) {
    const double *w = &g_.wk[WkRec::N * n];
    if (!(w[WkRec::V] > vmin)) return;
    const double *f = &g_.p2g[P2gRec::N * n + P2gRec::F];
    // a node whose points fill less than half a cell (a free surface, a front) divides by half a
    // cell: its force over its points' sliver of volume gave the grains there gradients of many
    // rho g, and the collapsing bed of tank quick blew up at 0.026 s (it runs with the floor)
    const double Vd = std::max(w[WkRec::V], vhalf);
    for (int d = 0; d < 3; ++d) g_.gw[3 * n + d] = -(f[d] - w[WkRec::F + d]) / Vd;
  });
  grid_.forward(g_.gw.data(), 3);
  weak_face_copy();
}

// grad_p weak: nodes on a grid face and padding nodes take the value of the nearest node off the faces
// Only the nodes a copy writes are visited: the slabs of the patch at or beyond a face (index <= 0
// or >= ncell along a dimension that is clamped). The node copied from lies in none of them (its
// clamped indices are inside), so a node in two slabs gets the same copy twice.
void FluidSolver::weak_face_copy() {
  const GridSpec &gs = opt.grid;
  const IndexBox &pb = grid_.patch();
  auto copy = [&](int i, int j, int k, std::size_t n) {
    int c[3] = {i, j, k};
    for (int d = 0; d < 3; ++d) {
      if (gs.periodic[d] || gs.ncell[d] < 2) continue;
      c[d] = std::min(std::max(c[d], 1), gs.ncell[d] - 1);
    }
    if (!grid_.in_patch(c[0], c[1], c[2])) return;
    const std::size_t m = grid_.index(c[0], c[1], c[2]);
    for (int d = 0; d < 3; ++d) g_.gw[3 * n + d] = g_.gw[3 * m + d];
  };
  for (int d = 0; d < 3; ++d) {
    if (gs.periodic[d] || gs.ncell[d] < 2) continue;
    IndexBox lo = pb, hi = pb;
    lo.hi[d] = std::min(pb.hi[d], 0);
    hi.lo[d] = std::max(pb.lo[d], gs.ncell[d]);
    if (!lo.empty()) grid_.for_box(lo, copy);
    if (!hi.empty()) grid_.for_box(hi, copy);
  }
}

}  // namespace mpm
