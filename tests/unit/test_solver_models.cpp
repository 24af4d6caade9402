// The pressure and coupling models of the solver (mpm/pressure_model.h, mpm/coupling_model.h):
// each options' choice gives the model whose answers the phases and the time-step check use, and
// those answers are the laws' (equation of state, incompressible fluid, the volume correction's
// period) computed here from the inputs alone.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "mpm/coupling_model.h"
#include "mpm/grid_fields.h"
#include "mpm/options.h"
#include "mpm/pressure_model.h"
#include "mpm/solver.h"

namespace {

mpm::Options options(bool projection, bool coupled) {
  mpm::Options o;
  o.projection = projection;
  o.coupled = coupled;
  o.eos.rho0 = 1000.0;
  o.eos.K = 2.0e7;
  return o;
}

TEST(PressureModel, EosCarriesTheEquationOfState) {
  const mpm::Options o = options(false, false);
  const auto m = mpm::PressureModel::make(o);
  EXPECT_FALSE(m->incompressible());
  EXPECT_EQ(m->solve(), nullptr);
  // linear law: rho = rho0 / (1 - p/K)
  EXPECT_NEAR(m->density(o.eos, 1.0e5), 1000.0 / (1.0 - 1.0e5 / 2.0e7), 1e-9);
  // c^2 = K rho0 / rho^2 falls with rho: the largest at the lowest density
  EXPECT_NEAR(m->sound_speed(o.eos, 990.0, 1010.0), std::sqrt(2.0e7 * 1000.0) / 990.0, 1e-9);
  mpm::Eos tait = o.eos;
  tait.kind = mpm::EosKind::Tait;
  // c^2 = K/rho0 (rho/rho0)^(gamma-1) grows with rho: the largest at the highest density
  EXPECT_NEAR(m->sound_speed(tait, 990.0, 1010.0), std::sqrt(2.0e7 / 1000.0 * std::pow(1.01, 6.0)), 1e-9);
  mpm::Clock clock;
  clock.dt = 0.012;
  mpm::SolverState st;
  for (clock.step = 0; clock.step < 12; ++clock.step) EXPECT_EQ(m->volume_correction_due(o, clock, st), 0.0);
  EXPECT_EQ(m->solver_seconds(), 0.0);
  EXPECT_EQ(m->solves(), 0);
}

TEST(PressureModel, ProjectionIsIncompressible) {
  mpm::Options o = options(true, false);
  const auto m = mpm::PressureModel::make(o);
  EXPECT_TRUE(m->incompressible());
  EXPECT_EQ(m->density(o.eos, 1.0e5), 1000.0);  // no pre-compression
  EXPECT_EQ(m->sound_speed(o.eos, 990.0, 1010.0), 0.0);
  EXPECT_EQ(m->solve(), nullptr);  // no grid yet
  // volume correction at rate k = 1/s over fluid steps of 0.012 s: every M = floor(0.05 / 0.012) = 4
  // steps, standing for M steps' time; the same with every auto at a constant step
  o.volume_correction = 1.0;
  mpm::Clock clock;
  clock.dt = 0.012;
  for (const bool every_auto : {false, true}) {
    o.every_auto = every_auto;
    mpm::SolverState st;
    std::vector<long> due;
    for (clock.step = 0; clock.step < 12; ++clock.step) {
      const double t = m->volume_correction_due(o, clock, st);
      if (t > 0.0) {
        due.push_back(clock.step);
        EXPECT_NEAR(t, 4 * 0.012, 1e-15);
      } else {
        EXPECT_EQ(t, 0.0);
      }
    }
    EXPECT_EQ(due, (std::vector<long>{0, 4, 8})) << "every auto " << every_auto;
  }
}

TEST(CouplingModel, NoneGivesTheGridUpdateNothing) {
  mpm::GridFields g;
  g.rx.assign(6, 1.0);
  g.th.assign(2, 0.5);
  const auto none = mpm::CouplingModel::make(options(false, false));
  EXPECT_EQ(none->fluid_force(g), nullptr);
  EXPECT_EQ(none->node_theta(g), nullptr);
  const auto grains = mpm::CouplingModel::make(options(false, true));
  EXPECT_EQ(grains->fluid_force(g), g.rx.data());
  EXPECT_EQ(grains->node_theta(g), g.th.data());
}

}  // namespace
