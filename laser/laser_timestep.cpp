#include "laser_timestep.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace laser {

namespace {
double rel_diff(double a, double b) {
  const double s = std::max(std::fabs(a), std::fabs(b));
  return s > 0.0 ? std::fabs(a - b) / s : 0.0;
}
// Steps per pulse and per melting time (onset at the centre to the pulse end)
// of the automatic step; the stability limit is kept at a factor 4 so that
// the companion run at twice the step is stable as well.
constexpr double kStepsPerPulse = 200.0;
constexpr double kStepsPerMelting = 400.0;
constexpr double kStableFraction = 0.25;
// A step given by the user is accepted up to this fraction of the linearised
// limit of (4-14) at the quasi-steady centre state. The linearisation is not the
// worst state of a run: in the first steps after onset, when the layer is a few
// steps thick, the run-time check fired from 0.85 of it (Table 5.1, 7.5e10 W/m2,
// rising and rising-fall; docs/theory/laser_model.md 2.8), i.e. only after running. At
// half of it no run has become unstable, and the automatic step's companion at
// 2 dt (a quarter of the limit x 2) is exactly at this bound.
constexpr double kAcceptFraction = 0.5;
constexpr double kNoDecrease = 0.5;
}  // namespace

TimeStepPolicy::TimeStepPolicy(const Config& cfg) {
  dt_stable_ = cfg.implicit_melt ? 0.0 : explicit_step_limit(cfg);
  const Groups G = make_groups(cfg.mat, cfg.absorbed_I0(), cfg.R);
  const double t_melt = melt_onset_tau(G, 0.0) * G.t_scale;
  if (cfg.dt > 0.0) {
    dt_ = cfg.dt;
    reason_ = cfg.dtau > 0.0 ? "--dtau" : "--dt";
    if (dt_stable_ > 0.0 && dt_ > kAcceptFraction * dt_stable_) {
      char buf[480];
      std::snprintf(buf, sizeof buf,
                    "%s: time step %.4g s is above the accepted step %.4g s of the explicit melt thickness "
                    "update (4-14) at this intensity (%.4g of its explicit stability limit %.4g s, which is linearised "
                    "at the quasi-steady centre; thin layers after onset became unstable from 0.85 of it); valid "
                    "range (0, %.4g] s (or --melt-update implicit)",
                    reason_.c_str(), dt_, kAcceptFraction * dt_stable_, kAcceptFraction, dt_stable_,
                    kAcceptFraction * dt_stable_);
      throw UsageError(buf);
    }
    if (cfg.tp / dt_ > kMaxSteps / 3)
      throw UsageError(reason_ + ": " + fmt(cfg.tp / dt_, 4) + " steps of " + fmt(dt_, 4) + " s over the pulse " +
                       fmt(cfg.tp, 4) + " s; at most " + fmt(kMaxSteps / 3, 4) + " allowed (valid range [" +
                       fmt(3 * cfg.tp / kMaxSteps, 4) + ", " + fmt(cfg.tp, 4) + ") s)");
    check_work(cfg);
    return;
  }
  automatic_ = true;
  dt_ = cfg.tp / kStepsPerPulse;
  reason_ = "pulse / " + fmt(kStepsPerPulse, 4);
  if (t_melt < cfg.tp && (cfg.tp - t_melt) / kStepsPerMelting < dt_) {
    dt_ = (cfg.tp - t_melt) / kStepsPerMelting;
    reason_ = "melting time / " + fmt(kStepsPerMelting, 4);
  }
  if (dt_stable_ > 0.0 && kStableFraction * dt_stable_ < dt_) {
    dt_ = kStableFraction * dt_stable_;
    reason_ = "explicit limit (4-14) x " + fmt(kStableFraction, 4);
  }
  check_work(cfg);
}

// Frames of a run at dt fit in kMaxFrameBytes
bool TimeStepPolicy::buffered(const Config& cfg, double dt) const {
  const double nframes = std::min<double>(std::max(cfg.frames, 2), std::ceil(cfg.tp / dt) + 1.0);
  return nframes * nodes_ * kFrameFields * sizeof(double) <= kMaxFrameBytes;
}

// Refuses a case whose reported run alone would exceed the step or node-step
// budget (grid size estimated as in the model's setup).
void TimeStepPolicy::check_work(const Config& cfg) {
  const Groups G = make_groups(cfg.mat, cfg.absorbed_I0(), cfg.R);
  const double tau_p = cfg.tp / G.t_scale, tau_m0 = melt_onset_tau(G, 0.0);
  double nodes;
  if (cfg.xi_max > 0.0) nodes = std::round(cfg.xi_max / cfg.dxi) + 1;
  else nodes = (tau_p > tau_m0 ? std::floor(std::sqrt(0.5 * std::log(tau_p / tau_m0)) / cfg.dxi) : 0.0) + 3;
  nodes = std::max(nodes, 3.0);
  nodes_ = nodes;
  const double steps = std::ceil(cfg.tp / dt_), work = steps * nodes;
  if (steps <= kMaxSteps / 3 && work <= kMaxNodeSteps) return;
  const double tp_max = std::min(kMaxSteps / 3, kMaxNodeSteps / nodes) * dt_;
  throw UsageError("the case cannot finish in this program's budget: --intensity " + fmt(cfg.I0, 4) +
                   " W/m2, --pulse " + fmt(cfg.tp, 4) + " s, --radius " + fmt(cfg.R, 4) + " m, --dxi " +
                   fmt(cfg.dxi, 4) + " need about " + fmt(steps, 3) + " steps of " + fmt(dt_, 4) + " s (" +
                   reason_ + ") on " + fmt(nodes, 4) + " nodes = " + fmt(work, 3) +
                   " node steps; at most " + fmt(kMaxSteps / 3, 3) + " steps and " + fmt(kMaxNodeSteps, 3) +
                   " node steps are accepted: shorten --pulse to at most " + fmt(tp_max, 3) +
                   " s, coarsen --dxi or lower --intensity");
}

namespace {
// Streams a candidate's frames to the output sink and keeps a copy in memory, so that a
// candidate accepted after a finer run was streamed can be written again.
struct TeeSink : FrameSink {
  FrameSink* out;
  bool keep;
  std::vector<Frame> frames;
  TeeSink(FrameSink* o, bool k) : out(o), keep(k) {}
  void begin(const std::vector<double>& xi, const std::vector<double>& t_melt_s) override {
    if (out) out->begin(xi, t_melt_s);
  }
  void frame(const Frame& f) override {
    if (keep) frames.push_back(f);
    if (out) out->frame(f);
  }
  void finish() override {
    if (out) out->finish();
  }
};
}  // namespace

// One run at dt. A run that may be reported streams its frames to a fresh sink (the last one
// streamed is what the output holds) and keeps them in memory when they fit in
// kMaxFrameBytes; the others are quiet with two frames.
Result TimeStepPolicy::run_at(Config cfg, double dt, bool reported, long& steps, const SinkFactory& make_sink) const {
  cfg.dt = dt;
  if (!reported) {
    cfg.quiet = true;
    cfg.frames = 2;
  }
  std::unique_ptr<FrameSink> out;
  if (reported && make_sink) out = make_sink();
  const bool keep = reported && buffered(cfg, dt);
  TeeSink tee(out.get(), keep);
  Result r = run_simulation(cfg, &tee);
  r.frames = std::move(tee.frames);
  steps += r.steps;
  return r;
}

namespace {
// a safeguard of the step (the b2 limit of (4-25), the curvature clamp of (3-37)) acted often
// enough to make the run inaccurate
bool safeguarded(const Result& r) {
  for (const auto& c : r.causes)
    if (c == "b2 limiter" || c == "curvature clamp") return true;
  return false;
}
// share of a run's steps split by the heat Courant limit (--melt-heat flux): their heat march
// advances by the limit's sub-step whatever the step, so halving the step does not halve it
// and a step-doubling difference leaves that part of the error out
double substep_share(const Result& r) { return r.steps > 0 ? double(r.heat_substeps_extra) / r.steps : 0.0; }
// sub-steps per step of a run on average, mbar = (steps + sub-steps added) / steps (steps > 0)
double mean_substeps(const Result& r) { return laser::mean_substeps(r.steps, r.heat_substeps_extra); }
}  // namespace

// Step-doubling estimate of the middle run of three at steps 2h, h, h/2 (quantities Dc, Dm,
// Df), checked by the third: d1 = D(h) - D(2h) estimates the error of D(h) (first order, as a
// single step doubling does), and d2 = D(h/2) - D(h) must confirm that the differences behave
// as those of a converging sequence: the same sign and a ratio r = |d2/d1| <= kMaxRatio. The
// estimate is the larger difference, max(|d1|, |d2|).
TimeStepPolicy::Level3 TimeStepPolicy::three_level(double Dc, double Dm, double Df) {
  Level3 q;
  const double s = std::max({std::fabs(Dc), std::fabs(Dm), std::fabs(Df)});
  if (!(s > 0.0)) return q;
  const double d1 = (Dm - Dc) / s, d2 = (Df - Dm) / s;
  q.moves = q.est = std::max(std::fabs(d1), std::fabs(d2));
  q.ratio = std::fabs(d1) > 0.0 ? std::fabs(d2 / d1) : (d2 == 0.0 ? 0.0 : HUGE_VAL);
  q.asymptotic = (d1 * d2 > 0.0 && q.ratio <= kMaxRatio) || q.moves == 0.0;
  return q;
}

// A level's estimate is accepted when it is within tol and the differences contract as those
// of a converging sequence do, or both are below kNoiseFraction of tol (where their pattern is
// rounding of the fronts' positions, not a trend).
bool TimeStepPolicy::Level3::accepted(double tol) const {
  return est <= tol && (asymptotic || moves <= kNoiseFraction * tol);
}

namespace {
bool finished(const Result& r) { return r.status == "ok" || r.status == "inaccurate"; }
}  // namespace

// Halvings of the automatic step skipped after its first (coarse) run, whose steps the heat
// Courant limit split into mbar = (steps + sub-steps added) / steps on average: a run split into
// m sub-steps per step costs about as much as an unsplit run at 1/m of its step, and its
// step-doubling difference leaves out the heat march's sub-step error, for which a split level is
// refined anyway (kMaxSubstepShare). Where mbar > kSkipSubsteps, the ladder restarts at the
// level whose reported run (at half the coarse step) is expected unsplit: k = ceil(log2 mbar) - 1
// halvings (the rate that sets the split is that of the flow, about the same at every step).
int TimeStepPolicy::heat_courant_skip(const Result& coarse) {
  if (!(coarse.steps > 0) || coarse.heat_substeps_extra <= 0) return 0;
  const double mbar = mean_substeps(coarse);
  if (!(mbar > kSkipSubsteps)) return 0;
  return static_cast<int>(std::ceil(std::log2(mbar))) - 1;
}

// The three runs of the estimate at 2 dt, dt and dt/2 (the reported one in the middle); where
// 2 dt is not admissible (unstable, not shorter than the pulse, a run that did not finish) dt,
// dt/2 and dt/4, the error of dt then being twice the larger difference. Returns
// false when the run to report is already settled (L.mid: unstable or not finished; for an
// automatic step also a coarse run that ended with a state that is not a solution).
bool TimeStepPolicy::first_levels(const Config& cfg, Levels& L, long& steps, int& runs,
                                  const SinkFactory& make_sink) const {
  double dt = dt_;
  const auto coarse_ok = [&](double c) {
    return c < cfg.tp && (dt_stable_ == 0.0 || c <= kAcceptFraction * dt_stable_);
  };
  // after a coarse run: true where it ended unstable or diverged (it is then the reported run),
  // else whether it finished noted
  auto coarse_stopped = [&]() {
    if (L.coarse.status == "unstable_time_step" || L.coarse.status == "diverged") {
      L.mid = std::move(L.coarse);
      return true;
    }
    L.has_coarse = finished(L.coarse);
    return false;
  };
  if (automatic_ && coarse_ok(2.0 * dt)) {
    // the first run stops after kSkipProbeShare of its steps where they were split into more
    // than kSkipSubsteps sub-steps on average (status "split_probe": the ladder skips below it)
    Config first = cfg;
    first.heat_probe_share = kSkipProbeShare;
    first.heat_probe_mbar = kSkipSubsteps;
    // the run-time check of (4-14) may still fire: the automatic step is halved then
    L.coarse = run_at(first, 2.0 * dt, true, steps, make_sink);
    ++runs;
    for (int k = 0; k < 6 && L.coarse.status == "unstable_time_step"; ++k) {
      dt *= 0.5;
      if (!cfg.quiet)
        std::fprintf(stderr, "laser_drill: automatic step unstable (%s); retrying with dt = %.4g s\n",
                     L.coarse.message.c_str(), dt);
      L.coarse = run_at(first, 2.0 * dt, true, steps, make_sink);
      ++runs;
    }
    if (coarse_stopped()) return false;
    const bool probed = L.coarse.status == "split_probe";
    const int skip = L.has_coarse || probed ? heat_courant_skip(L.coarse) : 0;
    if (skip > 0) {
      const double mbar = mean_substeps(L.coarse);
      const double dt0 = dt;
      dt = std::ldexp(dt, -skip);
      L.skipped = "the heat Courant limit split the steps of the first run (" + fmt(2.0 * dt0, 4) + " s) into " +
                  fmt(mbar, 3) + " sub-steps on average" +
                  (probed ? " over its first " + std::to_string(L.coarse.steps) + " steps (where it stopped)" : "") +
                  ": the ladder skipped " + std::to_string(skip) +
                  " halvings and started at dt = " + fmt(dt, 4) + " s, where the reported run is expected unsplit";
      if (!cfg.quiet) std::fprintf(stderr, "laser_drill: %s\n", L.skipped.c_str());
      L.coarse = run_at(cfg, 2.0 * dt, true, steps, make_sink);
      ++runs;
      if (coarse_stopped()) return false;
    }
  }
  L.mid = run_at(cfg, dt, true, steps, make_sink);
  ++runs;
  if (!finished(L.mid)) return false;
  if (!automatic_ && coarse_ok(2.0 * dt)) {
    L.coarse = run_at(cfg, 2.0 * dt, false, steps);
    ++runs;
    L.has_coarse = finished(L.coarse);
  }
  L.fine = run_at(cfg, 0.5 * dt, true, steps, make_sink);
  ++runs;
  if (!L.has_coarse && finished(L.fine)) {  // dt, dt/2, dt/4
    L.finest = run_at(cfg, 0.25 * dt, false, steps);
    ++runs;
  }
  return finished(L.fine) && (L.has_coarse || finished(L.finest));
}

void TimeStepPolicy::estimate(const Levels& L, Level3& qd, Level3& qv) {
  if (L.has_coarse) {
    qd = three_level(L.coarse.depth_center, L.mid.depth_center, L.fine.depth_center);
    qv = three_level(L.coarse.volume_removed, L.mid.volume_removed, L.fine.volume_removed);
    return;
  }
  // dt, dt/2, dt/4: the error of D(dt) is twice the larger difference (first order)
  qd = three_level(L.mid.depth_center, L.fine.depth_center, L.finest.depth_center);
  qv = three_level(L.mid.volume_removed, L.fine.volume_removed, L.finest.volume_removed);
  qd.est *= 2.0;
  qv.est *= 2.0;
}

Result TimeStepPolicy::run(const Config& cfg, const SinkFactory& make_sink) const {
  long steps = 0;
  int runs = 0;
  Levels L;
  if (!first_levels(cfg, L, steps, runs, make_sink)) {
    // reported as it ended (no estimate of a run that did not finish or of a companion that did not)
    Result& r = finished(L.mid) ? L.fine.status == "unstable_time_step" ? L.fine : L.mid : L.mid;
    if (finished(r)) r.notes.push_back("no time-step error estimate: a companion run did not finish");
    r.step.automatic = automatic_;
    r.step.runs = runs;
    r.step.steps_total = steps;
    r.step.stable_limit = dt_stable_;
    r.step.accepted_limit = kAcceptFraction * dt_stable_;
    r.step.depth_error = r.step.volume_error = std::numeric_limits<double>::quiet_NaN();
    r.step.reason = reason_;
    if (r.status != "unstable_time_step") deliver_frames(cfg, r, make_sink, steps);
    r.frames.clear();
    return std::move(r);
  }
  Level3 qd, qv;
  estimate(L, qd, qv);
  // Halving a step brings the estimate down by the scheme's order; where two halvings fail to
  // bring it below kNoDecrease of the smallest one so far, the result is not converging in dt
  // and refining further only costs time
  double best = std::max(qd.est, qv.est);
  int stalls = 0, extra_halvings = 0;
  std::string history = fmt(best, 3) + " at " + fmt(L.mid.dt, 4) + " s";
  bool stalled = false;
  // A level is refined when its estimate is not accepted, or (at most kSafeguardHalvings
  // times) when a safeguard made its run inaccurate (a step too long for the flow) or the heat
  // Courant limit split more than kMaxSubstepShare of its steps or its fine companion's
  auto refine = [&]() {
    if (!qd.accepted(cfg.tol) || !qv.accepted(cfg.tol)) return true;
    const bool split = std::max(substep_share(L.mid), substep_share(L.fine)) > kMaxSubstepShare;
    return (safeguarded(L.mid) || split) && extra_halvings++ < kSafeguardHalvings;
  };
  while (automatic_ && L.has_coarse && double(steps) + 2.0 * cfg.tp / L.fine.dt <= kMaxSteps && !stalled &&
         refine()) {
    if (!cfg.quiet)
      std::fprintf(stderr, "laser_drill: estimated error %.2e at dt = %.4g s (--tol %.2e); refining to dt = %.4g s\n",
                   std::max(qd.est, qv.est), L.mid.dt, cfg.tol, L.fine.dt);
    // shift: the reported run becomes the coarse companion, the fine one the reported run
    L.coarse = std::move(L.mid);
    L.mid = std::move(L.fine);
    L.coarse.frames.clear();
    L.coarse.frames.shrink_to_fit();
    L.fine = run_at(cfg, 0.5 * L.mid.dt, true, steps, make_sink);
    ++runs;
    if (!finished(L.fine)) return std::move(L.fine);
    estimate(L, qd, qv);
    const double e = std::max(qd.est, qv.est);
    history += ", " + fmt(e, 3) + " at " + fmt(L.mid.dt, 4) + " s";
    if (!(e < kNoDecrease * best)) stalled = ++stalls >= 2;
    best = std::min(best, e);
  }
  Estimate est;
  est.dt = L.mid.dt;
  est.companion = L.has_coarse ? L.coarse.dt : L.fine.dt;
  est.fine_companion = L.has_coarse ? L.fine.dt : L.finest.dt;
  est.runs = runs;
  est.steps = steps;
  est.stalled = stalled;
  est.history = history;
  est.depth = qd;
  est.volume = qv;
  grid_estimate(L.mid, L.coarse, cfg, est);
  report(L.mid, cfg, est);
  if (!L.skipped.empty()) L.mid.notes.push_back(L.skipped);
  const double split = std::max(substep_share(L.mid), substep_share(L.fine));
  if (split > kMaxSubstepShare)
    L.mid.notes.push_back("the heat Courant limit split " + fmt(100.0 * split, 3) +
                          " % of the steps of the estimate's runs at dt and dt/2: the step-doubling estimate "
                          "leaves out the error of the heat march's sub-steps");
  deliver_frames(cfg, L.mid, make_sink, est.steps);
  L.mid.frames.clear();
  return std::move(L.mid);
}

// The output holds the frames of the last candidate streamed (the fine run); the reported run's
// frames are written again from memory (or, beyond kMaxFrameBytes, by repeating the run).
void TimeStepPolicy::deliver_frames(const Config& cfg, Result& r, const SinkFactory& make_sink, long& steps) const {
  if (!make_sink) return;
  if (!buffered(cfg, r.dt)) {
    Config c = cfg;
    c.dt = r.dt;
    c.quiet = true;
    std::unique_ptr<FrameSink> sink = make_sink();
    const Result again = run_simulation(c, sink.get());
    steps += again.steps;
    return;
  }
  std::unique_ptr<FrameSink> sink = make_sink();
  if (!sink) return;
  sink->begin(r.xi, r.tau_m_s);
  for (const Frame& f : r.frames) sink->frame(f);
  sink->finish();
}


// Records the estimate in the reported run and marks it inaccurate where the
// estimate is above --tol (with the history when refining stalled).
void TimeStepPolicy::report(Result& fine, const Config& cfg, const Estimate& est) const {
  StepReport& s = fine.step;
  s.automatic = automatic_;
  s.companion_dt = est.companion;
  s.depth_error = est.depth.est;
  s.volume_error = est.volume.est;
  s.runs = est.runs;
  s.steps_total = est.steps;
  s.stable_limit = dt_stable_;
  s.grid_companion_dxi = est.grid_dxi;
  s.grid_companion_dt = est.grid_dt;
  s.grid_depth_error = est.grid_ed;
  s.grid_volume_error = est.grid_ev;
  s.accepted_limit = kAcceptFraction * dt_stable_;
  s.fine_companion_dt = est.fine_companion;
  s.depth_ratio = est.depth.ratio;
  s.volume_ratio = est.volume.ratio;
  s.reason = reason_ + (est.dt < dt_ ? ", refined to meet --tol" : "");
  const bool within = est.depth.accepted(cfg.tol) && est.volume.accepted(cfg.tol);
  if (!within && finished(fine)) {
    const bool high = std::max(est.depth.est, est.volume.est) > cfg.tol;
    const std::string m =
        std::string(high ? "estimated error of the time step" : "time-step differences not contracting") +
        ": depth " + fmt(est.depth.est, 4) + ", volume " + fmt(est.volume.est, 4) + " (three levels: dt = " + fmt(est.dt, 4) +
        " s against " + fmt(est.companion, 4) + " s and " + fmt(est.fine_companion, 4) +
        " s; ratios of successive differences " + fmt(est.depth.ratio, 3) + ", " + fmt(est.volume.ratio, 3) + ")" +
        (high ? " above --tol " + fmt(cfg.tol, 4)
              : ": a ratio above " + fmt(kMaxRatio, 3) + " with moves above " + fmt(kNoiseFraction, 3) +
                    " of --tol, the estimate is not trusted") +
        (automatic_ ? (est.stalled ? "" : " after refining to the step budget")
                    : "; use a smaller --dt or leave it automatic");
    const std::string stall =
        est.stalled ? "; time-step error not decreasing: the estimate did not fall below " + fmt(kNoDecrease, 3) +
                      " of the smallest one in two halvings (" + est.history + "): the result does not converge in dt, "
                      "refining stopped"
                : "";
    fine.message = fine.status == "ok" ? m + stall : fine.message + "; " + m + stall;
    fine.status = "inaccurate";
    fine.causes.push_back(est.stalled ? "time-step error not decreasing"
                                      : (high ? "time-step error estimate above --tol"
                                              : "time-step differences not contracting"));
  }
  if (std::max(est.grid_ed, est.grid_ev) > cfg.tol && finished(fine)) {
    const std::string m = "grid error estimate above --tol: depth " + fmt(est.grid_ed, 4) + ", volume " +
                          fmt(est.grid_ev, 4) + " (d(xi) = " + fmt(cfg.dxi, 4) + " against " + fmt(est.grid_dxi, 4) +
                          ", dt = " + fmt(est.grid_dt, 4) + " s) above --tol " + fmt(cfg.tol, 4) +
                          ": the result is not converged in d(xi); use a smaller --dxi";
    fine.message = fine.status == "ok" ? m : fine.message + "; " + m;
    fine.status = "inaccurate";
    fine.causes.push_back("grid error estimate above --tol");
  }
}

// Grid companion: the step-doubling companion run (2 dt, else the reported run)
// repeated at 2 d(xi); the relative difference of centre depth and removed
// volume between the two estimates the d(xi) error (first order assumed:
// conservative for the second order measured at Pr = 0.142; where the model
// does not converge in d(xi) the estimate is large and says so). At 2 dt and
// 2 d(xi) it costs a quarter of the reported run. A companion that does not
// finish gives no estimate (NaN, null in summary.json) and a note.
void TimeStepPolicy::grid_estimate(Result& fine, const Result& coarse, const Config& cfg, Estimate& est) const {
  if (!finished(fine)) return;
  // the grid companion runs at the coarse companion's step unless a safeguard acted there or
  // the estimate is taken again after a halving for it
  const bool use_coarse =
      est.companion > est.dt && finished(coarse) &&
      !safeguarded(coarse);
  const Result& base = use_coarse ? coarse : fine;
  Config gc = cfg;
  gc.dxi = 2.0 * cfg.dxi;
  est.grid_dxi = gc.dxi;
  est.grid_dt = use_coarse ? est.companion : est.dt;
  const Result grid = run_at(gc, est.grid_dt, false, est.steps);
  ++est.runs;
  if (!finished(grid)) {
    est.grid_ed = est.grid_ev = std::numeric_limits<double>::quiet_NaN();
    fine.notes.push_back("no grid error estimate: the companion run at d(xi) = " + fmt(gc.dxi, 4) + ", dt = " +
                         fmt(est.grid_dt, 4) + " s ended " + grid.status +
                         (grid.message.empty() ? "" : " (" + grid.message + ")"));
    return;
  }
  est.grid_ed = rel_diff(base.depth_center, grid.depth_center);
  est.grid_ev = rel_diff(base.volume_removed, grid.volume_removed);
}

}  // namespace laser
