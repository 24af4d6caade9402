// The time-step policy of laser_drill, in one place: the automatic step from
// pulse length, melting time, radius and intensity (through the explicit
// stability limit of (4-14)), the check of a step given by the user, and the
// a-posteriori error estimate by step doubling, which refines an automatic
// step until the estimate meets --tol or marks the run `inaccurate`.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "laser_model.h"
#include "laser_params.h"

namespace laser {

class TimeStepPolicy {
 public:
  // Chooses or checks the step; throws UsageError for a step given by the
  // user that is above the explicit limit or needs too many steps.
  explicit TimeStepPolicy(const Config& cfg);

  double dt() const { return dt_; }
  bool automatic() const { return automatic_; }
  const std::string& reason() const { return reason_; }

  using SinkFactory = std::function<std::unique_ptr<FrameSink>()>;
  // Runs the case at dt() and a companion run at twice (or half) the step,
  // estimates the relative depth and volume error of the reported run from
  // their difference (first order, so the estimate is conservative for the
  // observed orders 1.2-2), and, for an automatic step, halves the step until
  // the estimate is below cfg.tol or the step budget is spent. Frames of the
  // reported run go to a fresh sink from make_sink (may be empty).
  Result run(const Config& cfg, const SinkFactory& make_sink) const;

  // At most this many time steps over all runs of one case.
  static constexpr double kMaxSteps = 4e6;
  // At most this many node steps (time steps x grid nodes) in the reported run:
  // about 15-20 minutes of CPU at the 4e5 node steps per second measured for
  // Table 5.1; a case that needs more is refused before anything is computed.
  static constexpr double kMaxNodeSteps = 4e8;

 private:
  struct Estimate {
    double dt, companion, ed, ev;  // reported step, companion step, relative depth/volume error estimates
    int runs;
    long steps;
    bool stalled;
    std::string history;
    double grid_dxi = 0, grid_dt = 0, grid_ed = 0, grid_ev = 0;  // grid companion's d(xi), step, error estimates
  };
  void grid_estimate(Result& fine, const Result& coarse, const Config& cfg, Estimate& est) const;
  void report(Result& fine, const Config& cfg, const Estimate& est) const;
  Result run_at(Config cfg, double dt, const SinkFactory& make_sink, bool reported, long& steps) const;
  void check_work(const Config& cfg) const;
  double dt_ = 0, dt_stable_ = 0;
  bool automatic_ = false;
  std::string reason_;
};

}  // namespace laser
