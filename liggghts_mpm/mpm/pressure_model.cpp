// The two pressure models (pressure_model.h): the equation of state and the projection.
#include "mpm/pressure_model.h"

#include <algorithm>
#include <cmath>

#include "mpm/projection.h"
#include "mpm/solver.h"

namespace mpm {

class EosPressure final : public PressureModel {
 public:
  EosPressure() : PressureModel(false) {}
  double density(const Eos &eos, double p) const override { return eos.density(p); }
  // largest over the density range: Tait stiffens under compression, the linear law under tension
  double sound_speed(const Eos &eos, double rho_lo, double rho_hi) const override {
    return std::sqrt(std::max(eos.sound_speed_sq(rho_hi), eos.sound_speed_sq(rho_lo)));
  }
  void particles_to_grid(FluidSolver &s) override { s.p2g(true); }
  void update_grid(FluidSolver &s, double h, double) override { s.grid_velocity(h, true); }
  void update_stress(FluidSolver &s, double h, bool theta_only) override { s.eos_stress(h, theta_only); }
};

class ProjectionPressure final : public PressureModel {
 public:
  ProjectionPressure() : PressureModel(true) {}
  double density(const Eos &eos, double) const override { return eos.rho0; }  // incompressible
  double sound_speed(const Eos &, double, double) const override { return 0.0; }

  // the last solve goes on into the new patch (the warm start, the grains' pressure gradient, the
  // d(theta)/dt source), so that run N; run M equals run N+M: from the old Projection (its owned
  // box, or the whole grid if a rank's box changed), else from a restart file
  void leave_patch() override {
    last_ = ProjectionState();
    if (!proj_) return;
    proj_->save(last_);
    seconds_before_ += proj_->solver_seconds();
    solves_before_ += proj_->solves();
    iterations_before_ += proj_->iterations_summed();
  }
  void enter_patch(LocalGrid &grid, MPI_Comm comm, const Options &opt, SolverState &state) override {
    proj_.reset(new Projection(grid, comm, opt));
    if (last_.valid) {
      const IndexBox &ob = grid.owned();
      int same = 1, all = 0;
      for (int d = 0; d < 3; ++d)
        if (ob.lo[d] != last_.box.lo[d] || ob.hi[d] != last_.box.hi[d]) same = 0;
      MPI_Allreduce(&same, &all, 1, MPI_INT, MPI_MIN, comm);
      if (!all) last_ = gather_global(last_, opt.grid, comm);
      proj_->load(last_);
    } else if (state.projection.valid) {
      proj_->load(state.projection);
    }
    last_ = ProjectionState();
    state.projection = ProjectionState();  // read once
  }
  ProjectionState restart_state(const Options &opt, MPI_Comm comm, SolverState &state) override {
    if (!proj_) return state.projection;
    ProjectionState local;
    proj_->save(local);
    return gather_global(local, opt.grid, comm);
  }
  // the volume correction runs on every M-th fluid step (its first sub-step), removing the share
  // min(k M hf, 1) of the volume error each time (Projection::volume_correction_every)
  double volume_correction_due(const Options &opt, const Clock &clock, SolverState &state) override {
    if (!(opt.volume_correction > 0.0)) return 0.0;
    double vc_time = 0.0;
    const double hf = opt.fluid_every * clock.dt;
    const long every = Projection::volume_correction_every(opt.volume_correction, hf);
    if (!opt.every_auto) {
      if ((clock.step / opt.fluid_every) % every == 0) vc_time = every * hf;
    } else {
      // N varies: the correction's period every * hf is counted down in time
      if (state.vc_due <= 0.5 * hf) {
        vc_time = every * hf;
        state.vc_due = vc_time;
      }
      state.vc_due -= hf;
    }
    return vc_time;
  }

  void particles_to_grid(FluidSolver &s) override { s.p2g(false); }
  void update_grid(FluidSolver &s, double h, double vc_time) override {
    s.grid_velocity(h, false);
    s.project_velocity(*proj_, pvol_, h, vc_time);
  }
  void point_pressure(FluidSolver &s) override { s.interpolate_pressure(proj_->pressure()); }
  void update_stress(FluidSolver &s, double, bool theta_only) override { s.incompressible_stress(theta_only); }

  Projection *solve() override { return proj_.get(); }
  const std::vector<double> *volume_drift() const override { return proj_ ? &proj_->volume_drift() : nullptr; }
  // since the solver was made: the Projection of each grid patch (a new one at every re-cut) adds
  // to what the ones before it counted
  double solver_seconds() const override { return seconds_before_ + (proj_ ? proj_->solver_seconds() : 0.0); }
  long solves() const override { return solves_before_ + (proj_ ? proj_->solves() : 0); }
  long iterations_summed() const override { return iterations_before_ + (proj_ ? proj_->iterations_summed() : 0); }

 private:
  std::unique_ptr<Projection> proj_;
  ProjectionState last_;      // the old patch's solve, between leave_patch and enter_patch
  std::vector<double> pvol_;  // volume_correction: sum S V of the points per node
  double seconds_before_ = 0.0;
  long solves_before_ = 0, iterations_before_ = 0;
};


PressureModel::~PressureModel() = default;

std::unique_ptr<PressureModel> PressureModel::make(const Options &opt) {
  if (opt.projection) return std::unique_ptr<PressureModel>(new ProjectionPressure());
  return std::unique_ptr<PressureModel>(new EosPressure());
}

}  // namespace mpm
