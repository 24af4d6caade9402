// Case description of laser_drill: every parameter declared once (name, TOML
// section, unit, range, default, help), read from defaults < material preset <
// config file (TOML, toml++) < command line (CLI11), and validated before
// anything is computed or written.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "laser_laws.h"

namespace laser {

// v as an ostream prints it with that precision (numbers in messages and notes).
std::string fmt(double v, int precision = 6);

constexpr const char* kVersion = "2.0.0";

enum class FlowModel { Conduction, Rising, RisingFall, Boundary };
enum class SolidModel { Exact, Shifted, Stefan };
// Melt layer energy: Advected = quasi-steady advection-diffusion in the frame of
// the vaporizing surface (exponential profile; the vaporized mass carries
// c_pl (T_s - T_m)); Text = the linear conduction layer of the dissertation.
enum class MeltEnergy { Advected, Text };
// Surface-normal velocity of the melt flow in (4-13): Conservative = the
// divergence of the layer's volume flux (includes -u(g) dg/dxi, the melt is
// conserved), Text = v(xi, g) of (4-22)/(4-13) as printed.
enum class MeltFlow { Conservative, Text };
enum class MeltHeat { Auto, Ode, Flux };
// Heat content of the melt layer with the face heat fluxes: Transient = the
// transient term of (3-3b) kept in the layer's energy balance (the layer's
// content int theta dzeta changes over a step), Steady = the text's quasi-steady
// layer (what flows in is conducted out at once); Auto = transient with the face
// heat fluxes and the implicit melt update (docs/theory/laser_model.md 2.7).
enum class MeltContent { Auto, Transient, Steady };
// Curvature factor of the melting front in (3-39)/(3-40): Conduction = the two
// branches of (3-37) set by conduction into the curved solid (C_c >= 1 under a
// front that bulges into the solid, a > 0; damps node-scale modes of the front),
// Text = (3-37) as printed (C_c <= 1 for a > 0; feeds them; docs 2.5).
enum class CurvatureForm { Conduction, Text };

const char* to_string(FlowModel m);
const char* to_string(SolidModel m);
const char* to_string(MeltEnergy m);
const char* to_string(MeltFlow m);
const char* to_string(CurvatureForm m);

struct Config {
  Material mat;
  double I0 = 7.5e10;     // W/m2
  double tp = 700e-6;     // s
  double R = 0.254e-3;    // m
  double absorbed_I0() const { return I0 * absorptivity; }  // W/m2 the surface takes
  FlowModel model = FlowModel::RisingFall;
  double m = 2.0;
  double xi_p = 1.0;
  SolidModel solid = SolidModel::Exact;
  MeltEnergy melt_energy = MeltEnergy::Advected;
  MeltFlow melt_flow = MeltFlow::Conservative;
  // b2 of (4-25): auto = flux with the conservative flow, ode with the text's flow
  MeltHeat melt_heat = MeltHeat::Auto;
  bool flux_heat() const {
    return melt_heat == MeltHeat::Flux || (melt_heat == MeltHeat::Auto && melt_flow == MeltFlow::Conservative);
  }
  MeltContent melt_content = MeltContent::Auto;
  // auto: transient with the face heat fluxes and the implicit melt update; the explicit
  // update (4-14) keeps the quasi-steady layer (docs/theory/laser_model.md 2.7: with it the
  // transient term does not converge in dt at the Table 5.1 case)
  bool transient_content() const {
    return flux_heat() && model != FlowModel::Conduction &&
           (melt_content == MeltContent::Transient || (melt_content == MeltContent::Auto && implicit_melt));
  }
  // Recoil pressure that drives the melt flow, as a fraction of p_sat(T_s): 1 =
  // the text (full saturation pressure), 0.54 = Anisimov (1968) / Knight (1979)
  // for strong evaporation with a Knudsen layer.
  double recoil = 1.0;
  double absorptivity = 1.0;  // absorbed fraction of the beam (the text: 1)
  double shift = 3.0 / (4.0 * kPi);  // (3-36): shift of the Stefan solution in tau_m
  bool curvature = true;
  CurvatureForm curvature_form = CurvatureForm::Conduction;
  bool moving_origin = true;
  bool implicit_melt = false;  // implicit in g instead of (4-14): backward Euler, or
  bool trapezoidal_melt = false;  // the trapezoidal rule (implies implicit_melt)
  const char* melt_update_name() const {
    return trapezoidal_melt ? "trapezoidal" : implicit_melt ? "implicit" : "explicit";
  }
  double dxi = 0.0125;
  double xi_max = 0.0;     // 0: just beyond the last node that melts within the pulse
  double dt = 0.0;         // s; 0: chosen by the time-step policy (laser_timestep.h)
  double dtau = 0.0;       // nondimensional; overrides dt when > 0
  double tol = 1e-3;       // relative depth/volume error the time-step policy aims at
  // heat Courant number kept per step by --melt-heat flux by splitting the step
  // (docs/theory/laser_model.md 2.10); 0: no splitting
  double heat_courant = 0.0;
  // Set by the time-step policy for the first run of an automatic ladder (no option): where the
  // heat Courant limit split the first heat_probe_share of the run's steps into more than
  // heat_probe_mbar sub-steps on average, the run stops there with status "split_probe" (the
  // ladder then skips to finer levels, laser_timestep.h); 0: the run goes to the end.
  double heat_probe_share = 0.0;
  double heat_probe_mbar = 0.0;
  int frames = 200;        // HDF5 frames
  std::string out = "laser_out";
  bool overwrite = false;
  bool quiet = false;
  std::string config_file;
  std::string material = "superalloy";
};

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Invocation {
  Config cfg;
  bool exit_now = false;        // --help or --version printed
  bool dump_conduction = false;
};

// Parses argv with CLI11 and the file named by --config with toml++. Throws
// UsageError naming the option (or file:line and key), its unit and range.
// Prints --help / --version to stdout and sets exit_now.
Invocation parse_command_line(int argc, const char* const* argv);
// Reads one TOML config into cfg (sections [laser], [model], [numerics],
// [output], [material]); throws UsageError. Exposed for the tests.
void read_config_file(Config& cfg, const std::string& path);
// Cross-parameter checks (T_i < T_m < T_sat0, grid, step versus pulse);
// throws UsageError.
void validate(Config& c);
// The material presets built in (Table 5.1 of the dissertation).
std::vector<std::string> material_presets();
// Keys of each TOML section, for documentation and tests.
std::vector<std::pair<std::string, std::string>> config_keys();

}  // namespace laser
