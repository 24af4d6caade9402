// The heat Courant limit of the face heat fluxes (--heat-courant 0.5, docs/theory/laser_model.md 2.11): at
// Pr = 1420 (the shipped Pr = 142 config with a ten times larger Prandtl number, 200 us)
// the b2 limiter of (4-25) does not act at any step of a dt ladder or any grid of a d(xi)
// ladder, no column takes more than its energy bound, and centre depth, removed volume and
// the flow's share converge: the step ladder to 2e-3 between neighbours, with the differences
// falling, the grid ladder monotone at an observed order above 0.7 (measured 0.9-1.2).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "laser_model.h"
#include "laser_params.h"
#include "laser_timestep.h"
#include "laser_quarter_step.h"

using namespace laser;

namespace {
struct Point {
  double depth, volume, share;
};

Point run_pr1420(double dxi, double dt, long* substeps = nullptr) {
  Config c;
  read_config_file(c, std::string(LASER_INPUTS_DIR) + "/prandtl142.toml");
  c.mat.Pr = 1420;
  c.heat_courant = 0.5;
  c.tp = 200e-6;
  c.dxi = dxi;
  c.dt = dt;
  c.quiet = true;
  validate(c);
  const Result r = run_simulation(c);
  EXPECT_EQ(r.status, "ok") << "d(xi) " << dxi << ", dt " << dt << ": " << r.message;
  EXPECT_EQ(r.b2_clamps, 0) << "d(xi) " << dxi << ", dt " << dt;
  EXPECT_EQ(r.curvature_clamps, 0) << "d(xi) " << dxi << ", dt " << dt;
  EXPECT_LT(r.check.worst_node_ratio, 1.0) << "d(xi) " << dxi << ", dt " << dt;
  if (substeps) *substeps = r.heat_substeps_max;
  const Point p{r.depth_center, r.volume_removed, r.volume_expelled / r.volume_removed};
  std::printf("[ PR1420 ] d(xi) %.5f dt %.4g s: depth %.4f um, volume %.5e m3, flow share %.5f, b2 hits %d, "
              "most heat sub-steps %ld\n", dxi, dt, p.depth * 1e6, p.volume, p.share, r.b2_clamps,
              r.heat_substeps_max);
  return p;
}

double rel(double a, double b) { return std::fabs(a / b - 1.0); }
// The shipped Pr 142 config at Pr 1420 with the heat Courant limit X, 50 us, d(xi) 0.025, quiet
Config prandtl1420(double X) {
  Config c;
  read_config_file(c, std::string(LASER_INPUTS_DIR) + "/prandtl142.toml");
  c.mat.Pr = 1420;
  c.heat_courant = X;
  c.tp = 50e-6;
  c.dxi = 0.025;
  c.quiet = true;
  validate(c);
  return c;
}

}  // namespace

TEST(LaserCourant, Prandtl1420StepLadderConvergesWithoutLimiter) {
  std::vector<Point> p;
  long sub_coarse = 0;
  for (double dt : {1e-6, 5e-7, 2.5e-7, 1.25e-7}) p.push_back(run_pr1420(0.0125, dt, p.empty() ? &sub_coarse : nullptr));
  EXPECT_GT(sub_coarse, 1);  // the limit acts at the coarsest step
  for (size_t k = 0; k + 1 < p.size(); ++k) {
    EXPECT_LT(rel(p[k].depth, p[k + 1].depth), 2e-3) << k;
    EXPECT_LT(rel(p[k].volume, p[k + 1].volume), 2e-3) << k;
    EXPECT_LT(std::fabs(p[k].share - p[k + 1].share), 2e-3) << k;
  }
  EXPECT_LT(rel(p[2].depth, p[3].depth), 0.5 * rel(p[0].depth, p[1].depth));
}

TEST(LaserCourant, Prandtl1420GridLadderConvergesWithoutLimiter) {
  std::vector<Point> p;
  for (double dxi : {0.05, 0.025, 0.0125}) p.push_back(run_pr1420(dxi, 2.5e-7));
  auto order = [&](double Point::*q) {
    const double d1 = p[1].*q - p[0].*q, d2 = p[2].*q - p[1].*q;
    EXPECT_GT(d1 * d2, 0.0);  // monotone
    return std::log2(std::fabs(d1 / d2));
  };
  const double od = order(&Point::depth), ov = order(&Point::volume), os = order(&Point::share);
  std::printf("[ PR1420 ] d(xi) orders: depth %.2f, volume %.2f, flow share %.2f\n", od, ov, os);
  EXPECT_GT(od, 0.7);
  EXPECT_GT(ov, 0.7);
  EXPECT_GT(os, 0.7);
}

// The automatic step at Pr = 1420 with the heat Courant limit (50 us, d(xi) 0.025): the b2
// limiter never acts, no column takes more than its energy bound, the melt volume balance
// closes, the step control accepts its three-level estimate (the only cause the run may name
// is the grid estimate: d(xi) 0.025 against 0.05 is not converged at this Prandtl number), and
// a run at a quarter of the reported step moves centre depth and removed volume by less than
// the step's estimate.
TEST(LaserCourant, Prandtl1420StaysWithinItsEstimate) {
  const Config c = prandtl1420(0.5);
  const Result r = TimeStepPolicy(c).run(c, nullptr);
  ASSERT_TRUE(r.status == "ok" || r.status == "inaccurate") << r.status << ": " << r.message;
  for (const auto& cause : r.causes) EXPECT_EQ(cause, "grid error estimate above --tol") << r.message;
  EXPECT_EQ(r.b2_clamps, 0);
  EXPECT_LT(r.check.worst_node_ratio, 1.0);
  EXPECT_LT(std::fabs(r.melt_balance), 1e-6);
  const QuarterStepChange qs = quarter_step_change(c, r);
  const double dd = qs.depth, dv = qs.volume;
  std::printf("[ PR1420 ] automatic: %s, dt %.4g s, runs %d; at dt/4 depth %.3e (estimate %.3e), volume %.3e "
              "(estimate %.3e); melt balance %.2e, column %.3f\n", r.status.c_str(), r.dt, r.step.runs, dd,
              r.step.depth_error, dv, r.step.volume_error, r.melt_balance, r.check.worst_node_ratio);
  EXPECT_LT(dd, r.step.depth_error);
  EXPECT_LT(dv, r.step.volume_error);
}

// The heat Courant start of the automatic ladder (docs 2.10): the halvings skipped after a first
// run whose steps the limit split into mbar sub-steps on average are ceil(log2 mbar) - 1 above
// mbar = 4 (the reported run, at half the coarse step, expected unsplit), none at or below it.
TEST(LaserCourant, SkipCountFollowsTheFirstRunsSplit) {
  Result r;
  auto skip = [&](long steps, long extra) {
    r.steps = static_cast<int>(steps);
    r.heat_substeps_extra = extra;
    return TimeStepPolicy::heat_courant_skip(r);
  };
  EXPECT_EQ(skip(201, 7209), 5);  // Pr 1420, 700 us, X = 0.5: mbar 36.9
  EXPECT_EQ(skip(200, 417), 0);   // Pr 142, X = 0.5: mbar 3.09
  EXPECT_EQ(skip(100, 300), 0);   // mbar 4: not above the threshold
  EXPECT_EQ(skip(100, 301), 2);   // mbar 4.01: log2 just above 2
  EXPECT_EQ(skip(100, 700), 2);   // mbar 8
  EXPECT_EQ(skip(100, 701), 3);
  EXPECT_EQ(skip(100, 0), 0);     // not split
  EXPECT_EQ(skip(0, 0), 0);       // no steps
}

// The skip in a run (Pr 1420, 50 us, d(xi) 0.025, X = 0.1, first run split into about 7): the
// reported run names the skip, its steps are not split beyond kMaxSubstepShare, its three-level
// estimate is accepted (the only cause the grid's), and it starts below the automatic step by
// the halvings skipped.
TEST(LaserCourant, SplitFirstRunSkipsToTheUnsplitLevel) {
  const Config c = prandtl1420(0.1);
  const TimeStepPolicy p(c);
  const Result r = p.run(c, nullptr);
  ASSERT_TRUE(r.status == "ok" || r.status == "inaccurate") << r.status << ": " << r.message;
  for (const auto& cause : r.causes) EXPECT_EQ(cause, "grid error estimate above --tol") << r.message;
  bool named = false;
  for (const auto& n : r.notes) named = named || n.find("the ladder skipped 2 halvings") != std::string::npos;
  EXPECT_TRUE(named);
  EXPECT_LE(double(r.heat_substeps_extra) / r.steps, TimeStepPolicy::kMaxSubstepShare);
  EXPECT_LE(r.dt, p.dt() / 4.0 * (1.0 + 1e-12));
  EXPECT_LE(std::max(r.step.depth_error, r.step.volume_error), c.tol);
  EXPECT_EQ(r.b2_clamps, 0);
}

// The first run of an automatic ladder is judged on its first kSkipProbeShare of steps (docs 2.10):
// where they were split into more than kSkipSubsteps sub-steps on average it stops there
// ("split_probe") and the skip taken from them is the one the whole run gives (Pr 1420, 50 us,
// X = 0.1); where they were not, it runs to the end with the state of a run without the probe,
// to the bit (the shipped Pr 142 config with X = 0.5, whose first run is split into 3.1 on
// average, and 3.85 over its first tenth).
TEST(LaserCourant, FirstRunProbeStopsOnlyWhereTheSkipIsDecided) {
  auto first_runs = [](Config c) {
    c.dt = 2.0 * TimeStepPolicy(c).dt();
    const Result full = run_simulation(c);
    c.heat_probe_share = TimeStepPolicy::kSkipProbeShare;
    c.heat_probe_mbar = TimeStepPolicy::kSkipSubsteps;
    return std::make_pair(full, run_simulation(c));
  };
  const auto [full, probe] = first_runs(prandtl1420(0.1));
  ASSERT_EQ(full.status, "ok") << full.message;
  EXPECT_EQ(probe.status, "split_probe");
  EXPECT_EQ(probe.steps, static_cast<int>(std::ceil(TimeStepPolicy::kSkipProbeShare * full.steps)));
  EXPECT_GT(double(probe.steps + probe.heat_substeps_extra) / probe.steps, TimeStepPolicy::kSkipSubsteps);
  EXPECT_EQ(TimeStepPolicy::heat_courant_skip(probe), TimeStepPolicy::heat_courant_skip(full));
  EXPECT_EQ(TimeStepPolicy::heat_courant_skip(full), 2);
  std::printf("[ PR1420 ] first run: %d steps, %ld sub-steps added; stopped after %d, %ld added\n", full.steps,
              full.heat_substeps_extra, probe.steps, probe.heat_substeps_extra);

  Config c142;
  read_config_file(c142, std::string(LASER_INPUTS_DIR) + "/prandtl142.toml");
  c142.heat_courant = 0.5;
  c142.quiet = true;
  validate(c142);
  const auto [f142, p142] = first_runs(c142);
  EXPECT_EQ(p142.status, f142.status);
  EXPECT_EQ(p142.steps, f142.steps);
  EXPECT_EQ(p142.heat_substeps_extra, f142.heat_substeps_extra);
  EXPECT_GT(f142.heat_substeps_extra, 0);
  EXPECT_EQ(p142.depth_center, f142.depth_center);
  EXPECT_EQ(p142.volume_removed, f142.volume_removed);
  EXPECT_EQ(TimeStepPolicy::heat_courant_skip(f142), 0);
}
