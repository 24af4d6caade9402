// The checks of fix mpm/fluid's settings after the keywords are read (options_checks.h): each
// pressure model's own keywords, keywords another choice makes inert, the grid fitted to the
// bounds, derived quantities in range, and the settings that follow from the keywords given.
#include "mpm/options_checks.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <iterator>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "mpm/args.h"
#include "mpm/error.h"

namespace mpm {

namespace {

// gravity of the default volume_correction rate (m/s^2)
constexpr double kVolumeCorrectionG = 9.81;

// Keywords that belong to one pressure model only: an error under the other, naming them.
void check_pressure_model(Options &o, const std::vector<std::string> &seen) {
  static const char *const eos_only[] = {"bulk", "eos", "pmin"};
  static const char *const projection_only[] = {"tolerance", "max_iterations", "volume_correction",
                                                 "pressure_average", "pressure_output", "grain_pressure"};
  std::string bad;
  for (const std::string &kw : seen)
    for (const char *w : o.projection ? std::vector<const char *>(std::begin(eos_only), std::end(eos_only))
                                      : std::vector<const char *>(std::begin(projection_only), std::end(projection_only)))
      if (kw == w && bad.find("'" + kw + "'") == std::string::npos) bad += (bad.empty() ? "'" : ", '") + kw + "'";
  // The ghost-fluid surface finds the surface from the nodal fill, which next to a mesh wall lacks
  // the mass the B-spline puts behind it (no mirror image of a triangle): measured beside a
  // vertical and a 30 degree mesh wall, a column at rest moved at 3.5e-3 and 6.6e-2 m/s after 1 s.
  if (o.projection && std::find(seen.begin(), seen.end(), "mesh_wall") != seen.end()) o.surface_ghost = false;
  if (o.projection && o.model == Model::Yang2016)
    throw Error("Fix mpm/fluid: keyword 'model yang2016' is the dissertation's weakly compressible model and "
                "needs 'pressure eos' (with 'bulk'); remove 'pressure projection' or the model");
  if (bad.empty()) return;
  if (o.projection)
    throw Error("Fix mpm/fluid: the pressure model 'projection' (the default) does not use keyword(s) " + bad +
                " (they belong to the equation of state of the weakly compressible model); add 'pressure eos' "
                "to use that model, or remove them");
  throw Error("Fix mpm/fluid: keyword(s) " + bad + " belong to 'pressure projection' (the pressure solve); "
              "add 'pressure projection' or remove them");
}

// Keywords that another choice makes inert: one row each (keyword, when it has no effect, why);
// an error naming the keyword and the reason, from the fix command (the keywords given) and from
// fix_modify (the keyword changed). Add a row for a new dependency.
struct Inert {
  const char *keyword;
  bool (*inert)(const Options &);
  const char *why;
};
bool no_grains(const Options &o) { return !o.coupled; }
bool shear_without_viscosity(const Options &o) {
  if (o.viscosity > 0.0) return false;
  for (const Face &f : o.face)
    if (f.kind == BcKind::Shear) return true;
  return false;
}
const Inert kInert[] = {
    {"drag", no_grains, "the drag acts between the fluid and the grains of keyword 'couple', which is not given"},
    {"theta_min", no_grains, "the fluid fraction comes from the grains of keyword 'couple', which is not given"},
    {"theta_smooth", no_grains, "the fluid fraction comes from the grains of keyword 'couple', which is not given"},
    {"cell_check", no_grains, "it checks the grains of keyword 'couple', which is not given"},
    {"boundary", shear_without_viscosity,
     "a 'shear' face exerts the stress mu v_t / delta, which is 0 without keyword 'viscosity' > 0"},
};

// Grid: cubic cells fitted exactly into the bounds (the box, or keyword grid).
void fit_grid(Options &o, const ParseEnv &env) {
  GridSpec &g = o.grid;
  double b[6];
  for (int d = 0; d < 3; ++d) {
    b[2 * d] = o.grid_bounds_given ? o.gbounds[2 * d] : env.boxlo[d];
    b[2 * d + 1] = o.grid_bounds_given ? o.gbounds[2 * d + 1] : env.boxhi[d];
    const double n = (b[2 * d + 1] - b[2 * d]) / g.dx;
    const long nr = std::lround(n);
    if (nr < 1 || std::fabs(n - nr) > 1e-6 * std::max(1.0, n)) {
      std::ostringstream os;
      os << "Fix mpm/fluid: keyword 'cell' expects a cell size that divides the grid extent in "
         << "xyz"[d] << " (" << b[2 * d + 1] - b[2 * d] << "), got " << g.dx << " (" << n << " cells)";
      throw Error(os.str());
    }
    g.origin[d] = b[2 * d];
    g.ncell[d] = static_cast<int>(nr);
    g.periodic[d] = env.periodic[d];
    if (g.periodic[d] && (std::fabs(b[2 * d] - env.boxlo[d]) > 1e-9 * g.dx ||
                          std::fabs(b[2 * d + 1] - env.boxhi[d]) > 1e-9 * g.dx))
      throw Error("Fix mpm/fluid: keyword 'grid' must span the whole box in a periodic dimension");
    if (!g.periodic[d] && (b[2 * d] < env.boxlo[d] - 1e-9 * g.dx || b[2 * d + 1] > env.boxhi[d] + 1e-9 * g.dx))
      throw Error("Fix mpm/fluid: keyword 'grid' bounds must lie inside the simulation box");
  }
  g.pad = o.shape == ShapeKind::QuadraticBSpline ? 1 : 0;
}

// Values each within its range whose derived quantities are not (sound speed, stable steps,
// smoothing passes, hydrostatic density): an error naming the keywords, before any computation.
void check_derived(const Options &o) {
  const GridSpec &g = o.grid;
  std::ostringstream os;
  os.precision(6);
  double extent = 0.0;
  for (int d = 0; d < 3; ++d) extent = std::max(extent, g.ncell[d] * g.dx);
  // passes of the smoothing filter: 2 L^2 / dx^2 (coupling.h), at most 2 ncell^2
  if (o.theta_smooth > extent) {
    os << "Fix mpm/fluid: keyword 'theta_smooth' expects a smoothing length (length unit, m in SI) in [0, " << extent
       << "] (at most the largest grid extent), got " << o.theta_smooth;
    throw Error(os.str());
  }
  const double passes = 2.0 * (o.theta_smooth / g.dx) * (o.theta_smooth / g.dx);
  if (!(passes <= 1e6)) {
    os << "Fix mpm/fluid: keyword 'theta_smooth' (" << o.theta_smooth << " m) needs " << passes
       << " smoothing passes per step with cell " << g.dx << " (at most 1e6); reduce it";
    throw Error(os.str());
  }
  const double dt_visc = viscous_dt_limit(g.dx, o.rho0, o.viscosity, o.dimension);
  if (!(dt_visc >= DBL_MIN) || std::isnan(dt_visc)) {
    os << "Fix mpm/fluid: keywords 'viscosity' (" << o.viscosity << ") and 'density' (" << o.rho0
       << ") give a viscous time step limit " << dt_visc << " that is not a positive normal number in double precision";
    throw Error(os.str());
  }
  // the pressure solve forms 1/rho0 and dot products of its squares: both within double precision
  if (o.projection && !(o.rho0 >= 1e-150 && o.rho0 <= 1e150)) {
    os << "Fix mpm/fluid: keyword 'density' expects with 'pressure projection' a reference density in [1e-150, 1e150] "
       << "(the pressure solve squares 1/rho0), got " << o.rho0;
    throw Error(os.str());
  }
  if (o.projection) return;  // no equation of state
  const Eos &e = o.eos;
  double rho_hi = e.rho0;
  if (o.hydrostatic) {
    // the deepest point of the grid: the largest initial pressure and density
    const double depth = o.hydro_surface - g.origin[o.hydro_axis];
    const double p = std::max(0.0, e.rho0 * o.hydro_g * depth);
    rho_hi = e.density(p);
    if (!std::isfinite(p) || !std::isfinite(rho_hi) || !(rho_hi > 0.0)) {
      os << "Fix mpm/fluid: keyword 'hydrostatic' gives at the bottom of the grid a pressure rho0 g depth = " << p
         << " with which the equation of state ('bulk' " << e.K << ") has no finite density; reduce g or the surface";
      throw Error(os.str());
    }
  }
  // the sound speed up to 2 rho0, the density range the run watches (density warning)
  if (!std::isfinite(e.sound_speed_sq(2.0 * e.rho0)) || !std::isfinite(e.pressure(2.0 * e.rho0))) {
    os << "Fix mpm/fluid: keyword 'eos' (" << (e.kind == EosKind::Tait ? "tait, gamma " : "linear") ;
    if (e.kind == EosKind::Tait) os << e.gamma;
    os << ") with 'bulk' " << e.K << " gives at twice the reference density a pressure or sound speed that is not "
       << "finite in double precision; use a smaller gamma";
    throw Error(os.str());
  }
  const double c2 = std::max(e.sound_speed_sq(e.rho0), e.sound_speed_sq(rho_hi));
  const double dt_ac = acoustic_dt_limit(o.cfl, g.dx, std::sqrt(c2), 0.0);
  if (!std::isfinite(c2) || !(c2 > 0.0) || !std::isfinite(dt_ac) || !(dt_ac > 0.0)) {
    os << "Fix mpm/fluid: keywords 'bulk' (" << e.K << ") and 'density' (" << e.rho0
       << ") give a sound speed squared " << c2 << " and an acoustic time step limit " << dt_ac
       << " that are not finite and positive in double precision; use values of physical size";
    throw Error(os.str());
  }
}

// boundary ... inflow U | outflow: a non-periodic face, the pressure projection, no mesh walls
void check_flow_faces(const Options &o, const std::vector<std::string> &seen) {
  static const char *const names[6] = {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"};
  for (int f = 0; f < 6; ++f) {
    const Face &fc = o.face[f];
    if (!fc.flow()) continue;
    const std::string kw = std::string("boundary ") + names[f] + (fc.kind == BcKind::Inflow ? " inflow" : " outflow");
    if (o.grid.periodic[f / 2])
      throw Error("Fix mpm/fluid: keyword '" + kw + "' expects a face of a non-periodic dimension, got " + names[f] +
                  ", along which the box is periodic (boundary p in that dimension; what leaves through one face "
                  "enters through the other)");
    // eos: a point's pressure comes from its own density, which a face with p = 0 does not reach,
    // and points created at the reference density into a compressed fluid would shock it
    if (!o.projection)
      throw Error("Fix mpm/fluid: keyword '" + kw + "' needs 'pressure projection' (the default): the weakly "
                  "compressible model ('pressure eos') has no pressure condition on a face, so an outflow would "
                  "not hold p = 0 and new points at the reference density would meet a compressed fluid");
    // the labels beside mesh walls do not hold the face's node plane as an open surface
    if (std::find(seen.begin(), seen.end(), "mesh_wall") != seen.end())
      throw Error("Fix mpm/fluid: keyword '" + kw + "' cannot be combined with keyword 'mesh_wall' (a mesh may lie on "
                  "or cross the face, which would close it; the projection beside mesh walls has no open grid "
                  "faces): use grid faces, or give the fluid a free surface instead of an outflow");
  }
}

}  // namespace

// superficial_velocity axis U|v_name (also fix_modify; a.iarg at the keyword)
void parse_drive(Options &o, Args &a) {
  const char *what = "an axis x, y or z and a superficial velocity (velocity), a number or v_name of an equal-style variable";
  a.need(2, "superficial_velocity", what);
  FlowDrive dr;
  dr.active = true;
  dr.axis = axis_of(a.at(1));
  if (dr.axis < 0) bad_arg("superficial_velocity", "an axis x, y or z", a.at(1));
  const char *v = a.at(2);
  if (strncmp(v, "v_", 2) == 0) {
    if (v[2] == '\0') bad_arg("superficial_velocity", "a variable name after 'v_'", v);
    dr.variable = v + 2;
  } else if (!parse_double(v, dr.target)) {
    bad_arg("superficial_velocity", "a finite superficial velocity (velocity) or v_name of an equal-style variable", v);
  }
  o.drive = dr;
  a.iarg += 3;
}

// fix_modify superficial_velocity axis U|v_name (arg[0] the keyword): returns the words used
int modify_drive(Options &o, int narg, char **arg) {
  // the fix's global vector has the gradient's entry only if the fix command gave the keyword,
  // and the gradient it holds drives that axis
  if (!o.drive.active)
    throw Error("Fix mpm/fluid: fix_modify superficial_velocity needs the keyword in the fix command (the driving "
                "gradient's entry of the global vector is made there)");
  const FlowDrive before = o.drive;
  const int axis = o.drive.axis;
  Args a{narg, arg, 0};
  parse_drive(o, a);
  if (o.drive.axis != axis) {
    const std::string got = arg[1];
    o.drive = before;
    bad_arg("fix_modify superficial_velocity", (std::string("the axis of the fix command, ") + "xyz"[axis]).c_str(),
            got.c_str());
  }
  return a.iarg;
}

// superficial_velocity: a periodic axis (the flux it holds passes the box's faces along it), no gate
// across it (also after fix_modify)
void check_drive(const Options &o) {
  const FlowDrive &dr = o.drive;
  if (!dr.active) return;
  if (!o.grid.periodic[dr.axis]) {
    std::ostringstream os;
    os << "Fix mpm/fluid: keyword 'superficial_velocity' expects a periodic axis (the flux it holds leaves the box "
       << "through one face and enters through the other), got '" << "xyz"[dr.axis]
       << "', along which the box is not periodic (boundary p in that dimension)";
    throw Error(os.str());
  }
  if (o.gate.active && o.gate.dim == dr.axis)
    throw Error(std::string("Fix mpm/fluid: keyword 'gate' across axis ") + "xyz"[dr.axis] +
                " stops the flux that keyword 'superficial_velocity' holds along it; remove one of them");
}

void check_flow_change(const Options &before, Options &o) {
  static const char *const names[6] = {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"};
  for (int f = 0; f < 6; ++f)
    if ((o.face[f].flow() || before.face[f].flow()) && o.face[f].kind != before.face[f].kind) {
      o = before;
      throw Error(std::string("Fix mpm/fluid: fix_modify boundary cannot make face ") + names[f] +
                  " an inflow or outflow face or change one (the points it creates and removes and their "
                  "entries of the global vector are set up by the fix command); give it there");
    }
}

void check_inert(const Options &o, const std::vector<std::string> &seen, const char *command) {
  for (const Inert &r : kInert)
    if (std::find(seen.begin(), seen.end(), r.keyword) != seen.end() && r.inert(o))
      throw Error(std::string("Fix mpm/fluid: ") + command + "keyword '" + r.keyword + "' has no effect here: " + r.why +
                  "; remove it");
}

// parse_options after the keywords: the required ones, the settings that follow from those given
// (seen; given: cell, density, bulk), the grid and the checks of ranges and positions.
void finish_options(Options &o, const std::vector<std::string> &seen, const bool given[3], const ParseEnv &env) {
  if (!given[0]) throw Error("Fix mpm/fluid: keyword 'cell' (cell size) is required");
  if (!given[1]) throw Error("Fix mpm/fluid: keyword 'density' (reference density) is required");
  if (!given[2] && !o.projection)
    throw Error("Fix mpm/fluid: keyword 'pressure eos' needs keyword 'bulk' (the bulk modulus of its equation of state)");
  check_pressure_model(o, seen);
  if (o.coupled && !(o.viscosity > 0.0))
    throw Error("Fix mpm/fluid: keyword 'couple' needs keyword 'viscosity' > 0 (the drag laws scale with it)");
  // grain_pressure: the pressure the grains feel; without grains there is none to choose (and the
  // default acceleration would cost a second solve for nothing)
  if (!o.projection) o.grain_pressure_acceleration = false;  // the keyword itself: an error above
  // the model's coupling forms
  const bool text = o.model == Model::Yang2016;
  o.grad_p = text ? GradP::Fit : GradP::Weak;
  o.reaction_points = !text;
  o.drag_form = text ? DragForm::Literal : DragForm::Consistent;
  // pressure_output: with grains the acceleration pressure is solved anyway (grain_pressure's
  // default), so the points carry the flow's pressure at no cost; the multiplier's part that
  // removes the transfer's divergence within one step reached 5 times rho g h + rho (omega R)^2 in
  // a turning drum with lifters where the acceleration pressure stayed below it (docs/validation/drum.md)
  if (o.projection && o.coupled && o.grain_pressure_acceleration &&
      std::find(seen.begin(), seen.end(), "pressure_output") == seen.end())
    o.pressure_acceleration = true;
  if (!o.coupled) {
    if (std::find(seen.begin(), seen.end(), "grain_pressure") != seen.end())
      throw Error("Fix mpm/fluid: keyword 'grain_pressure' needs keyword 'couple' (the grains that feel the pressure)");
    o.grain_pressure_acceleration = false;
  }
  o.dimension = env.dimension;
  o.grid.dx = o.cell_size;
  // volume_correction: by default at the rate of a gravity wave one cell long, sqrt(g / cell)
  // (g = 9.81 m/s^2, SI units; docs/theory/projection.md, "Volume over long runs")
  if (o.projection && std::find(seen.begin(), seen.end(), "volume_correction") == seen.end())
    o.volume_correction = std::sqrt(kVolumeCorrectionG / o.grid.dx);
  // the node surface's film front: relaxed at the same rate (docs/theory/projection.md, "The step size")
  o.front_rate = o.projection && !o.surface_ghost ? std::sqrt(kVolumeCorrectionG / o.grid.dx) : 0.0;
  o.eos.rho0 = o.rho0;
  o.eos.K = o.bulk;
  fit_grid(o, env);
  if (!o.wall_pos_given) o.wall_pos = o.grid.origin[o.wall_axis];
  check_derived(o);
  check_inert(o, seen, "");
  if (o.wall_pos_given && !o.grid.periodic[o.wall_axis] &&
      !(o.wall_pos >= o.grid.origin[o.wall_axis] && o.wall_pos <= o.grid.upper(o.wall_axis))) {
    std::ostringstream os;
    os << "Fix mpm/fluid: keyword 'height' expects a wall position inside the grid along " << "xyz"[o.wall_axis]
       << " [" << o.grid.origin[o.wall_axis] << ", " << o.grid.upper(o.wall_axis) << "], got " << o.wall_pos;
    throw Error(os.str());
  }
  if (o.hydrostatic && !(o.hydro_surface > o.grid.origin[o.hydro_axis])) {
    std::ostringstream os;
    os << "Fix mpm/fluid: keyword 'hydrostatic' expects a surface above the grid's lower bound along "
       << "xyz"[o.hydro_axis] << " (" << o.grid.origin[o.hydro_axis] << "; below it every initial pressure is 0), got "
       << o.hydro_surface;
    throw Error(os.str());
  }
  const Gate &g = o.gate;
  if (g.active && !o.grid.periodic[g.dim] && (g.pos <= o.grid.origin[g.dim] || g.pos >= o.grid.upper(g.dim)))
    throw Error("Fix mpm/fluid: keyword 'gate' expects a position inside the grid");
  check_drive(o);
  check_flow_faces(o, seen);
  for (const Probe &p : o.probes)
    for (int d = 0; d < 3; ++d)
      if (!(p.lo[d] >= o.grid.origin[d] && p.hi[d] <= o.grid.upper(d))) {
        std::ostringstream os;
        os << "Fix mpm/fluid: keyword 'probe " << (p.box ? "box" : "point") << "' expects "
           << (p.box ? "bounds" : "a point") << " inside the grid along " << "xyz"[d] << " [" << o.grid.origin[d]
           << ", " << o.grid.upper(d) << "], got " << (p.lo[d] < o.grid.origin[d] ? p.lo[d] : p.hi[d]);
        throw Error(os.str());
      }
  if (o.probes.empty() && std::find(seen.begin(), seen.end(), "probe_window") != seen.end())
    throw Error("Fix mpm/fluid: keyword 'probe_window' (the probes' averaging window) needs keyword 'probe'");
}

}  // namespace mpm
