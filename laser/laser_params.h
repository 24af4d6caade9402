// Case description of laser_drill: every parameter declared once (name, unit,
// range, default, help), read from defaults < material preset < config file
// < command line, and validated before anything is written.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "laser_laws.h"

namespace laser {

enum class FlowModel { Conduction, Rising, RisingFall, Boundary };
enum class SolidModel { Exact, Shifted, Stefan };

const char* to_string(FlowModel m);
const char* to_string(SolidModel m);

struct Config {
  Material mat;
  double I0 = 7.5e10;     // W/m2
  double tp = 700e-6;     // s
  double R = 0.254e-3;    // m
  FlowModel model = FlowModel::RisingFall;
  double m = 2.0;
  double xi_p = 1.0;
  SolidModel solid = SolidModel::Exact;
  double shift = 3.0 / (4.0 * kPi);  // (3-36): shift of the Stefan solution in tau_m
  bool curvature = true;
  bool moving_origin = true;
  bool implicit_melt = false;  // backward Euler for g instead of (4-14)
  double dxi = 0.0125;
  double xi_max = 0.0;     // 0: just beyond the last node that melts within the pulse
  double dt = 0.0;         // s; 0: 5e-7 s * min(1, (7.5e10 W/m2 / I0)^2)
  double dtau = 0.0;       // nondimensional; overrides dt when > 0
  bool dt_auto = false;    // dt chosen by the program: halved on instability
  int frames = 200;        // HDF5 frames
  std::string out = "laser_out";
  bool quiet = false;
  std::string config_file;
  std::string material = "superalloy";
};

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Parses argv (and the config file named by --config). Throws UsageError with
// a message naming the option and its valid range. Sets help=true for --help.
Config parse_command_line(int argc, const char* const* argv, bool& help, bool& dump_conduction);
// Checks ranges and cross-parameter conditions; throws UsageError.
void validate(Config& c);
std::string usage_text();
// The material presets built in (Table 5.1 of the dissertation).
std::vector<std::string> material_presets();

}  // namespace laser
