// Inflow faces of keyword boundary (docs/fix_mpm_fluid.md, "Flow in and out"): the fluid that entered
// through face f since its last layer of points, as a depth along the face's normal.
//
// The inflow's fluid is a lattice of the fill's spacing moving in at U from behind the face: the
// fill's first layer lies half a spacing s inside the face, and the next layer of the stream crosses
// that plane once the fluid has advanced by s. inflow_depth holds the advance since the last layer
// was made; each whole s of it is one layer due, made by the host (FixMpmFluid::flow_exchange) at
// the position it has reached, s/2 + (depth - (j + 1) s) inside the face for the j-th of n layers
// due. The volume made is then U A t less the depth still owed (under one layer), kept in the state
// and restart file: no layer is lost or made twice, whatever the steps.
#include <cmath>

#include "mpm/solver.h"

namespace mpm {

void FluidSolver::inflow_advance(double hf) {
  for (int f = 0; f < 6; ++f)
    if (opt.face[f].kind == BcKind::Inflow) state.inflow_depth[f] += opt.face[f].inflow * hf;
}

int FluidSolver::inflow_layers(int f) const {
  if (opt.face[f].kind != BcKind::Inflow) return 0;
  const double s = state.spacing[f / 2];
  if (!(s > 0.0)) return 0;
  return static_cast<int>(std::floor(state.inflow_depth[f] / s));
}

double FluidSolver::inflow_layer_position(int f, int j) const {
  const int d = f / 2;
  const double s = state.spacing[d];
  const double depth = 0.5 * s + (state.inflow_depth[f] - (j + 1) * s);
  return f % 2 == 0 ? opt.grid.origin[d] + depth : opt.grid.upper(d) - depth;
}

void FluidSolver::inflow_created(int f, int n) { state.inflow_depth[f] -= n * state.spacing[f / 2]; }

}  // namespace mpm
