// The state FluidSolver keeps per axis of the model (docs/design.md, "The solver's axes"): the
// points' work arrays of the core, the time-step limits, the outputs' series, sums and timers.
// Each is owned by one FluidSolver and read by the phases of its axis only; the pressure model's
// and the coupling's state live behind their interfaces (mpm/pressure_model.h,
// mpm/coupling_model.h).
#pragma once
#include <mpi.h>

#include <cmath>
#include <cstddef>
#include <memory>
#include <vector>

#include "mpm/stencil.h"

namespace mpm {

class Hdf5Series;

// wall time of a phase, added to acc (f_ID[14], f_ID[15])
template <class Fn>
inline void timed(double &acc, Fn &&fn) {
  const double t0 = MPI_Wtime();
  fn();
  acc += MPI_Wtime() - t0;
}

// core: the points of this sub-step, their stencils and the grid velocity and gradient at them
struct PointWork {
  std::vector<Stencil> shapes;
  std::vector<int> plist;       // local indices of the material points (this sub-step)
  std::vector<double> vpic;     // grid (PIC) velocity at the points, for the position update
  std::vector<double> velgrad;  // velocity gradient at the points, for the stress update (APIC only)
  // the velocity gradient of the last transfer sits in the points' affine record (FLIP and PIC,
  // whose affine record holds nothing else), not in velgrad: 9 doubles per point less, allocated
  // with APIC only
  bool grad_in_state = false;
  // anti-locking (eos): the node index of each point's cell, and whether the MUSL gradient pass
  // has already summed the cells of this sub-step's stress update (sum_cell)
  std::vector<std::size_t> pcell;
  bool cells_summed = false;
  // compute_shapes: the smallest and largest stencil base of this rank's points (INT_MAX / INT_MIN
  // without any), for the projection's work box
  int base_lo[3] = {0, 0, 0}, base_hi[3] = {-1, -1, -1};
  long gone = 0;  // points of this rank that left through an outflow face in the last fluid step
};

// core: the grid constants shape_at takes once per grid set-up, and setup_grid's subdomain and
// skin (outside_patch)
struct ShapeCtx {
  double inv = 0.0;  // 1 / dx
  double origin[3] = {0, 0, 0};
  double ncell[3] = {0, 0, 0};
  bool periodic[3] = {false, false, false};
  // the nodes a stencil may use: the patch less the layers read beyond a stencil (mesh walls)
  // where the patch does not end at a grid face; a stencil's last node within hi
  int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  double skin = 0.0, sub_lo[3] = {0, 0, 0}, sub_hi[3] = {0, 0, 0};
};

// time step (timestep.cpp): the limits and diagnostics of the last check
struct StepLimits {
  double dt_stable = 0.0, c_max = 0.0;
  double dt_couple = HUGE_VAL, dt_grain = HUGE_VAL, c_couple = 0.0, c_grain = 0.0;
  double couple_theta_min = 1.0, couple_rho_grain = 0.0;
  double rho_range[2] = {0.0, 0.0};  // lowest and highest density of the points at the last check
  bool range_warned = false;         // range_warning() given in this run
  double p_max = 0.0, p_scale = 0.0;  // pressure eos: largest point pressure, rho0 (|a| H + |v|^2)
  double vmax = 0.0;                 // |v|max of the points at the last time-step check
  // every auto: the limits of the last check besides the fluid's own, and the one that set N
  struct EveryAuto {
    double grain_speed = 0.0;     // |v|max of the coupled grains
    double accel = 0.0;           // |f/m|max of the points' external forces (gravity)
    double wall_speed = 0.0;      // |w|max of the mesh walls' triangles near this rank
    double grain_tau = HUGE_VAL;  // shortest drag response time m/K of a moving grain, all ranks
    double limit = HUGE_VAL;      // the step N dt must not exceed
    const char *which = "";
  } every;
};

// io: the HDF5 + XDMF series, the mesh walls' loads and the probes' sums, the wall-time counters
struct OutputState {
  std::unique_ptr<Hdf5Series> series;
  long last_step = -1;  // the step last written
  // wall time in write_output on this rank (s, cumulative) and the step files written
  double time_output = 0.0;
  long n_outputs = 0;
  // wall time of the fluid's own work and of the coupling on this rank (s, cumulative)
  double time_fluid = 0.0, time_couple = 0.0;
  // wall_loads.cpp: per node the fluid mass and (pressure eos) mass times the points' pressure,
  // of this sub-step (owned and halos); the mesh walls' loads (6 per wall) and the probes' sums
  // (p h, h) summed over this fluid step's sub-steps on this rank, and their time
  std::vector<double> wmp;
  std::vector<double> wall_sum, wall_mean;
  double wall_time = 0.0;
  std::vector<double> probe_sum, probe_mean;  // 2 per probe: sum p h (local), sum h
  double probe_time = 0.0;
  double p_surface = 0.0;  // pressure projection: the solve's pressure at the free surface (this sub-step)
  OutputState();
  ~OutputState();
};

}  // namespace mpm
