#include "mpm/options.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <iterator>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "mpm/error.h"
#include "mpm/options_checks.h"

namespace mpm {

const char *const kPointFields[10] = {"v", "p", "rho", "vol", "tau", "theta", "id", "type", "affine", "mass"};
const char *const kGridFields[2] = {"mass", "v"};

namespace {

const char *kFaceNames[6] = {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"};

// a keyword with one of two words: flag = (word == first)
void choice(Args &a, const char *first, const char *second, bool &flag) {
  const char *kw = a.at(0);
  const std::string expected = std::string("'") + first + "' or '" + second + "'";
  a.need(1, kw, expected.c_str());
  if (strcmp(a.at(1), first) == 0)
    flag = true;
  else if (strcmp(a.at(1), second) == 0)
    flag = false;
  else
    bad_arg(kw, expected.c_str(), a.at(1));
  a.iarg += 2;
}

void parse_grid(Options &o, Args &a, const ParseEnv &) {
  a.need(6, "grid", "six bounds xlo xhi ylo yhi zlo zhi");
  for (int k = 0; k < 6; ++k)
    if (!parse_double(a.at(1 + k), o.gbounds[k])) bad_arg("grid", "a number", a.at(1 + k));
  for (int d = 0; d < 3; ++d)
    if (o.gbounds[2 * d + 1] <= o.gbounds[2 * d]) bad_arg("grid", "hi > lo in every dimension", a.at(2 + 2 * d));
  o.grid_bounds_given = true;
  a.iarg += 7;
}

void parse_eos(Options &o, Args &a, const ParseEnv &) {
  a.need(1, "eos", "'linear' or 'tait gamma'");
  if (strcmp(a.at(1), "linear") == 0) {
    o.eos.kind = EosKind::Linear;
    a.iarg += 2;
  } else if (strcmp(a.at(1), "tait") == 0) {
    a.need(2, "eos", "'tait' followed by the exponent gamma");
    if (!parse_double(a.at(2), o.eos.gamma) || o.eos.gamma < 1.0)
      bad_arg("eos tait", "an exponent gamma >= 1", a.at(2));
    o.eos.kind = EosKind::Tait;
    a.iarg += 3;
  } else
    bad_arg("eos", "'linear' or 'tait'", a.at(1));
}

void parse_shape(Options &o, Args &a, const ParseEnv &) {
  a.need(1, "shape", "'linear' or 'bspline2'");
  if (strcmp(a.at(1), "linear") == 0)
    o.shape = ShapeKind::Linear;
  else if (strcmp(a.at(1), "bspline2") == 0)
    o.shape = ShapeKind::QuadraticBSpline;
  else
    bad_arg("shape", "'linear' or 'bspline2'", a.at(1));
  a.iarg += 2;
}

void parse_transfer(Options &o, Args &a, const ParseEnv &) {
  a.need(1, "transfer", "'apic', 'pic' or 'flip alpha'");
  if (strcmp(a.at(1), "apic") == 0) {
    o.transfer = Transfer::Apic;
    a.iarg += 2;
  } else if (strcmp(a.at(1), "pic") == 0) {
    o.transfer = Transfer::Pic;
    a.iarg += 2;
  } else if (strcmp(a.at(1), "flip") == 0) {
    // optional FLIP fraction; a following word that is not a number is the next keyword
    o.transfer = Transfer::Flip;
    o.flip_alpha = 1.0;
    a.iarg += 2;
    double v;
    if (a.iarg < a.narg && !find_keyword(a.at(0))) {
      if (!parse_double(a.at(0), v) || v < 0.0 || v > 1.0) bad_arg("transfer flip", "a FLIP fraction in [0,1]", a.at(0));
      o.flip_alpha = v;
      ++a.iarg;
    }
  } else
    bad_arg("transfer", "'apic', 'pic' or 'flip'", a.at(1));
}

void parse_update(Options &o, Args &a, const ParseEnv &) { choice(a, "musl", "usl", o.musl); }
void parse_model(Options &o, Args &a, const ParseEnv &) {
  bool standard = true;
  choice(a, "standard", "yang2016", standard);
  o.model = standard ? Model::Standard : Model::Yang2016;
}

// 'multiplier' or 'acceleration' (true) of the projection's pressure kinds
void multiplier_or_acceleration(Args &a, bool &acceleration) {
  bool multiplier = true;
  choice(a, "multiplier", "acceleration", multiplier);
  acceleration = !multiplier;
}

void parse_pressure_output(Options &o, Args &a, const ParseEnv &) {
  multiplier_or_acceleration(a, o.pressure_acceleration);
}
void parse_grain_pressure(Options &o, Args &a, const ParseEnv &) {
  multiplier_or_acceleration(a, o.grain_pressure_acceleration);
}


const char *const kBoundaryKinds = "'noslip', 'freeslip', 'partial f', 'shear delta', 'inflow U' or 'outflow'";

// boundary FACE KIND [value], also for fix_modify (a.iarg at the keyword)
void parse_face(Options &o, Args &a) {
  const char *name = a.at(1), *kind = a.at(2);
  int f0 = -1, f1 = -1;
  if (strcmp(name, "all") == 0) {
    f0 = 0;
    f1 = 5;
  } else {
    for (int f = 0; f < 6; ++f)
      if (strcmp(name, kFaceNames[f]) == 0) f0 = f1 = f;
  }
  if (f0 < 0) bad_arg("boundary", "a face xlo xhi ylo yhi zlo zhi or all", name);
  Face fc;
  int used = 3;
  if (strcmp(kind, "noslip") == 0) {
    fc.kind = BcKind::NoSlip;
    fc.sticky = 1.0;
  } else if (strcmp(kind, "freeslip") == 0) {
    fc.kind = BcKind::FreeSlip;
    fc.sticky = 0.0;
  } else if (strcmp(kind, "partial") == 0) {
    if (a.iarg + 3 >= a.narg) bad_arg("boundary partial", "a sticky fraction in [0,1]", nullptr);
    if (!parse_double(a.at(3), fc.sticky) || fc.sticky < 0.0 || fc.sticky > 1.0)
      bad_arg("boundary partial", "a sticky fraction in [0,1]", a.at(3));
    fc.kind = BcKind::Partial;
    used = 4;
  } else if (strcmp(kind, "shear") == 0) {
    if (a.iarg + 3 >= a.narg) bad_arg("boundary shear", "a positive wall layer thickness delta (length)", nullptr);
    if (!parse_double(a.at(3), fc.delta) || !(fc.delta > 0.0))
      bad_arg("boundary shear", "a positive wall layer thickness delta (length)", a.at(3));
    fc.kind = BcKind::Shear;
    fc.sticky = 0.0;
    used = 4;
  } else if (strcmp(kind, "inflow") == 0) {
    const char *what = "a normal velocity U > 0 (velocity, into the grid) of the inflow";
    if (a.iarg + 3 >= a.narg) bad_arg("boundary inflow", what, nullptr);
    if (!parse_double(a.at(3), fc.inflow) || !(fc.inflow > 0.0) || !std::isfinite(fc.inflow))
      bad_arg("boundary inflow", what, a.at(3));
    fc.kind = BcKind::Inflow;
    fc.sticky = 1.0;
    used = 4;
  } else if (strcmp(kind, "outflow") == 0) {
    fc.kind = BcKind::Outflow;
    fc.sticky = 0.0;
  } else
    bad_arg("boundary", kBoundaryKinds, kind);
  if (fc.flow() && f0 != f1)
    bad_arg("boundary", "one face (xlo xhi ylo yhi zlo zhi) for 'inflow' or 'outflow'", name);
  for (int f = f0; f <= f1; ++f) o.face[f] = fc;
  a.iarg += used;
}

void parse_boundary(Options &o, Args &a, const ParseEnv &) {
  a.need(2, "boundary", "a face (xlo xhi ylo yhi zlo zhi all) and 'noslip', 'freeslip', 'partial f', 'shear delta', "
                       "'inflow U' or 'outflow'");
  parse_face(o, a);
}

void parse_gate(Options &o, Args &a, const ParseEnv &) {
  a.need(4, "gate", "'dim pos lower|upper release_time'");
  Gate &g = o.gate;
  g.dim = axis_of(a.at(1));
  if (g.dim < 0) bad_arg("gate", "an axis x, y or z", a.at(1));
  if (!parse_double(a.at(2), g.pos)) bad_arg("gate", "a gate position", a.at(2));
  if (strcmp(a.at(3), "lower") == 0)
    g.fluid_below = true;
  else if (strcmp(a.at(3), "upper") == 0)
    g.fluid_below = false;
  else
    bad_arg("gate", "'lower' or 'upper' (side of the gate that holds the fluid)", a.at(3));
  if (strcmp(a.at(4), "never") == 0)
    g.release_time = -1.0;
  else if (!parse_double(a.at(4), g.release_time) || g.release_time < 0.0)
    bad_arg("gate", "a release time >= 0 or 'never'", a.at(4));
  g.active = true;
  a.iarg += 5;
}

void parse_couple(Options &o, Args &a, const ParseEnv &env) {
  a.need(1, "couple", "the group-ID of the DEM grains");
  o.couple_group = a.at(1);
  if (!env.group_exists || !env.group_exists(a.at(1)))
    bad_arg("couple", "an existing group-ID of the DEM grains", a.at(1));
  o.coupled = true;
  a.iarg += 2;
}

void parse_drag(Options &o, Args &a, const ParseEnv &) {
  a.need(1, "drag", "a drag law ergun_wenyu, difelice or stokes");
  if (!parse_drag_law(a.at(1), o.drag_law)) bad_arg("drag", "a drag law ergun_wenyu, difelice or stokes", a.at(1));
  a.iarg += 2;
  DragForm form;
  if (a.iarg < a.narg && parse_drag_form(a.at(0), form))
    throw Error(std::string("Fix mpm/fluid: keyword 'drag' takes the law only, got the form '") + a.at(0) +
                "' after it; the text's literal form belongs to 'model yang2016'");
}

void parse_pmin(Options &o, Args &a, const ParseEnv &) {
  a.need(1, "pmin", "the lowest (cavitation) pressure, a number or 'none'");
  if (strcmp(a.at(1), "none") == 0)
    o.pmin = -HUGE_VAL;
  else if (!parse_double(a.at(1), o.pmin) || o.pmin > 0.0)
    bad_arg("pmin", "the lowest (cavitation) pressure, a number <= 0 (no tension beyond it) or 'none'", a.at(1));
  a.iarg += 2;
}

void parse_fill(Options &o, Args &a, const ParseEnv &env) {
  a.need(6, "fill", "'region-ID nx ny nz type T'");
  o.fill_region = a.at(1);
  for (int d = 0; d < 3; ++d)
    if (!parse_int(a.at(2 + d), o.fill_ppc[d]) || o.fill_ppc[d] < 1 || o.fill_ppc[d] > 8)
      bad_arg("fill", "points per cell per direction, an integer 1..8", a.at(2 + d));
  if (strcmp(a.at(5), "type") != 0) bad_arg("fill", "'type T' after the points per cell", a.at(5));
  if (!parse_int(a.at(6), o.fill_type) || o.fill_type < 1 || o.fill_type > env.ntypes)
    bad_arg("fill type", "an existing atom type", a.at(6));
  a.iarg += 7;
  // optional: inside mesh-ID (once), outside mesh-ID (repeated); the meshes are checked at the fill
  o.fill_inside.clear();
  o.fill_outside.clear();
  while (a.iarg < a.narg && (strcmp(a.at(0), "inside") == 0 || strcmp(a.at(0), "outside") == 0)) {
    const bool in = strcmp(a.at(0), "inside") == 0;
    const char *kw = in ? "fill inside" : "fill outside";
    a.need(1, kw, "the ID of a closed fix mesh/surface");
    const std::string id = a.at(1);
    if (in && !o.fill_inside.empty()) bad_arg(kw, "one container mesh ('inside' given once)", a.at(1));
    if (id == o.fill_inside || std::find(o.fill_outside.begin(), o.fill_outside.end(), id) != o.fill_outside.end())
      bad_arg(kw, "a mesh not named before in this fill", a.at(1));
    if (in)
      o.fill_inside = id;
    else
      o.fill_outside.push_back(id);
    a.iarg += 2;
  }
}

void parse_hydrostatic(Options &o, Args &a, const ParseEnv &) {
  a.need(3, "hydrostatic", "'axis surface g' (initial pressure rho g (surface - coordinate))");
  o.hydro_axis = axis_of(a.at(1));
  if (o.hydro_axis < 0) bad_arg("hydrostatic", "an axis x, y or z", a.at(1));
  if (!parse_double(a.at(2), o.hydro_surface)) bad_arg("hydrostatic", "the surface coordinate", a.at(2));
  if (!parse_double(a.at(3), o.hydro_g) || o.hydro_g < 0.0) bad_arg("hydrostatic", "g >= 0", a.at(3));
  o.hydrostatic = true;
  a.iarg += 4;
}

void parse_front(Options &o, Args &a, const ParseEnv &) {
  a.need(1, "front", "an axis x, y or z");
  o.front_axis = axis_of(a.at(1));
  if (o.front_axis < 0) bad_arg("front", "an axis x, y or z", a.at(1));
  a.iarg += 2;
}

void parse_height(Options &o, Args &a, const ParseEnv &) {
  a.need(3, "height", "'axis wall-axis wall-position'");
  o.height_axis = axis_of(a.at(1));
  o.wall_axis = axis_of(a.at(2));
  if (o.height_axis < 0 || o.wall_axis < 0 || o.height_axis == o.wall_axis)
    bad_arg("height", "two different axes x, y or z", a.at(1));
  if (!parse_double(a.at(3), o.wall_pos)) bad_arg("height", "a wall position", a.at(3));
  o.wall_pos_given = true;
  a.iarg += 4;
}

void parse_every(Options &o, Args &a, const ParseEnv &) {
  const char *what = "an integer N >= 1 (the fluid advances every N-th time step) or 'auto'";
  a.need(1, "every", what);
  o.every_auto = strcmp(a.at(1), "auto") == 0;
  if (o.every_auto)
    o.fluid_every = 1;
  else if (!parse_int(a.at(1), o.fluid_every) || o.fluid_every < 1)
    bad_arg("every", what, a.at(1));
  a.iarg += 2;
}

bool is_one_of(const char *w, const char *const *list, int n) {
  for (int q = 0; q < n; ++q)
    if (strcmp(w, list[q]) == 0) return true;
  return false;
}

void parse_output(Options &o, Args &a, const ParseEnv &) {
  a.need(3, "output", "'N prefix points f1 ... [grid g1 ...]'");
  if (!parse_int(a.at(1), o.out_every) || o.out_every < 0)
    bad_arg("output", "an output interval N >= 0 (steps; 0 = no output)", a.at(1));
  o.out_prefix = a.at(2);
  a.iarg += 3;
  if (strcmp(a.at(0), "points") != 0) bad_arg("output", "'points' followed by field names", a.at(0));
  ++a.iarg;
  std::vector<std::string> *list = &o.out_point_fields;
  while (a.iarg < a.narg) {
    const char *w = a.at(0);
    if (strcmp(w, "grid") == 0 && list == &o.out_point_fields) {
      // 'grid' starts the grid-field list only if a grid field follows;
      // otherwise it is the fix's own 'grid' keyword
      if (!(a.iarg + 1 < a.narg && is_one_of(a.at(1), kGridFields, 2))) break;
      list = &o.out_grid_fields;
      ++a.iarg;
      continue;
    }
    const bool points = list == &o.out_point_fields;
    if (!(points ? is_one_of(w, kPointFields, 10) : is_one_of(w, kGridFields, 2))) {
      // The first word that is no field name ends the list only if it is a keyword.
      if (find_keyword(w)) break;
      std::string names = points ? "point fields" : "grid fields";
      for (const char *f : points ? std::vector<const char *>(kPointFields, kPointFields + 10)
                                  : std::vector<const char *>(kGridFields, kGridFields + 2))
        names += std::string(" ") + f;
      bad_arg(points ? "output points" : "output grid", names.c_str(), w);
    }
    list->push_back(w);
    ++a.iarg;
  }
  if (o.out_point_fields.empty() && o.out_grid_fields.empty())
    bad_arg("output", "at least one field after 'points' (point fields or 'grid' and grid fields)", nullptr);
}

void parse_pressure(Options &o, Args &a, const ParseEnv &) { choice(a, "projection", "eos", o.projection); }

void parse_max_iterations(Options &o, Args &a, const ParseEnv &) {
  // hypre's PCG keeps two doubles per allowed iteration (its residual history): 1e6 is 16 MB
  const char *what = "an integer in [1, 1000000] (iterations of the pressure solve)";
  a.need(1, "max_iterations", what);
  if (!parse_int(a.at(1), o.pressure_max_iterations, 1, 1000000))
    bad_arg("max_iterations", what, a.at(1));
  a.iarg += 2;
}

void parse_probe(Options &o, Args &a, const ParseEnv &) {
  const char *what = "'point x y z' or 'box xlo xhi ylo yhi zlo zhi' (length)";
  a.need(1, "probe", what);
  Probe p;
  if (strcmp(a.at(1), "point") == 0) {
    a.need(4, "probe point", "three coordinates x y z (length)");
    for (int d = 0; d < 3; ++d) {
      if (!parse_double(a.at(2 + d), p.lo[d])) bad_arg("probe point", "a coordinate (length)", a.at(2 + d));
      p.hi[d] = p.lo[d];
    }
    a.iarg += 5;
  } else if (strcmp(a.at(1), "box") == 0) {
    p.box = true;
    a.need(7, "probe box", "six bounds xlo xhi ylo yhi zlo zhi (length)");
    for (int d = 0; d < 3; ++d) {
      if (!parse_double(a.at(2 + 2 * d), p.lo[d])) bad_arg("probe box", "a bound (length)", a.at(2 + 2 * d));
      if (!parse_double(a.at(3 + 2 * d), p.hi[d])) bad_arg("probe box", "a bound (length)", a.at(3 + 2 * d));
      if (!(p.hi[d] > p.lo[d])) bad_arg("probe box", "hi > lo in every dimension", a.at(3 + 2 * d));
    }
    a.iarg += 8;
  } else
    bad_arg("probe", what, a.at(1));
  o.probes.push_back(p);
}

void parse_superficial_velocity(Options &o, Args &a, const ParseEnv &) { parse_drive(o, a); }

void parse_mesh_wall(Options &, Args &a, const ParseEnv &env) {
  if (!env.mesh_wall) bad_arg("mesh_wall", "a LIGGGHTS host", nullptr);
  a.iarg = env.mesh_wall(a.narg, a.arg, a.iarg);
}

#define REAL(member) &Options::member
constexpr double kInf = HUGE_VAL;

// name, type, unit, range, default, help; numeric target, lo, hi, open lo, open hi; yes/no flag;
// parse function; fix_modify
const std::vector<Keyword> kTable = {
    {"cell", "real", "length", "> 0", "required", "a positive cell size (length)",
     REAL(cell_size), 0.0, kInf, true, true, nullptr, nullptr, false},
    {"grid", "xlo xhi ylo yhi zlo zhi", "length", "hi > lo, inside the box", "simulation box",
     "six bounds xlo xhi ylo yhi zlo zhi", nullptr, 0, 0, false, false, nullptr, parse_grid, false},
    {"density", "real", "mass/volume", "> 0", "required", "a positive reference density",
     REAL(rho0), 0.0, kInf, true, true, nullptr, nullptr, false},
    {"bulk", "real", "pressure", "> 0", "required with pressure eos", "a positive bulk modulus (pressure)",
     REAL(bulk), 0.0, kInf, true, true, nullptr, nullptr, false},
    {"viscosity", "real", "pressure*time", ">= 0", "0", "a non-negative dynamic viscosity",
     REAL(viscosity), 0.0, kInf, false, true, nullptr, nullptr, false},
    {"eos", "linear | tait gamma", "-", "gamma >= 1", "linear", "'linear' or 'tait gamma'",
     nullptr, 0, 0, false, false, nullptr, parse_eos, false},
    {"shape", "linear | bspline2", "-", "", "bspline2", "'linear' or 'bspline2'",
     nullptr, 0, 0, false, false, nullptr, parse_shape, false},
    {"transfer", "apic | pic | flip [alpha]", "-", "alpha in [0,1]", "flip 1", "'apic', 'pic' or 'flip alpha'",
     nullptr, 0, 0, false, false, nullptr, parse_transfer, false},
    {"update", "musl | usl", "-", "", "musl", "'musl' or 'usl'",
     nullptr, 0, 0, false, false, nullptr, parse_update, false},
    {"model", "standard | yang2016", "-", "", "standard", "'standard' or 'yang2016'",
     nullptr, 0, 0, false, false, nullptr, parse_model, false},
    {"boundary", "face kind [value]", "-, length, velocity", "sticky in [0,1], delta > 0, inflow U > 0", "all noslip",
     "a face (xlo xhi ylo yhi zlo zhi all) and 'noslip', 'freeslip', 'partial f', 'shear delta', 'inflow U' or 'outflow'",
     nullptr, 0, 0, false, false, nullptr, parse_boundary, true},
    {"gate", "dim pos lower|upper time|never", "length, time", "inside the grid, time >= 0", "no gate",
     "'dim pos lower|upper release_time'", nullptr, 0, 0, false, false, nullptr, parse_gate, true},
    {"damping", "real", "1/time", ">= 0", "0", "a damping rate (1/time) >= 0",
     REAL(damping), 0.0, kInf, false, true, nullptr, nullptr, true},
    {"cfl", "real", "-", "(0,1]", "0.5", "a CFL number in (0,1]",
     REAL(cfl), 0.0, 1.0, true, false, nullptr, nullptr, true},
    {"subcycle", "yes/no", "-", "", "no", "'yes' or 'no'",
     nullptr, 0, 0, false, false, &Options::subcycle, nullptr, true},
    {"every", "integer or auto", "steps", ">= 1", "1", "an integer N >= 1 (the fluid advances every N-th time step) or 'auto'",
     nullptr, 0, 0, false, false, nullptr, parse_every, false},
    {"mass_threshold", "real", "-", "[0,1)", "1e-5", "a fraction of the point mass in [0,1)",
     REAL(mass_threshold), 0.0, 1.0, false, true, nullptr, nullptr, false},
    {"sparse", "yes/no", "-", "", "yes", "'yes' or 'no'",
     nullptr, 0, 0, false, false, &Options::sparse, nullptr, false},
    {"pressure", "projection | eos", "-", "", "projection",
     "'eos' or 'projection'", nullptr, 0, 0, false, false, nullptr, parse_pressure, false},
    {"tolerance", "real", "-", "> 0", "1e-8", "a relative residual > 0 of the pressure solve",
     REAL(pressure_tolerance), 0.0, kInf, true, true, nullptr, nullptr, false},
    {"max_iterations", "integer", "-", "[1, 1000000]", "200", "an integer in [1, 1000000] (iterations of the pressure solve)",
     nullptr, 0, 0, false, false, nullptr, parse_max_iterations, false},
    {"volume_correction", "real", "1/time", ">= 0", "sqrt(9.81 m/s^2 / cell)", "a rate (1/time) >= 0 at which the points' volume error is removed",
     REAL(volume_correction), 0.0, kInf, false, true, nullptr, nullptr, false},
    {"pressure_output", "multiplier | acceleration", "-", "", "acceleration with couple, else multiplier", "'multiplier' or 'acceleration'",
     nullptr, 0, 0, false, false, nullptr, parse_pressure_output, false},
    {"grain_pressure", "multiplier | acceleration", "-", "", "acceleration", "'multiplier' or 'acceleration'",
     nullptr, 0, 0, false, false, nullptr, parse_grain_pressure, false},
    {"pressure_average", "real", "time", ">= 0", "0", "a time constant (time) >= 0 of the averaged pressure f_ID[19]",
     REAL(pressure_average), 0.0, kInf, false, true, nullptr, nullptr, false},
    {"fill", "region nx ny nz type T [inside mesh-ID] [outside mesh-ID ...]", "-", "1..8 points per cell per direction",
     "required (not after read_restart)", "'region-ID nx ny nz type T [inside mesh-ID] [outside mesh-ID ...]'", nullptr, 0, 0, false, false, nullptr, parse_fill, false},
    {"hydrostatic", "axis surface g", "length, acceleration", "g >= 0", "p = 0",
     "'axis surface g' (initial pressure rho g (surface - coordinate))",
     nullptr, 0, 0, false, false, nullptr, parse_hydrostatic, false},
    {"pmin", "real | none", "pressure", "", "none", "the lowest (cavitation) pressure, a number or 'none'",
     nullptr, 0, 0, false, false, nullptr, parse_pmin, false},
    {"couple", "group-ID", "-", "an existing group of grains", "off", "the group-ID of the DEM grains",
     nullptr, 0, 0, false, false, nullptr, parse_couple, false},
    {"drag", "law", "-", "ergun_wenyu, difelice, stokes", "ergun_wenyu",
     "a drag law ergun_wenyu, difelice or stokes", nullptr, 0, 0, false, false, nullptr, parse_drag, false},
    {"cell_check", "yes/no", "-", "", "yes", "'yes' or 'no'",
     nullptr, 0, 0, false, false, &Options::cell_check, nullptr, true},
    {"theta_min", "real", "-", "(0,1)", "0.3", "a lowest fluid fraction in (0,1)",
     REAL(theta_min), 0.0, 1.0, true, true, nullptr, nullptr, false},
    {"theta_smooth", "real", "length", ">= 0", "0", "a smoothing length >= 0 for the grains' volume fraction",
     REAL(theta_smooth), 0.0, kInf, false, true, nullptr, nullptr, false},
    {"front", "axis", "-", "x, y or z", "x", "an axis x, y or z",
     nullptr, 0, 0, false, false, nullptr, parse_front, false},
    {"height", "axis wall-axis wall-position", "length", "two different axes", "z x (grid's low x)",
     "'axis wall-axis wall-position'", nullptr, 0, 0, false, false, nullptr, parse_height, false},
    {"output", "N prefix points f ... [grid g ...]", "steps", "N >= 0", "off",
     "'N prefix points f1 ... [grid g1 ...]'", nullptr, 0, 0, false, false, nullptr, parse_output, false},
    {"probe", "point x y z | box xlo xhi ylo yhi zlo zhi", "length", "inside the grid; lo < hi", "none",
     "'point x y z' or 'box xlo xhi ylo yhi zlo zhi' (length)", nullptr, 0, 0, false, false, nullptr, parse_probe, false},
    {"probe_window", "real", "time", ">= 0", "0", "a time window (time) >= 0 of the probes' average",
     REAL(probe_window), 0.0, kInf, false, true, nullptr, nullptr, false},
    {"superficial_velocity", "axis U | axis v_name", "velocity", "axis periodic; U finite", "off",
     "an axis x, y or z and a superficial velocity (velocity), a number or v_name of an equal-style variable",
     nullptr, 0, 0, false, false, nullptr, parse_superficial_velocity, true},
    {"mesh_wall", "fix-ID kind [value] [side s] [loads yes|no] [reference_point x y z]", "-", "",
     "none; side auto; loads no; reference_point 0 0 0",
     "a fix ID and noslip | freeslip | partial f | sticky f | shear delta f",
     nullptr, 0, 0, false, false, nullptr, parse_mesh_wall, false},
};
#undef REAL

void parse_real(Options &o, const Keyword &k, const char *s) {
  double v;
  const bool ok = parse_double(s, v) && (k.open_lo ? v > k.lo : v >= k.lo) && (k.open_hi ? v < k.hi : v <= k.hi);
  if (!ok) bad_arg(k.name, k.help, s);
  o.*(k.real) = v;
}

}  // namespace

const std::vector<Keyword> &keywords() { return kTable; }

const Keyword *find_keyword(const char *name) {
  for (const Keyword &k : kTable)
    if (strcmp(k.name, name) == 0) return &k;
  return nullptr;
}

void Args::need(int n, const char *kw, const char *what) const {
  if (iarg + n >= narg) bad_arg(kw, what, nullptr);
}

void bad_arg(const char *keyword, const char *expected, const char *given) {
  throw Error(std::string("Fix mpm/fluid: keyword '") + keyword + "' expects " + expected + ", got " +
              (given ? std::string("'") + given + "'" : std::string("nothing")));
}

Options parse_options(int narg, char **arg, const ParseEnv &env) {
  Options o;
  bool given[3] = {false, false, false};  // cell, density, bulk
  std::vector<std::string> seen;          // keywords given
  Args a{narg, arg, 3};
  while (a.iarg < narg) {
    const char *kw = a.at(0);
    const Keyword *k = find_keyword(kw);
    if (!k)
      throw Error(std::string("Fix mpm/fluid: unknown keyword '") + kw +
                  "' (see docs/fix_mpm_fluid.md for the keywords)");
    // a keyword given again replaces its value (boundary and mesh_wall: one face or mesh each)
    if (std::find(seen.begin(), seen.end(), kw) != seen.end() && strcmp(kw, "boundary") != 0 &&
        strcmp(kw, "mesh_wall") != 0 && strcmp(kw, "probe") != 0)
      o.warnings.push_back(std::string("Fix mpm/fluid: keyword '") + kw + "' given more than once; the last value is used");
    seen.push_back(kw);
    if (k->real) {
      a.need(1, kw, k->help);
      parse_real(o, *k, a.at(1));
      if (k->real == &Options::cell_size) given[0] = true;
      if (k->real == &Options::rho0) given[1] = true;
      if (k->real == &Options::bulk) given[2] = true;
      a.iarg += 2;
    } else if (k->flag) {
      a.need(1, kw, k->help);
      if (!parse_yesno(a.at(1), o.*(k->flag))) bad_arg(kw, k->help, a.at(1));
      a.iarg += 2;
    } else {
      k->parse(o, a, env);
    }
  }
  finish_options(o, seen, given, env);
  return o;
}

int parse_reference_point(int narg, char **arg, int iarg, double ref[3]) {
  if (iarg >= narg || strcmp(arg[iarg], "reference_point") != 0) return iarg;
  for (int d = 0; d < 3; ++d) {
    const char *v = iarg + 1 + d < narg ? arg[iarg + 1 + d] : nullptr;
    if (!v || !parse_double(v, ref[d]))
      bad_arg("mesh_wall reference_point", "three coordinates x y z (length) of the torque's reference point", v);
  }
  return iarg + 4;
}

namespace {

// fix_modify of keyword k: its new value in o; returns the number of words used
int modify_value(Options &o, const Keyword &k, int narg, char **arg) {
  if (strcmp(arg[0], "gate") == 0) {
    if (narg < 2 || strcmp(arg[1], "off") != 0) bad_arg("fix_modify gate", "'off'", narg < 2 ? nullptr : arg[1]);
    o.gate.active = false;
    return 2;
  }
  if (strcmp(arg[0], "superficial_velocity") == 0) return modify_drive(o, narg, arg);
  if (strcmp(arg[0], "boundary") == 0) {
    if (narg < 3)
      bad_arg("fix_modify boundary", "a face and 'noslip', 'freeslip', 'partial f', 'shear delta' or 'inflow U'", nullptr);
    Args a{narg, arg, 0};  // arg[0] is the keyword, as in the fix command
    const Options before = o;
    parse_face(o, a);
    check_flow_change(before, o);
    return a.iarg;
  }
  if (narg < 2) bad_arg(arg[0], k.help, nullptr);
  if (k.flag) {
    if (!parse_yesno(arg[1], o.*(k.flag))) bad_arg(arg[0], k.help, arg[1]);
  } else {
    parse_real(o, k, arg[1]);
  }
  return 2;
}

}  // namespace

int modify_option(Options &o, int narg, char **arg) {
  const Keyword *k = find_keyword(arg[0]);
  if (!k || !k->modifiable) {
    std::string can;
    for (const Keyword &r : kTable)
      if (r.modifiable) can += std::string(can.empty() ? "" : ", ") + r.name;
    throw Error(std::string("Fix mpm/fluid: fix_modify ") + (k ? "cannot change keyword '" : "has no keyword '") +
                arg[0] + (k ? "' (set it in the fix command)" : "'") + "; it changes " + can);
  }
  Options before = o;
  const int used = modify_value(o, *k, narg, arg);
  try {
    check_inert(o, {arg[0]}, "fix_modify ");
  } catch (...) {
    o = before;
    throw;
  }
  return used;
}


}  // namespace mpm
