// Small helpers shared by the MPI unit tests of the pressure projection (test_pressure_solver,
// test_projection_state): rank and size, and a LocalGrid split into slabs along x.
#pragma once
#include <mpi.h>

#include "mpm/grid.h"

namespace mpm_test {

inline int rank_of(MPI_Comm c) {
  int r;
  MPI_Comm_rank(c, &r);
  return r;
}

inline int size_of(MPI_Comm c) {
  int s;
  MPI_Comm_size(c, &s);
  return s;
}

// grid over the whole of g, split into slabs along x: with 2 ranks rank 0 holds the fraction
// split of the length, otherwise equal slabs
inline void setup_slabs(mpm::LocalGrid &grid, const mpm::GridSpec &g, MPI_Comm c, double split, int halo) {
  const int me = rank_of(c), np = size_of(c);
  double lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = g.origin[d];
    hi[d] = g.upper(d);
  }
  const double L = g.upper(0) - g.origin[0];
  const double f0 = np == 2 ? (me == 0 ? 0.0 : split) : double(me) / np;
  const double f1 = np == 2 ? (me == 0 ? split : 1.0) : double(me + 1) / np;
  lo[0] = g.origin[0] + f0 * L;
  hi[0] = g.origin[0] + f1 * L;
  grid.setup(g, c, lo, hi, halo);
}

}  // namespace mpm_test
