// Output of laser_drill: summary.json, CSV tables and the HDF5 time series.
#pragma once

#include <string>

#include "laser_model.h"
#include "laser_params.h"

namespace laser {

// Writes DIR/summary.json, DIR/final_profile.csv, DIR/centre.csv and
// DIR/profiles.h5. Throws std::runtime_error on an I/O failure.
void write_outputs(const Config& cfg, const Result& r, double wall_time_s);
std::string summary_json(const Config& cfg, const Result& r, double wall_time_s);
// Figures 3.7/3.8: corrected-conduction gradients against s = (tau - tau_m)/tau_m.
void write_conduction_table(const std::string& dir);

}  // namespace laser
