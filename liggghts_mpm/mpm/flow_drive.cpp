// keyword superficial_velocity: the fluid's mean volume flux along a periodic axis held at a target
// (docs/fix_mpm_fluid.md, "Driving a periodic flow"; docs/validation/fluidized_bed.md).
//
// A periodic box holds no mean pressure gradient: its pressure is periodic. The gradient that drives
// the flow through it, G (pressure per length, positive along +axis), acts as a uniform body force:
// on the fluid G per unit fluid volume (m / rho0 of each point), on each coupled grain G V_k, as a
// mean pressure gradient acts on every volume it holds. G is the one that makes the fluid's mean flux
// sum m v / (rho0 V_grid) equal to the target after each fluid step, found as OpenFOAM's
// meanVelocityForce finds it: the step runs with the last step's G (a body force on the points, the
// same path as fix addforce's), then the points' velocity along the axis gets the uniform increment
// du that brings the flux to the target, and G grows by rho0 du / h, so that G V_fluid h is the
// momentum the drive gave the fluid in the step. The flux then equals the target to round-off
// after every step, whatever the drag, walls or grains did in it; no controller gains.
#include <cmath>

#include "mpm/solver.h"

namespace mpm {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

void FluidSolver::drive_force() {
  const int a = opt.drive.axis;
  const double acc = state.drive_gradient / opt.rho0;
  for (int i = 0; i < pts.nlocal; ++i)
    if (is_point(i)) pts.f[i][a] += pts.rmass[i] * acc;
}

void FluidSolver::drive_correct(double hf) {
  const int a = opt.drive.axis;
  double loc[2] = {0.0, 0.0}, glob[2];  // momentum along the axis, mass
  for (int i = 0; i < pts.nlocal; ++i)
    if (is_point(i)) {
      loc[0] += pts.rmass[i] * pts.v[i][a];
      loc[1] += pts.rmass[i];
    }
  MPI_Allreduce(loc, glob, 2, MPI_DOUBLE, MPI_SUM, comm_);
  if (!(glob[1] > 0.0)) return;  // no fluid: no flux to hold
  const GridSpec &gs = opt.grid;
  const double vgrid = gs.ncell[0] * gs.dx * gs.ncell[1] * gs.dx * gs.ncell[2] * gs.dx;
  const double du = (opt.rho0 * opt.drive.target * vgrid - glob[0]) / glob[1];
  for (int i = 0; i < pts.nlocal; ++i)
    if (is_point(i)) pts.v[i][a] += du;
  state.drive_gradient += opt.rho0 * du / hf;
  coup_->drive_share(*this, a);
}

// the grains' share of the mean gradient, G V_k, with the fluid's force of this step (couple)
void FluidSolver::drive_grain_share(int a) {
  const double G = state.drive_gradient;
  for (int k = 0; k < pts.nlocal; ++k)
    if (is_grain(k)) {
      const double r = pts.radius[k];
      coup_->grain_force[3 * static_cast<std::size_t>(k) + a] += G * (4.0 / 3.0) * kPi * r * r * r;
    }
}

}  // namespace mpm
