// Equation of state, Navier-Poisson stress and time-step limits against
// hand-computed values.
#include <gtest/gtest.h>

#include <cmath>

#include "mpm/fluid_laws.h"

namespace {

TEST(EosLinear, MatchesEq723AndInverts) {
  mpm::Eos e;
  e.kind = mpm::EosKind::Linear;
  e.rho0 = 1000.0;
  e.K = 2.2e9;
  EXPECT_DOUBLE_EQ(e.pressure(1000.0), 0.0);
  // (7-23): rho = rho0 / (1 - p/K); p = 2.2e7 -> rho = 1000/0.99
  EXPECT_NEAR(e.pressure(1000.0 / 0.99), 2.2e7, 1e-6);
  for (double p : {-1e5, 0.0, 1e4, 3.9e4, 1e7})
    EXPECT_NEAR(e.pressure(e.density(p)), p, 1e-9 * std::max(1.0, std::fabs(p)));
  // small-strain limit: dp = K drho/rho; c^2 = K/rho0 at rho0
  EXPECT_NEAR(e.sound_speed_sq(1000.0), 2.2e6, 1e-6);
  const double h = 1e-4;
  EXPECT_NEAR((e.pressure(1000.0 + h) - e.pressure(1000.0 - h)) / (2 * h), e.sound_speed_sq(1000.0), 1e-2);
}

TEST(EosTait, SameStiffnessAtRestAndInverts) {
  mpm::Eos e;
  e.kind = mpm::EosKind::Tait;
  e.rho0 = 1000.0;
  e.K = 2.0e7;
  e.gamma = 7.0;
  EXPECT_DOUBLE_EQ(e.pressure(1000.0), 0.0);
  // p = K/gamma ((rho/rho0)^7 - 1): rho = 1010 -> 2e7/7 * (1.01^7 - 1)
  EXPECT_NEAR(e.pressure(1010.0), 2.0e7 / 7.0 * (std::pow(1.01, 7) - 1.0), 1e-6);
  EXPECT_NEAR(e.sound_speed_sq(1000.0), 2.0e4, 1e-9);
  for (double p : {-1e5, 0.0, 1e4, 1e6}) EXPECT_NEAR(e.pressure(e.density(p)), p, 1e-8 * std::max(1.0, std::fabs(p)));
  // Tait stiffens under compression, the linear law softens
  mpm::Eos lin = e;
  lin.kind = mpm::EosKind::Linear;
  EXPECT_GT(e.sound_speed_sq(1050.0), lin.sound_speed_sq(1050.0));
}

TEST(NavierPoisson, SimpleShearAndTraceFree) {
  // simple shear v_x = G y: L[0][1] = G, tau_xy = eta G, no normal stress
  const double eta = 1e-3, G = 10.0;
  const double L[3][3] = {{0, G, 0}, {0, 0, 0}, {0, 0, 0}};
  double tau[6];
  mpm::newtonian_deviatoric_stress(eta, L, tau);
  EXPECT_DOUBLE_EQ(tau[5], eta * G);
  EXPECT_DOUBLE_EQ(tau[0], 0.0);
  EXPECT_DOUBLE_EQ(tau[3], 0.0);
  EXPECT_DOUBLE_EQ(tau[4], 0.0);
  // uniform expansion: deviatoric part vanishes (pressure is the EOS' job)
  const double E[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mpm::newtonian_deviatoric_stress(eta, E, tau);
  for (double t : tau) EXPECT_NEAR(t, 0.0, 1e-18);
  // uniaxial stretch: tau_xx = 2 eta (1 - 1/3), trace free
  const double U[3][3] = {{1, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  mpm::newtonian_deviatoric_stress(eta, U, tau);
  EXPECT_NEAR(tau[0], 2 * eta * 2.0 / 3.0, 1e-18);
  EXPECT_NEAR(tau[0] + tau[1] + tau[2], 0.0, 1e-18);
}

TEST(TimeStepLimits, AcousticAndViscous) {
  // real water, MPM32 cell: c = sqrt(2.2e9/1000) = 1483.2 m/s
  const double c = std::sqrt(2.2e9 / 1000.0);
  EXPECT_NEAR(mpm::acoustic_dt_limit(0.5, 0.125, c, 0.0), 0.5 * 0.125 / c, 1e-15);
  EXPECT_LT(mpm::acoustic_dt_limit(0.5, 0.125, c, 10.0), mpm::acoustic_dt_limit(0.5, 0.125, c, 0.0));
  // dt = 1e-5 of the dissertation is stable there, 1e-4 is not
  EXPECT_GT(mpm::acoustic_dt_limit(0.5, 0.125, c, 10.0), 1e-5);
  EXPECT_LT(mpm::acoustic_dt_limit(0.5, 0.125, c, 10.0), 1e-4);
  EXPECT_NEAR(mpm::viscous_dt_limit(0.01, 1000.0, 1.0, 3), 1e-4 * 1000.0 / 6.0, 1e-15);
  EXPECT_TRUE(std::isinf(mpm::viscous_dt_limit(0.01, 1000.0, 0.0, 3)));
}

TEST(PoreWave, CoupledAndGrainSpeeds) {
  // water (c_f = 1483 m/s) in a bed of glass beads, theta = 0.4: r = 1000 * 0.6 / (0.4 * 2500) = 0.6
  const double cf = 1483.0, r = 1000.0 * 0.6 / (0.4 * 2500.0);
  EXPECT_DOUBLE_EQ(mpm::coupled_wave_speed(cf, r), cf * std::sqrt(1.6));
  EXPECT_DOUBLE_EQ(mpm::grain_wave_speed(cf, r), cf * std::sqrt(0.6));
  // c^2 = c_f^2 + c_g^2; no grains (r = 0): the fluid's own speed, no grain wave
  EXPECT_NEAR(std::pow(mpm::coupled_wave_speed(cf, r), 2),
              cf * cf + std::pow(mpm::grain_wave_speed(cf, r), 2), 1e-9 * cf * cf);
  EXPECT_DOUBLE_EQ(mpm::coupled_wave_speed(cf, 0.0), cf);
  EXPECT_DOUBLE_EQ(mpm::grain_wave_speed(cf, 0.0), 0.0);
}

}  // namespace
