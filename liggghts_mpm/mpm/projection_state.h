// The state of the pressure projection that outlives one grid patch: restart files and a new
// grid patch at the next run (mpm/projection_state.cpp).
#pragma once
#include <mpi.h>

#include <cstddef>
#include <vector>

#include "mpm/grid.h"

namespace mpm {

// pressure projection: what the next fluid step reads of the last solve (restart files, a new
// grid patch at the next run): the nodal pressure (the solve's warm start), its nodal gradient
// (the grains' pressure force of the next step), theta of the last solve (the d(theta)/dt
// source) and the grains' levels (their immersion at the next step), on a box of global node
// indices, i fastest. Written by Projection::save, read by Projection::load
// (mpm/projection_state.cpp, like the functions below).
struct ProjectionState {
  bool valid = false;
  IndexBox box;                  // the nodes held: one rank's owned box, or the whole grid
  bool have_theta_last = false;  // theta_last holds values (couple, after the first solve)
  int iterations = 0;            // of the last solve (f_ID[16], f_ID[17])
  double residual = 0.0;
  bool have_avg = false;         // p_avg holds values (pressure_average, after the first solve)
  bool have_acc = false;         // p_acc holds values (pressure_output acceleration: its warm start)
  bool have_grain_level = false; // grain_level holds values (couple, after the first solve)
  // 1, 3, 1, 1, 1, 1 per node of box (grain_level: Projection::grain_level, the grains' immersion
  // at the next step)
  std::vector<double> p, grad, theta_last, p_avg, p_acc, grain_level;
  // appends the restart block (doubles); unpack reads one at in and returns the doubles read
  void pack(std::vector<double> &out) const;
  std::size_t unpack(const double *in);
};
// The states of all ranks (their owned boxes) as one state on the whole grid, node_lo..node_hi of
// spec, on every rank (collective over comm; values copied, not summed).
ProjectionState gather_global(const ProjectionState &local, const GridSpec &spec, MPI_Comm comm);

}  // namespace mpm
