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
  // Halvings an automatic ladder skips after its first (coarse) run: ceil(log2 mbar) - 1 where
  // the heat Courant limit split that run's steps into mbar > kSkipSubsteps sub-steps on average
  // (mbar = (steps + sub-steps added) / steps), else 0.
  static int heat_courant_skip(const Result& coarse);

  // At most this many time steps over all runs of one case.
  static constexpr double kMaxSteps = 4e6;
  // At most this many node steps (time steps x grid nodes) in the reported run:
  // about 15-20 minutes of CPU at the 4e5 node steps per second measured for
  // Table 5.1; a case that needs more is refused before anything is computed.
  static constexpr double kMaxNodeSteps = 4e8;
  // At most this many halvings of an automatic step for a safeguard alone (error within --tol).
  static constexpr int kSafeguardHalvings = 3;
  // The three-level estimate is accepted where successive differences keep their sign and
  // contract by at most this ratio (observed order 1/2), or where both are below
  // kNoiseFraction of --tol; a run whose steps the heat Courant limit split in more than
  // kMaxSubstepShare of them is refined as a safeguarded one is.
  static constexpr double kMaxRatio = 0.7071067811865476;
  static constexpr double kNoiseFraction = 0.1;
  static constexpr double kMaxSubstepShare = 0.1;
  // An automatic ladder whose first (coarse) run the heat Courant limit split into more than this
  // many sub-steps per step on average skips the levels down to the one whose reported run is
  // expected unsplit (heat_courant_start).
  static constexpr double kSkipSubsteps = 4.0;
  // The first run is judged on this share of its steps: where they were split into more than
  // kSkipSubsteps sub-steps on average it stops there and the skip is taken from their mean.
  static constexpr double kSkipProbeShare = 0.1;
  // Frames of a candidate run are kept in memory up to this size (fields per node and frame).
  static constexpr double kMaxFrameBytes = 256.0 * 1024 * 1024;
  static constexpr double kFrameFields = 11;

 private:
  struct Level3 {
    double est = 0, moves = 0, ratio = 0;
    bool asymptotic = true;
    bool accepted(double tol) const;
  };
  struct Levels {
    Result coarse, mid, fine, finest;
    bool has_coarse = false;
    std::string skipped;  // note on the levels skipped by the heat Courant start (empty: none)
  };
  static Level3 three_level(double Dc, double Dm, double Df);
  static void estimate(const Levels& L, Level3& qd, Level3& qv);
  bool first_levels(const Config& cfg, Levels& L, long& steps, int& runs, const SinkFactory& make_sink) const;
  void deliver_frames(const Config& cfg, Result& r, const SinkFactory& make_sink, long& steps) const;
  bool buffered(const Config& cfg, double dt) const;
  struct Estimate {
    double dt = 0, companion = 0;  // reported step, coarse companion's step
    int runs = 0;
    long steps = 0;
    bool stalled = false;
    std::string history;
    double grid_dxi = 0, grid_dt = 0, grid_ed = 0, grid_ev = 0;  // grid companion's d(xi), step, error estimates
    double fine_companion = 0;
    Level3 depth, volume;  // three-level estimates of the relative depth and volume errors (est)
  };
  void grid_estimate(Result& fine, const Result& coarse, const Config& cfg, Estimate& est) const;
  void report(Result& fine, const Config& cfg, const Estimate& est) const;
  Result run_at(Config cfg, double dt, bool reported, long& steps, const SinkFactory& make_sink = nullptr) const;
  void check_work(const Config& cfg);
  double dt_ = 0, dt_stable_ = 0, nodes_ = 3;
  bool automatic_ = false;
  std::string reason_;
};

}  // namespace laser
