// The check the automatic step's tests share: a run at a quarter of the step r.dt that the
// step control reported for c, and the relative change of centre depth and removed volume it
// gives (to be compared with the step-doubling estimates r.step.depth_error / volume_error).
#pragma once

#include <cmath>

#include "laser_model.h"
#include "laser_params.h"

struct QuarterStepChange {
  double depth, volume;
};

inline QuarterStepChange quarter_step_change(const laser::Config& c, const laser::Result& r) {
  laser::Config q = c;
  q.dt = 0.25 * r.dt;
  const laser::Result rq = laser::run_simulation(q);
  return {std::fabs(rq.depth_center / r.depth_center - 1.0), std::fabs(rq.volume_removed / r.volume_removed - 1.0)};
}
