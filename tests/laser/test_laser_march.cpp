// The implicit march of the face heat fluxes (--heat-march implicit, docs/theory/laser_model.md
// 2.12): a column's outflow leaves at a temperature proportional to its new heat content
// (backward Euler), so at any heat Courant number C = dtau qout / (a g) it sends (E - 1)/E of what
// it holds and receives, never more, its content stays >= 0, and along a chain of columns the
// face fluxes telescope: the contents change by what the layers' gradients gave minus what left
// over the rim, to round-off.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "laser_laws.h"
#include "laser_model.h"
#include "laser_params.h"

using namespace laser;

namespace {
const Material kMat{};  // Table 5.1
const double kR = 0.254e-3, kI0 = 7.5e10;

// b2 held to the monotone profile |b2| g^2 <= theta_sat, as the march's limiter does
double limited(double b2, double g, double th) {
  const double bmax = std::max(th, 0.0) / (g * g);
  return std::fabs(b2) > bmax ? std::copysign(bmax, b2) : b2;
}
}  // namespace

// One column at C from 0.1 to 1000 (no inflow: the centre column, the hardest case; and with
// inflow): the root satisfies the profile's content (unlimited b2), and with the limited b2 the
// column's content is >= 0, its outflow over the step is below what it holds and receives, and
// its balance H - H_old = dtau (2 b2 g - (qout theta_out - hin) / a) holds to round-off.
TEST(LaserHeatMarch, ImplicitColumnNeverSendsMoreThanItHolds) {
  const Groups G = make_groups(kMat, kI0, kR);
  const double a = 1e-3, dtn = 1e-4;
  int checked = 0, limited_count = 0;
  for (bool adv : {false, true}) {
    for (double g : {2e-2, 8e-2}) {
      const InterfaceState from = solve_interface(G, 0.5, g, 0.0, adv);
      const double H_full = layer_content(from, g, 0.0);
      for (double C : {0.1, 1.0, 10.0, 100.0, 1000.0}) {
        const double qout = C * a * g / dtn;
        for (double hin : {0.0, 0.5 * qout * from.theta_sat}) {
          for (double H_old : {0.0, 0.5 * H_full, H_full}) {
            const ImplicitHeatColumn c = solve_implicit_heat_column(G, 0.5, g, a, qout, hin, dtn, H_old, adv, from);
            const double th = c.itf.theta_sat;
            ASSERT_TRUE(std::isfinite(th) && std::isfinite(c.b2)) << adv << " " << g << " " << C;
            EXPECT_LT(std::fabs(c.itf.residual), 1e-10);
            const double H_root = implicit_heat_content(c, g, a, hin, dtn, H_old, c.b2);
            EXPECT_NEAR(H_root, layer_content(c.itf, g, c.b2), 1e-9 * (H_full + H_old + dtn * hin / a))
                << adv << " " << g << " " << C << " " << hin << " " << H_old;
            const double b2 = limited(c.b2, g, th);
            limited_count += b2 != c.b2;
            const double H = implicit_heat_content(c, g, a, hin, dtn, H_old, b2);
            const double holds = H_old + dtn * (2.0 * b2 * g + hin / a);  // what it holds and receives
            const double out = dtn * qout * c.lambda * H / (g * a);       // what it sends
            EXPECT_GE(H, 0.0) << adv << " " << g << " " << C << " " << hin << " " << H_old;
            EXPECT_LE(out, holds * (1.0 + 1e-14)) << adv << " " << g << " " << C;
            EXPECT_NEAR(H - H_old, dtn * (2.0 * b2 * g - (qout * c.lambda * H / g - hin) / a),
                        1e-13 * (std::fabs(holds) + std::fabs(out) + H_old))
                << adv << " " << g << " " << C;
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 120);
  EXPECT_GT(limited_count, 0);  // the limiter does act at large C without inflow (the profile's bound)
}

// A chain of columns marched with the flow (areas 2 pi xi d(xi) as on the grid, a face rate
// c_k g^2 from each column to the next, the last face over the rim) at C up to about 500: the
// heat the contents gained equals what the layers' gradients gave (2 b2 g a) minus what left over
// the rim, to round-off, and no content goes negative.
TEST(LaserHeatMarch, ImplicitChainConservesHeat) {
  const Groups G = make_groups(kMat, kI0, kR);
  const double dxi = 0.05;
  for (bool adv : {false, true}) {
    for (double dtn : {1e-6, 1e-4, 1e-2}) {
      const int N = 8;
      double gained = 0.0, given = 0.0, theta_up = 0.0, q_up = 0.0, scale = 0.0;
      for (int i = 1; i <= N; ++i) {
        const double xi = i * dxi, a = 2.0 * kPi * xi * dxi, g = 0.03 + 0.004 * i;
        const double qout = 2.0 * kPi * (xi + 0.5 * dxi) * 40.0 * g * g;  // face rate x g_up^2
        const double hin = q_up * theta_up;
        const InterfaceState from = solve_interface(G, xi, g, 0.0, adv);
        const double H_old = 0.7 * layer_content(from, g, 0.0);
        const ImplicitHeatColumn c = solve_implicit_heat_column(G, xi, g, a, qout, hin, dtn, H_old, adv, from);
        const double b2 = limited(c.b2, g, c.itf.theta_sat);
        const double H = implicit_heat_content(c, g, a, hin, dtn, H_old, b2);
        EXPECT_GE(H, 0.0) << adv << " " << dtn << " " << i;
        gained += a * (H - H_old);
        given += dtn * a * 2.0 * b2 * g;
        scale += a * (H + H_old) + std::fabs(dtn * a * 2.0 * b2 * g);
        theta_up = c.lambda * H / g;
        q_up = qout;
      }
      const double rim = dtn * q_up * theta_up;
      EXPECT_NEAR(gained, given - rim, 1e-13 * (scale + rim)) << adv << " " << dtn;
    }
  }
}

// The whole model at Pr 1420 (the shipped Pr 142 config, 50 us, d(xi) 0.025) at dt 1e-6 s, where
// the explicit march's heat Courant number is far above 1: the implicit march keeps the melt
// volume balance and every column within its energy bound, and the b2 limiter acts less often.
TEST(LaserHeatMarchRun, Prandtl1420CoarseStepStaysConservative) {
  auto run = [](HeatMarch march) {
    Config c;
    read_config_file(c, std::string(LASER_INPUTS_DIR) + "/prandtl142.toml");
    c.mat.Pr = 1420;
    c.tp = 50e-6;
    c.dxi = 0.025;
    c.dt = 1e-6;
    c.heat_march = march;
    c.quiet = true;
    validate(c);
    return run_simulation(c);
  };
  const Result ex = run(HeatMarch::Explicit), im = run(HeatMarch::Implicit);
  EXPECT_NE(im.status, "diverged") << im.message;
  EXPECT_LT(std::fabs(im.melt_balance), 1e-12);
  EXPECT_LT(im.check.worst_node_ratio, 1.0);
  EXPECT_LT(im.b2_clamps, ex.b2_clamps);
  std::printf("[ MARCH ] dt 1e-6 s: b2 limiter hits explicit %d, implicit %d; depth %.4f / %.4f um\n", ex.b2_clamps,
              im.b2_clamps, ex.depth_center * 1e6, im.depth_center * 1e6);
}
