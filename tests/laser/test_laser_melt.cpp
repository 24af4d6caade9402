// Melt flow and run status: the flux-conservative surface velocity conserves
// the melt (melted = vaporized + expelled over the rim + still molten), the
// text's form (4-22) stays available and reproduces the printed model, and
// the status names the physics check that failed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <thread>

#include "laser_model.h"
#include "laser_timestep.h"

#ifndef LASER_DRILL_EXE
#error "LASER_DRILL_EXE must name the laser_drill executable"
#endif

using namespace laser;
namespace fs = std::filesystem;

namespace {
// Table 5.1 case over 50 us at a fixed step with the implicit melt update.
Config short_case(double Pr, MeltFlow flow) {
  Config c;
  c.quiet = true;
  c.tp = 50e-6;
  c.dt = 2.5e-7;
  c.implicit_melt = true;
  c.mat.Pr = Pr;
  c.melt_flow = flow;
  validate(c);
  return c;
}

struct Volumes {
  double melted = 0, vaporized = 0, molten = 0;
};
// The volumes from the final profiles alone: node areas of the grid, pi (d/2)^2
// at the axis and 2 pi xi d otherwise (in R^2).
Volumes volumes(const Config& c, const Result& r) {
  Volumes v;
  const Frame& f = r.final_frame;
  for (size_t i = 0; i < r.xi.size(); ++i) {
    const double xi = r.xi[i];
    const double a = (i == 0 ? kPi * 0.25 * c.dxi * c.dxi : 2.0 * kPi * xi * c.dxi) * c.R * c.R;
    v.melted += f.S2[i] * a;
    v.vaporized += f.S1[i] * a;
    v.molten += f.g[i] * a;
  }
  return v;
}

bool has_cause(const Result& r, const std::string& name) {
  for (const auto& c : r.causes)
    if (c == name) return true;
  return false;
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}
}  // namespace

// Conservative form: the balance closes to round-off at Pr = 0.142, 142 and 1420
// (measured 1e-16 .. 4e-16), and at high Pr the flow does expel melt over the rim.
TEST(LaserMelt, VolumeBalanceClosesWithConservativeFlow) {
  for (double Pr : {0.142, 142.0, 1420.0}) {
    const Config c = short_case(Pr, MeltFlow::Conservative);
    const Result r = run_simulation(c);
    ASSERT_TRUE(r.status == "ok" || r.status == "inaccurate") << r.status << ": " << r.message;
    const Volumes v = volumes(c, r);
    const double residual = (v.melted - v.vaporized - r.volume_expelled - v.molten) / v.melted;
    std::printf("[ MELT ] Pr = %g conservative: melted %.6e, vaporized %.6e, expelled %.6e, molten %.6e m3, "
                "residual %.2e (summary %.2e), status %s\n", Pr, v.melted, v.vaporized, r.volume_expelled,
                v.molten, residual, r.melt_balance, r.status.c_str());
    EXPECT_LT(std::fabs(residual), 1e-6) << Pr;
    EXPECT_NEAR(residual, r.melt_balance, 1e-9) << Pr;
    EXPECT_LE(r.vaporization_cut, 1e-6 * v.melted) << Pr;
    if (Pr >= 142.0) EXPECT_GT(r.volume_expelled, 1e-5 * v.melted) << "no melt expelled at Pr " << Pr;
  }
}

// The text's surface velocity (4-22) as printed (--melt-flow text) reproduces
// the model of the version before the conservative form to the last digits,
// and its melt balance does not close at Pr = 142 (melt disappears), which the
// status names.
TEST(LaserMelt, TextFlowReproducesPrintedFormAndIsFlagged) {
  // The text's own update (4-14) (explicit): the implicit update holds the
  // flow's heat flux b2 g over the step now, which changes its numbers
  // (before: depth 4.922925055021487e-05 m, volume 8.747259614962258e-12 m3).
  Config c = short_case(142.0, MeltFlow::Text);
  c.implicit_melt = false;
  c.curvature_form = CurvatureForm::Text;  // the printed model: (3-37) as printed too
  const Result r = run_simulation(c);
  // laser_drill --pr 142 --pulse 50e-6 --dt 2.5e-7 --melt-flow text, measured with the
  // version before the implicit update held b2 g (its explicit update is the same)
  EXPECT_NEAR(r.depth_center / 4.9321585144968406e-05, 1.0, 1e-12);
  EXPECT_NEAR(r.volume_removed / 8.757543914793522e-12, 1.0, 1e-12);
  EXPECT_NEAR(r.volume_flow / 1.0050345934921622e-12, 1.0, 1e-12);
  const Volumes v = volumes(c, r);
  const double residual = (v.melted - v.vaporized - r.volume_expelled - v.molten) / v.melted;
  std::printf("[ MELT ] Pr = 142 text: residual %.3e of the melted volume, status %s: %s\n", residual,
              r.status.c_str(), r.message.c_str());
  EXPECT_GT(std::fabs(residual), 1e-2);
  EXPECT_EQ(r.status, "inaccurate");
  EXPECT_TRUE(has_cause(r, "melt volume balance"));
  EXPECT_EQ(r.message.rfind("melt volume balance", 0), 0u) << "the first named cause leads the message";
  // Table 5.1 (Pr = 0.142) at the automatic step: the values of the version before
  Config t;
  t.quiet = true;
  t.melt_flow = MeltFlow::Text;
  t.curvature_form = CurvatureForm::Text;
  validate(t);
  t.dt = TimeStepPolicy(t).dt();
  const Result rt = run_simulation(t);
  EXPECT_EQ(rt.status, "ok") << rt.message;
  EXPECT_NEAR(rt.depth_center / 6.583351290659386e-04, 1.0, 1e-12);
  EXPECT_NEAR(rt.volume_removed / 1.27518717477387e-10, 1.0, 1e-12);
}

// A safeguard that fires on many node steps makes the run inaccurate, with
// its name and count (Pr = 1420: the b2 limiter of (4-25)).
TEST(LaserStatus, SafeguardCountsAreNamed) {
  const Result r = run_simulation(short_case(1420.0, MeltFlow::Conservative));
  std::printf("[ STATUS ] Pr = 1420: %s: %s\n", r.status.c_str(), r.message.c_str());
  EXPECT_EQ(r.status, "inaccurate");
  EXPECT_TRUE(has_cause(r, "b2 limiter"));
  EXPECT_GT(r.b2_clamps, 1e-4 * r.steps * r.nodes);
  EXPECT_NE(r.message.find(std::to_string(r.b2_clamps)), std::string::npos);
  EXPECT_EQ(r.message.find("energy bookkeeping"), std::string::npos) << "a harmless imbalance is not a cause";
}

// The surface temperature against the critical temperature: a warning above
// 0.8 T_c, diverged above T_c (1e13 W/m2 reaches about 8200 K).
TEST(LaserStatus, CriticalTemperature) {
  Config c;
  c.quiet = true;
  c.I0 = 1e13;
  c.tp = 1e-6;
  validate(c);
  c.dt = TimeStepPolicy(c).dt();
  const Result r = run_simulation(c);
  std::printf("[ STATUS ] 1e13 W/m2: T_peak %.0f K, T/T_c %.3f, %s, warnings %zu\n", r.T_peak, r.T_over_Tc,
              r.status.c_str(), r.warnings.size());
  ASSERT_GT(r.T_peak, 0.8 * c.mat.Tc);
  EXPECT_NEAR(r.T_over_Tc, r.T_peak / c.mat.Tc, 1e-12);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("critical temperature"), std::string::npos);
  Config low = c;
  low.mat.Tc = 0.5 * (r.T_peak + c.mat.Tsat0);  // below the surface temperature reached
  const Result d = run_simulation(low);
  EXPECT_EQ(d.status, "diverged");
  EXPECT_TRUE(has_cause(d, "surface temperature above the critical temperature"));
  const Result t51 = run_simulation([] { Config k; k.quiet = true; validate(k); k.dt = 1.5e-6; k.tp = 50e-6; return k; }());
  EXPECT_TRUE(t51.warnings.empty()) << "Table 5.1 stays far below T_c";
}

// A non-finite or absurd state is diverged, exits non-zero and prints no error
// estimate: --hlv 1e9 drives the surface temperature to 1.6e5 K with p = inf.
TEST(LaserStatus, AbsurdStateIsDivergedWithNonZeroExit) {
  const fs::path dir = fs::temp_directory_path() / ("laser_status_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string cmd = std::string(LASER_DRILL_EXE) + " --hlv 1e9 --pulse 50e-6 --quiet --out " +
                          (dir / "out").string() + " >" + (dir / "o.txt").string() + " 2>" + (dir / "e.txt").string();
  const int st = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(st));
  EXPECT_EQ(WEXITSTATUS(st), 3);
  const std::string j = slurp(dir / "out" / "summary.json"), o = slurp(dir / "o.txt"), e = slurp(dir / "e.txt");
  EXPECT_NE(j.find("\"status\": \"diverged\""), std::string::npos) << j.substr(0, 400);
  EXPECT_NE(j.find("non-finite surface state"), std::string::npos);
  EXPECT_EQ(o.find("error 0.0"), std::string::npos) << o;
  EXPECT_NE(o.find("no error estimate"), std::string::npos) << o;
  EXPECT_NE(e.find("diverged"), std::string::npos) << e;
  // the CSV holds the last admissible state, not the absurd one
  const std::string csv = slurp(dir / "out" / "final_profile.csv");
  EXPECT_EQ(csv.find("inf"), std::string::npos);
  fs::remove_all(dir);
}

// --absorptivity a runs the model with a I0: identical to the run at the
// absorbed intensity (same step), and the summary keeps the beam's I0.
TEST(LaserOptions, AbsorptivityScalesTheIntensity) {
  Config a;
  a.quiet = true;
  a.tp = 100e-6;
  a.I0 = 1e11;
  a.absorptivity = 0.75;
  validate(a);
  a.dt = TimeStepPolicy(a).dt();
  Config b = a;
  b.I0 = 7.5e10;
  b.absorptivity = 1.0;
  EXPECT_EQ(TimeStepPolicy(b).dt(), a.dt);
  const Result ra = run_simulation(a), rb = run_simulation(b);
  ASSERT_EQ(ra.status, "ok") << ra.message;
  EXPECT_EQ(ra.depth_center, rb.depth_center);
  EXPECT_EQ(ra.volume_removed, rb.volume_removed);
  EXPECT_NEAR(ra.energy.laser_exact / rb.energy.laser_exact, 1.0, 1e-15);
}

// --recoil knight drives the flow with 0.54 p_sat: no effect without a flow;
// with the flow the least-squares coefficient A changes. Measured: at
// Pr = 1420 A drops from 3.42e5 to 3.12e5, at Pr = 142 it stays 8034 (the
// root the rule of (4-19) selects there is nearly independent of the pressure,
// docs/theory/laser_model.md 2.6), so the test holds the Pr = 1420 case.
TEST(LaserOptions, RecoilKnightEntersTheFlowOnly) {
  Config c = short_case(1420.0, MeltFlow::Conservative);
  c.melt_heat = MeltHeat::Ode;  // the figures above; with --melt-heat flux A drops by 4.8 % (271217 -> 258310)
  c.model = FlowModel::Conduction;
  Config k = c;
  k.recoil = 0.54;
  EXPECT_EQ(run_simulation(c).volume_removed, run_simulation(k).volume_removed);
  c.model = k.model = FlowModel::RisingFall;
  // the figures above were measured with (3-37) as printed (A 344758 / 298323 now, with
  // 3581 / 3110 curvature clamps); with the default curvature factor A, set by the shape of
  // dp/dxi (docs section 3), moves by 0.6 % (294583 / 292933) and the melt expelled over
  // the rim by -5.7 % (2.0849e-11 / 1.9654e-11 m3)
  Config ct = c, kt = k;
  ct.curvature_form = kt.curvature_form = CurvatureForm::Text;
  const Result rf = run_simulation(ct), rk = run_simulation(kt);
  std::printf("[ RECOIL ] Pr = 1420, 50 us, (3-37) as printed: A full %.6g, knight %.6g; expelled %.4e / %.4e m3\n",
              rf.A_last, rk.A_last, rf.volume_expelled, rk.volume_expelled);
  EXPECT_LT(rk.A_last, 0.95 * rf.A_last);
  EXPECT_GT(rk.A_last, 0.0);
  const Result df = run_simulation(c), dk = run_simulation(k);
  std::printf("[ RECOIL ] default curvature factor: A full %.6g, knight %.6g; expelled %.4e / %.4e m3\n",
              df.A_last, dk.A_last, df.volume_expelled, dk.volume_expelled);
  EXPECT_LT(dk.volume_expelled, 0.97 * df.volume_expelled);
  EXPECT_GT(dk.A_last, 0.0);
}

// summary.json max_stable_dt_s is the limit whose quarter the automatic step
// takes (as the docs say); the implicit update has none (null).
TEST(LaserStatus, MaxStableStepAgreesWithTheAutomaticStep) {
  const fs::path dir = fs::temp_directory_path() / ("laser_stable_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const std::string upd : {"explicit", "implicit"}) {
    const fs::path out = dir / upd;
    // Table 5.1 (700 us): the automatic step is set by the stability limit
    const std::string cmd = std::string(LASER_DRILL_EXE) + (upd == "explicit" ? "" : " --pulse 100e-6") +
                            " --melt-update " + upd +
                            " --quiet --out " + out.string() + " >/dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    const std::string j = slurp(out / "summary.json");
    const auto num_after = [&](const std::string& key) {
      const size_t k = j.find("\"" + key + "\": ");
      EXPECT_NE(k, std::string::npos) << key;
      return j.substr(k + key.size() + 4, 24);
    };
    if (upd == "explicit") {
      const double lim = std::stod(num_after("max_stable_dt_s")), dt = std::stod(num_after("dt_s"));
      EXPECT_NEAR(dt, 0.25 * lim, 1e-12 * lim) << j.substr(0, 300);
    } else {
      EXPECT_EQ(num_after("max_stable_dt_s").rfind("null", 0), 0u);
    }
  }
  fs::remove_all(dir);
}

// Killed while running (SIGTERM, SIGINT), laser_drill leaves no .part file and
// no lock behind, and removes the folder it created.
TEST(LaserOutput, KilledRunLeavesNothingBehind) {
  for (int sig : {SIGTERM, SIGINT}) {
    const fs::path dir = fs::temp_directory_path() / ("laser_kill_" + std::to_string(::getpid()) + "_" +
                                                      std::to_string(sig));
    fs::remove_all(dir);
    const std::string out = dir.string();
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::execl(LASER_DRILL_EXE, LASER_DRILL_EXE, "--pr", "142", "--dt", "1e-7", "--melt-update", "implicit", "--quiet",
              "--out", out.c_str(), static_cast<char*>(nullptr));
      std::_Exit(127);
    }
    ASSERT_GT(pid, 0);
    bool staged = false;
    for (int k = 0; k < 200 && !staged; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      staged = fs::exists(dir / "profiles.h5.part");
    }
    EXPECT_TRUE(staged) << "the run did not start writing";
    ::kill(pid, sig);
    int st = 0;
    ::waitpid(pid, &st, 0);
    EXPECT_TRUE(WIFSIGNALED(st) && WTERMSIG(st) == sig);
    EXPECT_FALSE(fs::exists(dir)) << "left behind in " << out;
    fs::remove_all(dir);
  }
}

// The shipped Pr = 142 config with the implicit update at steps that used to
// blow up (2.04e-6 s and more: 1e23-1e28 K, up to 24 m3 removed): the run stays
// finite and within the energy the beam delivers, computed from the inputs
// alone: rho (h_m V_melted + h_lv V_vaporized) <= pi R^2 I0 t_p, h_m = c_ps
// (T_m - T_i) + h_ls (h_lv alone is a lower bound on what vaporizing costs).
// The mechanism: the flow's share of the layer's gradients, b2 g, was held as
// b2 over the implicit step, so that b2 g_new grew with g_new.
TEST(LaserMelt, ImplicitUpdateStaysBoundedAtLargeSteps) {
  Config base;
  read_config_file(base, std::string(LASER_INPUTS_DIR) + "/prandtl142.toml");
  base.quiet = true;
  validate(base);
  const Material& m = base.mat;
  const double beam = kPi * base.R * base.R * base.I0 * base.tp;
  const double hm = m.cps * (m.Tm - m.Ti) + m.hls;
  for (double dt : {2.04e-6, 4e-6, 1e-5}) {
    Config c = base;
    c.dt = dt;
    const Result r = run_simulation(c);
    const double need = m.rho * (hm * r.volume_melted + m.hlv * r.volume_vaporized);
    std::printf("[ STABLE ] Pr 142 config, dt %.3g s: %s, T_peak %.0f K, demand/beam %.4f, depth %.4e m\n", dt,
                r.status.c_str(), r.T_peak, need / beam, r.depth_center);
    EXPECT_NE(r.status, "diverged") << dt << ": " << r.message;
    EXPECT_DOUBLE_EQ(r.t_end, c.tp) << dt;
    EXPECT_LT(need, beam) << dt;
    EXPECT_LT(r.T_peak, m.Tc) << dt;
  }
}

// Where the model's assumptions fail the run says so by name: no root of the
// least-squares cubic (4-19) (Pr = 142000: no positive root at the first step);
// a boundary layer (4-9) thicker than the melt (the boundary model at Pr = 142,
// where delta/g at the first node off the axis is about 1e3); the quadratic
// profile (4-25) asked by (4-27) for more than a monotone profile holds
// (|b2| g^2 / theta_sat > 1 at Pr = 1420).
TEST(LaserStatus, ModelAssumptionFailuresAreNamed) {
  Config c = short_case(142000.0, MeltFlow::Conservative);
  c.tp = 20e-6;
  c.dt = 1e-7;
  const Result r = run_simulation(c);
  EXPECT_EQ(r.status, "no_flow_solution") << r.message;
  EXPECT_TRUE(has_cause(r, "no root of (4-19)")) << r.message;
  EXPECT_NE(r.message.find("(4-19)"), std::string::npos) << r.message;

  Config b = short_case(142.0, MeltFlow::Conservative);
  b.model = FlowModel::Boundary;
  b.dt = 1e-7;
  const Result rb = run_simulation(b);
  std::printf("[ STATUS ] boundary model, Pr 142: %ld of %ld steps delta >= g, first delta/g %.4g; %s\n",
              rb.bl_thicker_steps, rb.bl_steps, rb.bl_first_ratio, rb.status.c_str());
  EXPECT_TRUE(has_cause(rb, "boundary layer thicker than the melt")) << rb.message;
  EXPECT_GT(2 * rb.bl_thicker_steps, rb.bl_steps);
  EXPECT_GT(rb.bl_first_ratio, 1.0);
  EXPECT_EQ(rb.status, "inaccurate");
  // at the text's Pr the layer is thinner than the melt in most steps: a note, not a cause
  Config b0 = b;
  b0.mat.Pr = 0.142;
  const Result r0 = run_simulation(b0);
  EXPECT_FALSE(has_cause(r0, "boundary layer thicker than the melt")) << r0.message;
  EXPECT_LE(2 * r0.bl_thicker_steps, r0.bl_steps);

  const Result rp = run_simulation(short_case(1420.0, MeltFlow::Conservative));
  EXPECT_TRUE(has_cause(rp, "b2 limiter"));
  EXPECT_GT(rp.b2_demand_max, 1.0);
  EXPECT_NE(rp.message.find("cannot carry the heat"), std::string::npos) << rp.message;
}

// The heat the flow carries sideways: an advective transport can only move heat,
// so summed over the melt the heat taken sideways (energy term flow_advected)
// is >= 0 (what leaves over the rim). The ODE (4-27) breaks this at Pr = 1420
// (d(xi) 0.05: -0.119 of the beam, heat created, the mechanism of the failed
// column bound); --melt-heat flux (face fluxes) keeps it (+0.103, +0.112), and
// every column stays under its energy bound (measured 0.828, 0.808).
TEST(LaserMelt, FluxHeatTransportCreatesNoHeat) {
  for (double dxi : {0.05, 0.0125}) {
    Config c = short_case(1420.0, MeltFlow::Conservative);
    c.dxi = dxi;
    c.melt_heat = MeltHeat::Ode;
    Config f = c;
    f.melt_heat = MeltHeat::Flux;
    const Result ro = run_simulation(c), rf = run_simulation(f);
    std::printf("[ HEAT ] Pr 1420, d(xi) %g: flow_advected/beam ode %.4f flux %.4f; column bound ode %.4f flux %.4f\n",
                dxi, ro.energy.flow_advected / ro.energy.laser_exact, rf.energy.flow_advected / rf.energy.laser_exact,
                ro.check.worst_node_ratio, rf.check.worst_node_ratio);
    EXPECT_GE(rf.energy.flow_advected, 0.0) << dxi;
    EXPECT_LT(rf.check.worst_node_ratio, 1.0) << dxi;
    EXPECT_LT(rf.check.melt_vap_over_beam, 1.0) << dxi;
    EXPECT_NE(rf.status, "diverged");
    if (dxi == 0.05) EXPECT_LT(ro.energy.flow_advected, 0.0) << "the ODE (4-27) creates heat here";
  }
}

// The automatic step stops refining when halving does not reduce the step-
// doubling estimate (Pr = 142: 3.7e-3, 9.2e-3, 6.1e-3 over three halvings) and
// names it; checked from outside: a run at half the reported step still moves
// the volume by more than --tol, so the estimate is not fooling anyone.
// The quasi-steady layer (--melt-content steady) is named: with the layer's heat content
// (the default with this config's implicit update) the same case meets --tol in dt
// (dt 6.25e-8 s after 6 runs, estimates 2.8e-4 / 8.7e-4; docs section 3).
TEST(LaserStatus, TimeStepErrorNotDecreasingIsNamed) {
  Config c;
  read_config_file(c, std::string(LASER_INPUTS_DIR) + "/prandtl142.toml");
  c.quiet = true;
  c.tp = 100e-6;
  c.melt_content = MeltContent::Steady;
  c.trapezoidal_melt = false;  // the figures above: the backward Euler update (--melt-update implicit)
  validate(c);
  const TimeStepPolicy policy(c);
  const Result r = policy.run(c, nullptr);
  std::printf("[ STEP ] Pr 142, 100 us: dt %.4g s, runs %d, estimates depth %.3g volume %.3g; %s\n", r.dt, r.step.runs,
              r.step.depth_error, r.step.volume_error, r.status.c_str());
  ASSERT_TRUE(has_cause(r, "time-step error not decreasing")) << r.message;
  EXPECT_EQ(r.status, "inaccurate");
  EXPECT_NE(r.message.find("does not converge in dt"), std::string::npos) << r.message;
  EXPECT_LE(r.step.runs, 6);
  Config h = c;
  h.dt = 0.5 * r.dt;
  const Result rh = run_simulation(h);
  const double dv = std::fabs(rh.volume_removed - r.volume_removed) / r.volume_removed;
  std::printf("[ STEP ] volume at dt/2 differs by %.3g\n", dv);
  EXPECT_GT(dv, c.tol);
}

namespace {
// Median surface temperature, one step after their onset, of the nodes that melt
// between t0 and the end of the run (every step is a frame).
double median_first_step_T(const Result& r, double t0) {
  std::vector<double> T;
  for (size_t i = 1; i < r.xi.size(); ++i) {
    const double tm = r.tau_m_s[i];
    if (tm < t0 || tm > r.t_end) continue;
    for (const Frame& f : r.frames) {
      if (f.t <= tm) continue;
      if (f.g[i] > 0.0) T.push_back(f.T[i]);
      break;
    }
  }
  if (T.empty()) return 0.0;
  std::sort(T.begin(), T.end());
  return T[T.size() / 2];
}
}  // namespace

// The layer's heat content (--melt-content transient, docs 2.7). With the quasi-steady
// layer the heat the flow brings into a column that has just melted is conducted out at
// once, half against the beam: the column's surface temperature one step after its
// onset rises as d(xi) shrinks (the power lands on one cell; docs section 3: 2016 /
// 2608 / 3988 K over 200 us). With the transient term the inflowing heat fills the
// new layer instead, and the first-step temperature no longer grows with refinement.
// The bookkeeping closes with the content as its own term, no heat is created
// (flow_advected >= 0) and every column stays under its energy bound.
TEST(LaserMelt, LayerContentTakesTheInflowingHeat) {
  double Ts[2][3];
  const double grids[3] = {0.025, 0.0125, 0.00625};
  for (int k = 0; k < 2; ++k) {
    for (int j = 0; j < 3; ++j) {
      Config c = short_case(142.0, MeltFlow::Conservative);
      c.tp = 60e-6;
      c.dxi = grids[j];
      c.frames = 241;
      c.melt_content = k == 0 ? MeltContent::Steady : MeltContent::Transient;
      const Result r = run_simulation(c);
      Ts[k][j] = median_first_step_T(r, 20e-6);
      const Energy& e = r.energy;
      const double imb = (e.sum() - e.laser_exact) / e.laser_exact;
      std::printf("[ CONTENT ] %s d(xi) %g: first-step T_s %.0f K, content %.4g J, flow_advected %.4g J, imbalance %.2g, "
                  "column %.3f, %s\n",
                  k ? "transient" : "steady", c.dxi, Ts[k][j], e.melt_content, e.flow_advected, imb,
                  r.check.worst_node_ratio, r.status.c_str());
      EXPECT_LT(std::fabs(imb), 1e-4);
      EXPECT_GE(e.flow_advected, 0.0);
      EXPECT_LT(r.check.worst_node_ratio, 1.0);
      if (k == 0) EXPECT_EQ(e.melt_content, 0.0);
      else EXPECT_GT(e.melt_content, 0.0);
    }
  }
  EXPECT_GT(Ts[0][2], 1.3 * Ts[0][0]) << "quasi-steady: the spike grows with refinement";
  EXPECT_LT(Ts[1][2], 1.1 * Ts[1][0]) << "transient: it does not";
  for (int j = 0; j < 3; ++j) EXPECT_LT(Ts[1][j], Ts[0][j]) << grids[j];
}

// Pr = 142 converges under d(xi) and dt refinement once the layer keeps its heat
// content (reduced ladders of docs section 3: 200 us, rising-fall xi_p = 1,
// implicit update; d(xi) 0.05 / 0.025 / 0.0125 at dt 2.5e-7 s, dt 1e-6 / 5e-7 /
// 2.5e-7 s at d(xi) 0.025). Centre depth, removed volume and the flow's share
// (expelled over the rim / removed) move monotonically with differences that
// shrink (measured ratios of successive differences 0.07-0.44 in d(xi), 0.59-0.70
// in dt), and every column stays under its energy bound. With the text's
// quasi-steady layer the same d(xi) ladder does not converge: the depth's
// differences grow (measured 0.37, 0.46 um).
TEST(LaserMelt, Prandtl142ConvergesWithLayerContent) {
  struct Out { double depth, volume, share; };
  auto run = [](double dxi, double dt, MeltContent mc) {
    Config c = short_case(142.0, MeltFlow::Conservative);
    c.tp = 200e-6;
    c.dxi = dxi;
    c.dt = dt;
    c.melt_content = mc;
    const Result r = run_simulation(c);
    EXPECT_LT(r.check.worst_node_ratio, 1.0) << dxi << " " << dt;
    EXPECT_NE(r.status, "diverged") << r.message;
    std::printf("[ PR142 ] %s d(xi) %g dt %g: depth %.3f um, volume %.5g m3, share %.4f, column %.3f, limiter %d\n",
                mc == MeltContent::Steady ? "steady" : "transient", dxi, dt, r.depth_center * 1e6, r.volume_removed,
                r.volume_expelled / r.volume_removed, r.check.worst_node_ratio, r.b2_clamps);
    return Out{r.depth_center, r.volume_removed, r.volume_expelled / r.volume_removed};
  };
  auto converging = [](const Out& a, const Out& b, const Out& c, const char* what) {
    const double d1[3] = {b.depth - a.depth, b.volume - a.volume, b.share - a.share};
    const double d2[3] = {c.depth - b.depth, c.volume - b.volume, c.share - b.share};
    for (int k = 0; k < 3; ++k) {
      EXPECT_GT(d1[k] * d2[k], 0.0) << what << " quantity " << k << ": not monotone";
      EXPECT_LT(std::fabs(d2[k]), 0.75 * std::fabs(d1[k])) << what << " quantity " << k;
    }
  };
  const Out g1 = run(0.05, 2.5e-7, MeltContent::Auto), g2 = run(0.025, 2.5e-7, MeltContent::Auto),
            g3 = run(0.0125, 2.5e-7, MeltContent::Auto);
  converging(g1, g2, g3, "d(xi) ladder");
  const Out t1 = run(0.025, 1e-6, MeltContent::Auto), t2 = run(0.025, 5e-7, MeltContent::Auto);
  converging(t1, t2, g2, "dt ladder");
  const Out s1 = run(0.05, 2.5e-7, MeltContent::Steady), s2 = run(0.025, 2.5e-7, MeltContent::Steady),
            s3 = run(0.0125, 2.5e-7, MeltContent::Steady);
  EXPECT_GT(std::fabs(s3.depth - s2.depth), std::fabs(s2.depth - s1.depth)) << "the quasi-steady layer converged";
}
