// The settings of fix mpm/fluid and the one table of its keywords.
//
// Every keyword of the fix command is one row of keywords(): name, type, unit, range, default and
// help (the help is what an error message says the keyword expects). The rows drive the parser,
// fix_modify, the end of the 'output' field lists (a word that is a keyword ends them) and the
// keyword table of docs/fix_mpm_fluid.md (a unit test checks the page lists exactly these rows).
// A numeric keyword is one row with its target member and bounds; words and lists have a parse
// function. Adding a numeric keyword: one row here plus its use.
#pragma once
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "mpm/args.h"
#include "mpm/drag_laws.h"
#include "mpm/fluid_laws.h"
#include "mpm/grid.h"
#include "mpm/shape_functions.h"

namespace mpm {

enum class BcKind { NoSlip, FreeSlip, Partial, Shear, Inflow, Outflow };
// Shear: wall stress mu v_t / delta of an unresolved wall layer delta (docs/theory/mesh_walls.md)
// Inflow: the fluid enters at the normal speed 'inflow' (> 0), no tangential velocity; points are
// created in layers inside the face (flow_faces.cpp). Outflow: p = 0, no velocity condition; points
// that leave through it are removed (docs/fix_mpm_fluid.md, "Flow in and out").
struct Face {
  BcKind kind = BcKind::NoSlip;
  double sticky = 1.0;
  double delta = 0.0;
  double inflow = 0.0;  // Inflow: normal speed into the grid (velocity)
  bool flow() const { return kind == BcKind::Inflow || kind == BcKind::Outflow; }
};
struct Gate {
  bool active = false;
  int dim = 0;
  double pos = 0.0;
  bool fluid_below = true;   // fluid held on the low-coordinate side
  double release_time = -1;  // simulation time of removal; < 0 = only by fix_modify
};
// keyword probe: the pressure at a point (lo) or the mean over the fluid nodes of a box (lo..hi)
struct Probe {
  bool box = false;
  double lo[3] = {0.0, 0.0, 0.0}, hi[3] = {0.0, 0.0, 0.0};
};
// keyword superficial_velocity: the fluid's mean volume flux along a periodic axis held at a target
// by a uniform driving pressure gradient (mpm/flow_drive.cpp)
struct FlowDrive {
  bool active = false;
  int axis = 2;
  double target = 0.0;   // superficial velocity (velocity); from the variable each fluid step if one is named
  std::string variable;  // an equal-style variable of the host (given as v_name), or ""
};
enum class Transfer { Apic, Pic, Flip };
// The coupling's forms (docs/theory): standard, the project's (the grains' pressure force is the
// gradient the fluid itself feels, its reaction goes through the points that displaced it, the
// drag's consistent form); yang2016, the dissertation's literal one (the least-squares fitted
// nodal gradient (8-27), the reaction spread to the nodes (8-26), the drag of (7-7) as written).
enum class Model { Standard, Yang2016 };
enum class GradP { Weak, Fit };  // set by the model

struct Options {
  // fluid and grid
  double cell_size = 0.0, rho0 = 1000.0, bulk = 2.2e9;  // copied into grid / eos
  GridSpec grid;
  bool grid_bounds_given = false;
  double gbounds[6] = {0, 0, 0, 0, 0, 0};
  ShapeKind shape = ShapeKind::QuadraticBSpline;
  Eos eos;
  double viscosity = 0.0;
  double pmin = -HUGE_VAL;          // cavitation pressure: no tension below it
  Transfer transfer = Transfer::Flip;  // the text's MUSL: FLIP velocity (8-40), grid velocity for x (8-41)
  double flip_alpha = 1.0;          // FLIP fraction of a FLIP/PIC blend
  bool musl = true;
  Model model = Model::Standard;    // keyword model; sets grad_p, reaction_points and drag_form
  // grad p at the grains (pressure eos): the gradient the fluid feels at the nodes, -(internal
  // force)/volume (at least half a cell), as the points see it (weak, standard), or the fitted
  // nodal gradients (fit, yang2016)
  GradP grad_p = GradP::Weak;
  // the grains' pressure reaction goes to the fluid through its points (standard: the kernel the
  // displaced fluid mass went through) or straight to the nodes (yang2016)
  bool reaction_points = true;
  Face face[6];
  Gate gate;
  double damping = 0.0;
  double cfl = 0.5;
  bool subcycle = false;
  int max_subcycle = 1000;
  int fluid_every = 1;              // the fluid advances every N-th time step, by N dt (keyword every)
  // every auto: N chosen at each fluid step from the stable step of the state then
  // (FluidSolver::choose_every); fluid_every holds the N of the current fluid step
  bool every_auto = false;
  double mass_threshold = 1e-5;
  bool sparse = true;                // fluid grid phases only on the blocks the points reach (pressure eos)
  // pressure model (keyword pressure): projection (default), the incompressible fluid of a pressure
  // Poisson solve (mpm/projection.h), or eos, the text's weakly compressible fluid
  bool projection = true;
  double pressure_tolerance = 1e-8;  // relative residual of the solve
  int pressure_max_iterations = 200;
  // projection: ghost-fluid free surface; with mesh walls p = 0 at the EMPTY nodes (the nodal fill
  // that places the ghost surface lacks the mass behind a triangle)
  bool surface_ghost = true;
  bool pressure_acceleration = false;  // pressure_output acceleration: points' p from the fluid's acceleration
  bool grain_pressure_acceleration = true;   // grain_pressure acceleration (couple only): grains feel its gradient
  double pressure_average = 0.0;     // time: time constant of the averaged nodal pressure f_ID[19] (0: none)
  double volume_correction = 0.0;    // 1/time: rate at which compressed points are pushed apart (0: off)
  // projection with the node surface (derived, no keyword): the rate at which the P2G velocity's
  // divergence is removed at the film's front, sqrt(9.81 m/s^2 / cell) (0: removed within each step)
  double front_rate = 0.0;
  // reports
  int front_axis = 0;
  int height_axis = 2, wall_axis = 0;
  double wall_pos = 0.0;
  bool wall_pos_given = false;
  // filling
  std::string fill_region;
  int fill_ppc[3] = {2, 2, 2};
  int fill_type = 1;
  std::string fill_inside;                // fill ... inside mesh-ID (mesh_fill.h)
  std::vector<std::string> fill_outside;  // fill ... outside mesh-ID, one per 'outside'
  bool hydrostatic = false;
  int hydro_axis = 2;
  double hydro_surface = 0.0, hydro_g = 9.81;
  int dimension = 3;                // of the host's simulation (viscous time-step limit)
  // two-way coupling with DEM grains (keyword couple)
  bool coupled = false;
  std::string couple_group;
  DragLaw drag_law = DragLaw::ErgunWenYu;
  DragForm drag_form = DragForm::Consistent;
  double theta_min = kDragThetaMin;
  double theta_smooth = 0.0;        // standard deviation of the smoothing of the solid fraction (0: none)
  bool cell_check = true;
  // pressure probes (keyword probe, one each) and the window of their time average (0: every fluid step)
  std::vector<Probe> probes;
  double probe_window = 0.0;
  FlowDrive drive;
  // output
  int out_every = 0;
  std::string out_prefix;
  std::vector<std::string> out_point_fields, out_grid_fields;
  // warnings of the parser (a keyword given twice), printed by the fix
  std::vector<std::string> warnings;

  // some face is an inflow or an outflow (boundary ... inflow U | outflow)
  bool flow_faces() const {
    for (const Face &f : face)
      if (f.flow()) return true;
    return false;
  }
  // the velocity along +d of grid face f's inflow (f = 2 d: +U, f = 2 d + 1: -U; 0 for other kinds)
  double face_velocity(int f) const {
    if (face[f].kind != BcKind::Inflow) return 0.0;
    return (f % 2 == 0 ? 1.0 : -1.0) * face[f].inflow;
  }
};

// What the parser needs to know of the simulation around it (LIGGGHTS' box, groups, types).
struct ParseEnv {
  int ntypes = 1;
  double boxlo[3] = {0, 0, 0}, boxhi[3] = {1, 1, 1};
  bool periodic[3] = {false, false, false};
  int dimension = 3;
  std::function<bool(const char *)> group_exists;
  // keyword mesh_wall (LIGGGHTS meshes, parsed by the adapter): returns the index after its arguments
  std::function<int(int narg, char **arg, int iarg)> mesh_wall;
};

// The arguments being parsed and the position in them.
struct Args {
  int narg;
  char **arg;
  int iarg;
  // throws the "expects <what>, got nothing" error if fewer than n values follow the keyword
  void need(int n, const char *kw, const char *what) const;
  const char *at(int k) const { return arg[iarg + k]; }
};

struct Keyword {
  const char *name;
  const char *type;   // real, integer, yes/no, or the argument pattern
  const char *unit;   // of the value ("-": none)
  const char *range;
  const char *deflt;
  const char *help;   // what the keyword expects (error messages)
  double Options::*real;  // numeric keywords: target and bounds (open: bound excluded)
  double lo, hi;
  bool open_lo, open_hi;
  bool Options::*flag;    // yes/no keywords
  void (*parse)(Options &, Args &, const ParseEnv &);  // other keywords: from the keyword on
  bool modifiable;        // accepted by fix_modify
};

const std::vector<Keyword> &keywords();
const Keyword *find_keyword(const char *name);

// Point and grid fields of keyword output.
extern const char *const kPointFields[10];
extern const char *const kGridFields[2];

// "Fix mpm/fluid: keyword 'kw' expects <expected>, got 'given'" (given null: "got nothing").
[[noreturn]] void bad_arg(const char *keyword, const char *expected, const char *given);

// fix ID group mpm/fluid keyword value ...: arg[3..narg). Throws mpm::Error.
Options parse_options(int narg, char **arg, const ParseEnv &env);
// mesh_wall's optional 'reference_point x y z' at arg[iarg] (the torque's reference point):
// returns the index after it, or iarg if arg[iarg] is not 'reference_point'. Throws mpm::Error
// naming the keyword, what it expects and the value given.
int parse_reference_point(int narg, char **arg, int iarg, double ref[3]);
// fix_modify keyword value ...: returns the number of words used. Throws mpm::Error for a word
// fix_modify cannot change (naming it and the keywords it can), a bad value, or a value that another
// choice makes inert (o unchanged then).
int modify_option(Options &o, int narg, char **arg);

}  // namespace mpm
