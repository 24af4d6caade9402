// The laws the solver's phases use, alone: the least-squares pressure fit at a node and the
// smoothing filter of the solid fraction (mpm/coupling.h), the (8-23) wall-traction factor
// (mpm/boundaries.h).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mpm/boundaries.h"
#include "mpm/coupling.h"
#include "mpm/grid_fields.h"

namespace {

// Moments of PfitRec from samples (offset from the node, weight, pressure).
void add_sample(double *c, const double o[3], double w, double p) {
  const double e[4] = {1.0, o[0], o[1], o[2]};
  for (int r = 0; r < 4; ++r) {
    c[mpm::PfitRec::R + r] += w * p * e[r];
    for (int q = 0; q < 4; ++q) c[mpm::PfitRec::MAT + 4 * r + q] += w * e[r] * e[q];
  }
}

TEST(SolverLaws, PressureFitReproducesALinearField) {
  const double dx = 0.01, p0 = 1234.5, b[3] = {9810.0, -20.0, 3.0};
  double c[mpm::PfitRec::N] = {0};
  std::mt19937_64 gen(3);
  std::uniform_real_distribution<double> u(-1.5 * dx, 1.5 * dx), w(0.1, 1.0);
  for (int s = 0; s < 30; ++s) {
    const double o[3] = {u(gen), u(gen), u(gen)};
    add_sample(c, o, w(gen), p0 + b[0] * o[0] + b[1] * o[1] + b[2] * o[2]);
  }
  double fit[4];
  ASSERT_TRUE(mpm::fit_linear_pressure(c, dx, fit));
  EXPECT_NEAR(fit[0], p0, 1e-9 * p0);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(fit[1 + d], b[d], 1e-7 * b[0]);
}

TEST(SolverLaws, PressureFitUndeterminedInOneLayer) {
  // all samples in one plane: the gradient across it is undetermined
  const double dx = 0.01;
  double c[mpm::PfitRec::N] = {0};
  for (int s = 0; s < 9; ++s) {
    const double o[3] = {(s % 3 - 1) * dx, (s / 3 - 1) * dx, 0.5 * dx};
    add_sample(c, o, 1.0, 100.0 + o[0]);
  }
  double fit[4];
  EXPECT_FALSE(mpm::fit_linear_pressure(c, dx, fit));
}

TEST(SolverLaws, SmoothingPassesGiveTheVariance) {
  // each pass adds dx^2 / 2 to the variance: L = dx needs 2 passes, L = 0 none
  EXPECT_EQ(mpm::smoothing_passes(0.0, 0.01), 0);
  EXPECT_EQ(mpm::smoothing_passes(0.01, 0.01), 2);
  EXPECT_EQ(mpm::smoothing_passes(0.015, 0.01), 5);
}

TEST(SolverLaws, SmoothingKeepsTheSolidVolume) {
  // a row of nodes, the two ends outside walls (V = 0): one pass keeps sum phi V exactly and a
  // uniform fraction uniform
  const int n = 8;
  const double V[n] = {0, 0.5, 1, 1, 1, 1, 0.5, 0};
  const double phi[n] = {0, 0.6, 0.1, 0.0, 0.3, 0.2, 0.5, 0};
  double total = 0, after = 0;
  for (int j = 0; j < n; ++j) total += phi[j] * V[j];
  for (int j = 0; j < n; ++j) {
    const double Vn[2] = {j > 0 ? V[j - 1] : 0, j + 1 < n ? V[j + 1] : 0};
    const double pn[2] = {j > 0 ? phi[j - 1] : 0, j + 1 < n ? phi[j + 1] : 0};
    const bool has[2] = {j > 0, j + 1 < n};
    after += mpm::smoothing_step(V[j], phi[j], Vn, pn, has) * V[j];
    const double uni[2] = {0.4, 0.4};
    if (V[j] > 0) EXPECT_NEAR(mpm::smoothing_step(V[j], 0.4, Vn, uni, has), 0.4, 1e-15);
  }
  EXPECT_NEAR(after, total, 1e-15);
}

TEST(SolverLaws, FaceTractionIsAnEighthOfThePush) {
  // the first node inside a wall has the B-spline weight 1/8 on it: 1/8 of p V / dx, towards the fluid
  EXPECT_DOUBLE_EQ(mpm::face_traction_push(1, 2000.0, 1e-6, 100.0), 0.125 * 2000.0 * 1e-6 * 100.0);
  EXPECT_DOUBLE_EQ(mpm::face_traction_push(-1, 2000.0, 1e-6, 100.0), -0.125 * 2000.0 * 1e-6 * 100.0);
}

}  // namespace
