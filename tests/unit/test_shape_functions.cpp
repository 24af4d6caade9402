// Shape functions: partition of unity, linear completeness (sum w_i x_i = x),
// gradients that sum to zero and match finite differences, compact support.
#include <gtest/gtest.h>

#include <cmath>

#include "mpm/shape_functions.h"

using mpm::Shape1D;
using mpm::ShapeKind;

namespace {

class ShapeTest : public ::testing::TestWithParam<ShapeKind> {};

TEST_P(ShapeTest, PartitionOfUnityAndLinearCompleteness) {
  for (double xi = -3.0; xi <= 5.0; xi += 0.0137) {
    Shape1D s;
    mpm::shape_eval(GetParam(), xi, s);
    double sum = 0.0, first = 0.0, dsum = 0.0, dfirst = 0.0;
    for (int a = 0; a < mpm::support(GetParam()); ++a) {
      EXPECT_GE(s.w[a], -1e-15);
      sum += s.w[a];
      first += s.w[a] * (s.base + a);
      dsum += s.dw[a];
      dfirst += s.dw[a] * (s.base + a);
    }
    EXPECT_NEAR(sum, 1.0, 1e-14) << "xi=" << xi;
    EXPECT_NEAR(first, xi, 1e-13) << "xi=" << xi;   // reproduces linear fields exactly
    EXPECT_NEAR(dsum, 0.0, 1e-14) << "xi=" << xi;   // gradient of a constant is zero
    EXPECT_NEAR(dfirst, 1.0, 1e-13) << "xi=" << xi; // gradient of x is one
  }
}

TEST_P(ShapeTest, GradientMatchesFiniteDifference) {
  const double h = 1e-6;
  for (double xi = 0.05; xi < 3.0; xi += 0.0931) {
    Shape1D s, sp, sm;
    mpm::shape_eval(GetParam(), xi, s);
    mpm::shape_eval(GetParam(), xi + h, sp);
    mpm::shape_eval(GetParam(), xi - h, sm);
    if (sp.base != s.base || sm.base != s.base) continue;  // kink of the support window
    for (int a = 0; a < mpm::support(GetParam()); ++a)
      EXPECT_NEAR(s.dw[a], (sp.w[a] - sm.w[a]) / (2 * h), 1e-7) << "xi=" << xi << " a=" << a;
  }
}

INSTANTIATE_TEST_SUITE_P(Kinds, ShapeTest,
                         ::testing::Values(ShapeKind::Linear, ShapeKind::QuadraticBSpline),
                         [](const auto &info) { return std::string(mpm::shape_name(info.param)); });

TEST(ShapeBSpline2, KnownValuesAndContinuity) {
  Shape1D s;
  mpm::shape_bspline2(2.0, s);  // on a node: 1/8, 3/4, 1/8
  EXPECT_EQ(s.base, 1);
  EXPECT_DOUBLE_EQ(s.w[0], 0.125);
  EXPECT_DOUBLE_EQ(s.w[1], 0.75);
  EXPECT_DOUBLE_EQ(s.w[2], 0.125);
  // C1: weight of one node is continuous with continuous slope across a cell centre
  const double xc = 2.5, e = 1e-9;
  Shape1D l, r;
  mpm::shape_bspline2(xc - e, l);
  mpm::shape_bspline2(xc + e, r);
  auto weight_of = [](const Shape1D &q, int node) {
    const int a = node - q.base;
    return (a >= 0 && a < 3) ? q.w[a] : 0.0;
  };
  for (int node = 1; node <= 4; ++node) EXPECT_NEAR(weight_of(l, node), weight_of(r, node), 1e-8);
}

TEST(ShapeBSpline2, ApicInertiaIsExact) {
  // D = sum_i w_i (x_i - x_p)^2 = 1/4 (cells^2) for every position: D^-1 = 4.
  for (double xi = 0.0; xi < 2.0; xi += 0.013) {
    Shape1D s;
    mpm::shape_bspline2(xi, s);
    double D = 0.0;
    for (int a = 0; a < 3; ++a) D += s.w[a] * (s.base + a - xi) * (s.base + a - xi);
    EXPECT_NEAR(1.0 / D, mpm::apic_dinv_bspline2(), 1e-12);
  }
}

TEST(ShapeLinear, ApicAffineEqualsGradientIdentity) {
  // For the tent function w_i D^-1 (x_i - x_p) = grad w_i, the identity the
  // fix relies on when it uses the velocity gradient as APIC affine field.
  for (double xi = 0.01; xi < 0.99; xi += 0.07) {
    Shape1D s;
    mpm::shape_linear(xi, s);
    double D = 0.0;
    for (int a = 0; a < 2; ++a) D += s.w[a] * (s.base + a - xi) * (s.base + a - xi);
    for (int a = 0; a < 2; ++a) EXPECT_NEAR(s.w[a] * (s.base + a - xi) / D, s.dw[a], 1e-12);
  }
}

}  // namespace
