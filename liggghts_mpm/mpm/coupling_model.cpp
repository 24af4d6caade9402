// The two coupling models (coupling_model.h): none, and the grains of keyword couple.
#include "mpm/coupling_model.h"

#include "mpm/grid_fields.h"
#include "mpm/solver.h"

namespace mpm {

class NoCoupling final : public CouplingModel {};

class GrainCoupling final : public CouplingModel {
 public:
  void setup(FluidSolver &s) override {
    if (!s.state.theta_initialized) s.init_theta();
  }
  void begin_step(FluidSolver &s) override { grain_force.assign(3 * static_cast<std::size_t>(s.pts.nlocal), 0.0); }
  // the host adds the state rows' force to the grains' forces on each of the N DEM steps this
  // fluid step covers (with every N; FixMpmFluid::add_grain_force), so that the grains receive the
  // impulse N dt F the fluid gave up
  void end_step(FluidSolver &s) override { s.store_grain_force(); }
  void drive_share(FluidSolver &s, int a) override { s.drive_grain_share(a); }
  void fraction(FluidSolver &s, double &timer) override {
    timed(timer, [&] {
      s.fluid_fraction();
      if (s.state.theta_initialized) s.refresh_pressure();
    });
  }
  void exchange(FluidSolver &s, double h, double &timer) override {
    timed(timer, [&] { s.couple_fluid_grains(h); });
  }
  const double *fluid_force(const GridFields &g) const override { return g.rx.data(); }
  const double *node_theta(const GridFields &g) const override { return g.th.data(); }
};

CouplingModel::~CouplingModel() = default;

std::unique_ptr<CouplingModel> CouplingModel::make(const Options &opt) {
  if (opt.coupled) return std::unique_ptr<CouplingModel>(new GrainCoupling());
  return std::unique_ptr<CouplingModel>(new NoCoupling());
}

}  // namespace mpm
