/* fix mpm/fluid: see fix_mpm_fluid.h, docs/fix_mpm_fluid.md and docs/design.md.
   The time step follows chapter 8 of the dissertation, phase by phase:
   particles_to_grid (8-10), (8-19), (8-24); update_grid (8-35), (8-36) with
   boundary conditions; grid_to_particles (8-37) to (8-41); MUSL remap and
   stress update (7-21) to (7-24). */

#include "fix_mpm_fluid.h"

#include <Eigen/Dense>

#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

#include "atom.h"
#include "atom_vec.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "force.h"
#include "group.h"
#include "memory.h"
#include "modify.h"
#include "fix_property_atom.h"
#include "neighbor.h"
#include "region.h"
#include "update.h"

#include "mpm/hdf5_series.h"

using namespace LAMMPS_NS;
using namespace FixConst;

namespace {

const char *kFaceNames[6] = {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"};

int axis_of(const char *s) {
  if (strcmp(s, "x") == 0) return 0;
  if (strcmp(s, "y") == 0) return 1;
  if (strcmp(s, "z") == 0) return 2;
  return -1;
}

bool parse_double(const char *s, double &v) {
  char *end = nullptr;
  v = strtod(s, &end);
  return end != s && *end == '\0' && std::isfinite(v);
}

bool parse_int(const char *s, int &v) {
  char *end = nullptr;
  long l = strtol(s, &end, 10);
  v = static_cast<int>(l);
  return end != s && *end == '\0';
}

bool parse_yesno(const char *s, bool &v) {
  if (strcmp(s, "yes") == 0) { v = true; return true; }
  if (strcmp(s, "no") == 0) { v = false; return true; }
  return false;
}

const char *kPointFields[] = {"v", "p", "rho", "vol", "tau", "theta", "id", "type", "affine", "mass"};
const char *kGridFields[] = {"mass", "v"};

}  // namespace

/* ---------------------------------------------------------------------- */

FixMpmFluid::FixMpmFluid(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg) {
  if (domain->triclinic) error->all(FLERR, "Fix mpm/fluid requires an orthogonal simulation box");
  if (!atom->rmass_flag || !atom->radius_flag)
    error->all(FLERR, "Fix mpm/fluid requires atom_style sphere (per-atom mass and radius)");

  parse_args(narg, arg);

  restart_global = 1;
  restart_peratom = 1;
  // no create_attribute: LIGGGHTS would call set_arrays() for every atom at
  // the first setup and wipe the points' state; new rows are zeroed in grow_arrays
  time_integrate = 1;  // the fix moves its material points itself
  vector_flag = 1;
  size_vector = 15;
  global_freq = 1;
  extvector = 0;
  peratom_flag = 1;
  size_peratom_cols = NCOL;
  peratom_freq = 1;
  nevery = out_every > 0 ? out_every : 1;

  grow_arrays(atom->nmax);
  atom->add_callback(0);
  atom->add_callback(1);
  array_atom = pdata;
}

FixMpmFluid::~FixMpmFluid() {
  atom->delete_callback(id, 0);
  atom->delete_callback(id, 1);
  memory->destroy(pdata);
}

int FixMpmFluid::setmask() {
  int mask = PRE_FINAL_INTEGRATE;
  if (out_every > 0) mask |= END_OF_STEP;
  return mask;
}

// error->one aborts without flushing stdio, so a message would be lost when
// the screen is a pipe or a file: print and flush first, then abort.
void FixMpmFluid::fail_one(const std::string &msg) {
  if (screen) {
    fprintf(screen, "ERROR on proc %d: %s\n", comm->me, msg.c_str());
    fflush(screen);
  }
  if (logfile) {
    fprintf(logfile, "ERROR on proc %d: %s\n", comm->me, msg.c_str());
    fflush(logfile);
  }
  MPI_Abort(world, 1);
  std::abort();
}

void FixMpmFluid::bad_arg(const char *keyword, const char *expected, const char *given) {
  std::string msg = std::string("Fix mpm/fluid: keyword '") + keyword + "' expects " + expected +
                    ", got " + (given ? std::string("'") + given + "'" : std::string("nothing"));
  error->all(FLERR, msg.c_str());
  std::abort();
}

/* ----------------------------------------------------------------------
   numeric keywords, each declared once: target, valid range, what to say
------------------------------------------------------------------------- */

const FixMpmFluid::ScalarKeyword *FixMpmFluid::find_scalar(const char *kw) {
  // lo/hi: bounds; open_lo/open_hi: bound excluded
  static const ScalarKeyword table[] = {
      {"cell", &FixMpmFluid::cell_size, 0.0, HUGE_VAL, true, true, "a positive cell size (length)"},
      {"density", &FixMpmFluid::rho0_arg, 0.0, HUGE_VAL, true, true, "a positive reference density"},
      {"bulk", &FixMpmFluid::bulk_arg, 0.0, HUGE_VAL, true, true, "a positive bulk modulus (pressure)"},
      {"viscosity", &FixMpmFluid::viscosity, 0.0, HUGE_VAL, false, true, "a non-negative dynamic viscosity"},
      {"damping", &FixMpmFluid::damping, 0.0, HUGE_VAL, false, true, "a damping rate (1/time) >= 0"},
      {"cfl", &FixMpmFluid::cfl, 0.0, 1.0, true, false, "a CFL number in (0,1]"},
      {"mass_threshold", &FixMpmFluid::mass_threshold, 0.0, 1.0, false, true,
       "a fraction of the point mass in [0,1)"},
      {"theta_min", &FixMpmFluid::theta_min, 0.0, 1.0, true, true, "a lowest fluid fraction in (0,1)"},
      {"theta_smooth", &FixMpmFluid::theta_smooth, 0.0, HUGE_VAL, false, true,
       "a smoothing length >= 0 for the grains' volume fraction"},
  };
  for (const ScalarKeyword &k : table)
    if (strcmp(k.name, kw) == 0) return &k;
  return nullptr;
}

// yes/no keywords
bool FixMpmFluid::*FixMpmFluid::find_flag(const char *kw) {
  static const struct { const char *name; bool FixMpmFluid::*flag; } table[] = {
      {"antilock", &FixMpmFluid::antilock},
      {"subcycle", &FixMpmFluid::subcycle},
      {"cell_check", &FixMpmFluid::cell_check},
      {"wall_traction", &FixMpmFluid::wall_traction},
      {"theta_transport", &FixMpmFluid::theta_transport},
  };
  for (const auto &k : table)
    if (strcmp(k.name, kw) == 0) return k.flag;
  return nullptr;
}

void FixMpmFluid::parse_scalar(const ScalarKeyword &k, const char *s) {
  double v;
  const bool ok = parse_double(s, v) && (k.open_lo ? v > k.lo : v >= k.lo) && (k.open_hi ? v < k.hi : v <= k.hi);
  if (!ok) bad_arg(k.name, k.expected, s);
  this->*(k.target) = v;
  gspec.dx = cell_size;
  eos.rho0 = rho0_arg;
  eos.K = bulk_arg;
}

/* ----------------------------------------------------------------------
   fix ID group mpm/fluid keyword value ...
------------------------------------------------------------------------- */

void FixMpmFluid::parse_args(int narg, char **arg) {
  bool have_cell = false, have_density = false, have_bulk = false;
  for (int f = 0; f < 6; ++f) face[f] = Face();

  auto need = [&](int iarg, int n, const char *kw, const char *what) {
    if (iarg + n >= narg) bad_arg(kw, what, nullptr);
  };
  int iarg = 3;
  // a keyword with one of two words: flag = (word == first)
  auto choice = [&](const char *kw, const char *first, const char *second, bool &flag) {
    const std::string expected = std::string("'") + first + "' or '" + second + "'";
    need(iarg, 1, kw, expected.c_str());
    if (strcmp(arg[iarg + 1], first) == 0)
      flag = true;
    else if (strcmp(arg[iarg + 1], second) == 0)
      flag = false;
    else
      bad_arg(kw, expected.c_str(), arg[iarg + 1]);
    iarg += 2;
  };

  while (iarg < narg) {
    const char *kw = arg[iarg];
    if (const ScalarKeyword *sk = find_scalar(kw)) {
      need(iarg, 1, kw, sk->expected);
      parse_scalar(*sk, arg[iarg + 1]);
      if (strcmp(kw, "cell") == 0) have_cell = true;
      if (strcmp(kw, "density") == 0) have_density = true;
      if (strcmp(kw, "bulk") == 0) have_bulk = true;
      iarg += 2;
    } else if (bool FixMpmFluid::*flag = find_flag(kw)) {
      need(iarg, 1, kw, "'yes' or 'no'");
      if (!parse_yesno(arg[iarg + 1], this->*flag)) bad_arg(kw, "'yes' or 'no'", arg[iarg + 1]);
      iarg += 2;
    } else if (strcmp(kw, "grid") == 0) {
      need(iarg, 6, kw, "six bounds xlo xhi ylo yhi zlo zhi");
      for (int k = 0; k < 6; ++k)
        if (!parse_double(arg[iarg + 1 + k], gbounds[k])) bad_arg(kw, "a number", arg[iarg + 1 + k]);
      for (int d = 0; d < 3; ++d)
        if (gbounds[2 * d + 1] <= gbounds[2 * d]) bad_arg(kw, "hi > lo in every dimension", arg[iarg + 2 + 2 * d]);
      grid_bounds_given = true;
      iarg += 7;
    } else if (strcmp(kw, "eos") == 0) {
      need(iarg, 1, kw, "'linear' or 'tait gamma'");
      if (strcmp(arg[iarg + 1], "linear") == 0) {
        eos.kind = mpm::EosKind::Linear;
        iarg += 2;
      } else if (strcmp(arg[iarg + 1], "tait") == 0) {
        need(iarg, 2, kw, "'tait' followed by the exponent gamma");
        if (!parse_double(arg[iarg + 2], eos.gamma) || eos.gamma < 1.0)
          bad_arg("eos tait", "an exponent gamma >= 1", arg[iarg + 2]);
        eos.kind = mpm::EosKind::Tait;
        iarg += 3;
      } else
        bad_arg(kw, "'linear' or 'tait'", arg[iarg + 1]);
    } else if (strcmp(kw, "shape") == 0) {
      need(iarg, 1, kw, "'linear' or 'bspline2'");
      if (strcmp(arg[iarg + 1], "linear") == 0)
        shape = mpm::ShapeKind::Linear;
      else if (strcmp(arg[iarg + 1], "bspline2") == 0)
        shape = mpm::ShapeKind::QuadraticBSpline;
      else
        bad_arg(kw, "'linear' or 'bspline2'", arg[iarg + 1]);
      iarg += 2;
    } else if (strcmp(kw, "transfer") == 0) {
      need(iarg, 1, kw, "'apic', 'pic' or 'flip alpha'");
      if (strcmp(arg[iarg + 1], "apic") == 0) {
        transfer = TR_APIC;
        iarg += 2;
      } else if (strcmp(arg[iarg + 1], "pic") == 0) {
        transfer = TR_PIC;
        iarg += 2;
      } else if (strcmp(arg[iarg + 1], "flip") == 0) {
        // optional FLIP fraction; a following word that is not a number is the next keyword
        transfer = TR_FLIP;
        flip_alpha = 1.0;
        iarg += 2;
        double a;
        if (iarg < narg && parse_double(arg[iarg], a)) {
          if (a < 0.0 || a > 1.0) bad_arg("transfer flip", "a FLIP fraction in [0,1]", arg[iarg]);
          flip_alpha = a;
          ++iarg;
        }
      } else
        bad_arg(kw, "'apic', 'pic' or 'flip'", arg[iarg + 1]);
    } else if (strcmp(kw, "update") == 0) {
      choice(kw, "musl", "usl", musl);
    } else if (strcmp(kw, "boundary") == 0) {
      need(iarg, 2, kw, "a face (xlo xhi ylo yhi zlo zhi all) and 'noslip', 'freeslip', 'partial f' or 'shear delta'");
      parse_face(arg[iarg + 1], arg[iarg + 2], narg, arg, iarg);
    } else if (strcmp(kw, "gate") == 0) {
      need(iarg, 4, kw, "'dim pos lower|upper release_time'");
      gate.dim = axis_of(arg[iarg + 1]);
      if (gate.dim < 0) bad_arg(kw, "an axis x, y or z", arg[iarg + 1]);
      if (!parse_double(arg[iarg + 2], gate.pos)) bad_arg(kw, "a gate position", arg[iarg + 2]);
      if (strcmp(arg[iarg + 3], "lower") == 0)
        gate.fluid_below = true;
      else if (strcmp(arg[iarg + 3], "upper") == 0)
        gate.fluid_below = false;
      else
        bad_arg(kw, "'lower' or 'upper' (side of the gate that holds the fluid)", arg[iarg + 3]);
      if (strcmp(arg[iarg + 4], "never") == 0)
        gate.release_time = -1.0;
      else if (!parse_double(arg[iarg + 4], gate.release_time) || gate.release_time < 0.0)
        bad_arg(kw, "a release time >= 0 or 'never'", arg[iarg + 4]);
      gate.active = true;
      iarg += 5;
    } else if (strcmp(kw, "couple") == 0) {
      need(iarg, 1, kw, "the group-ID of the DEM grains");
      couple_group = arg[iarg + 1];
      if (group->find(arg[iarg + 1]) < 0) bad_arg(kw, "an existing group-ID of the DEM grains", arg[iarg + 1]);
      coupled = true;
      iarg += 2;
    } else if (strcmp(kw, "drag") == 0) {
      need(iarg, 1, kw, "a drag law ergun_wenyu, difelice or stokes");
      if (!mpm::parse_drag_law(arg[iarg + 1], drag_law))
        bad_arg(kw, "a drag law ergun_wenyu, difelice or stokes", arg[iarg + 1]);
      iarg += 2;
      if (iarg < narg && mpm::parse_drag_form(arg[iarg], drag_form)) ++iarg;
    } else if (strcmp(kw, "grad_p") == 0) {
      choice(kw, "fit", "nodal", grad_p_fit);
    } else if (strcmp(kw, "pmin") == 0) {
      need(iarg, 1, kw, "the lowest (cavitation) pressure, a number or 'none'");
      if (strcmp(arg[iarg + 1], "none") == 0)
        pmin = -HUGE_VAL;
      else if (!parse_double(arg[iarg + 1], pmin))
        bad_arg(kw, "the lowest (cavitation) pressure, a number or 'none'", arg[iarg + 1]);
      iarg += 2;
    } else if (strcmp(kw, "fill") == 0) {
      need(iarg, 6, kw, "'region-ID nx ny nz type T'");
      fill_region = arg[iarg + 1];
      for (int d = 0; d < 3; ++d)
        if (!parse_int(arg[iarg + 2 + d], fill_ppc[d]) || fill_ppc[d] < 1 || fill_ppc[d] > 8)
          bad_arg(kw, "points per cell per direction, an integer 1..8", arg[iarg + 2 + d]);
      if (strcmp(arg[iarg + 5], "type") != 0) bad_arg(kw, "'type T' after the points per cell", arg[iarg + 5]);
      if (!parse_int(arg[iarg + 6], fill_type) || fill_type < 1 || fill_type > atom->ntypes)
        bad_arg("fill type", "an existing atom type", arg[iarg + 6]);
      iarg += 7;
    } else if (strcmp(kw, "hydrostatic") == 0) {
      need(iarg, 3, kw, "'axis surface g' (initial pressure rho g (surface - coordinate))");
      hydro_axis = axis_of(arg[iarg + 1]);
      if (hydro_axis < 0) bad_arg(kw, "an axis x, y or z", arg[iarg + 1]);
      if (!parse_double(arg[iarg + 2], hydro_surface)) bad_arg(kw, "the surface coordinate", arg[iarg + 2]);
      if (!parse_double(arg[iarg + 3], hydro_g) || hydro_g < 0.0) bad_arg(kw, "g >= 0", arg[iarg + 3]);
      hydrostatic = true;
      iarg += 4;
    } else if (strcmp(kw, "front") == 0) {
      need(iarg, 1, kw, "an axis x, y or z");
      front_axis = axis_of(arg[iarg + 1]);
      if (front_axis < 0) bad_arg(kw, "an axis x, y or z", arg[iarg + 1]);
      iarg += 2;
    } else if (strcmp(kw, "height") == 0) {
      need(iarg, 3, kw, "'axis wall-axis wall-position'");
      height_axis = axis_of(arg[iarg + 1]);
      wall_axis = axis_of(arg[iarg + 2]);
      if (height_axis < 0 || wall_axis < 0 || height_axis == wall_axis)
        bad_arg(kw, "two different axes x, y or z", arg[iarg + 1]);
      if (!parse_double(arg[iarg + 3], wall_pos)) bad_arg(kw, "a wall position", arg[iarg + 3]);
      wall_pos_given = true;
      iarg += 4;
    } else if (strcmp(kw, "every") == 0) {
      need(iarg, 1, kw, "an integer N >= 1 (the fluid advances every N-th time step)");
      if (!parse_int(arg[iarg + 1], fluid_every) || fluid_every < 1)
        bad_arg(kw, "an integer N >= 1 (the fluid advances every N-th time step)", arg[iarg + 1]);
      iarg += 2;
    } else if (strcmp(kw, "output") == 0) {
      need(iarg, 3, kw, "'N prefix points f1 ... [grid g1 ...]'");
      if (!parse_int(arg[iarg + 1], out_every) || out_every < 0)
        bad_arg(kw, "an output interval N >= 0 (steps; 0 = no output)", arg[iarg + 1]);
      out_prefix = arg[iarg + 2];
      iarg += 3;
      if (strcmp(arg[iarg], "points") != 0) bad_arg(kw, "'points' followed by field names", arg[iarg]);
      ++iarg;
      std::vector<std::string> *list = &out_point_fields;
      while (iarg < narg) {
        if (strcmp(arg[iarg], "grid") == 0 && list == &out_point_fields) {
          // 'grid' starts the grid-field list only if a grid field follows;
          // otherwise it is the fix's own 'grid' keyword
          bool gfield = false;
          if (iarg + 1 < narg)
            for (const char *f : kGridFields) gfield = gfield || strcmp(arg[iarg + 1], f) == 0;
          if (!gfield) break;
          list = &out_grid_fields;
          ++iarg;
          continue;
        }
        bool ok = false;
        if (list == &out_point_fields) {
          for (const char *f : kPointFields) ok = ok || strcmp(arg[iarg], f) == 0;
        } else {
          for (const char *f : kGridFields) ok = ok || strcmp(arg[iarg], f) == 0;
        }
        if (!ok) {
          // The first word that is no field name ends the list only if it is a keyword.
          static const char *keywords[] = {"cell", "grid", "density", "bulk", "viscosity", "eos", "shape",
                                           "transfer", "update", "antilock", "boundary", "gate", "damping",
                                           "cfl", "subcycle", "every", "mass_threshold", "fill", "hydrostatic", "pmin",
                                           "couple", "drag", "cell_check", "theta_min", "theta_smooth", "wall_traction", "theta_transport", "grad_p",
                                           "front", "height", "output", "mesh_wall"};
          bool is_kw = false;
          for (const char *k : keywords) is_kw = is_kw || strcmp(arg[iarg], k) == 0;
          if (is_kw) break;
          bad_arg(list == &out_point_fields ? "output points" : "output grid",
                  list == &out_point_fields ? "point fields v p rho vol tau theta id type affine mass"
                                            : "grid fields mass v",
                  arg[iarg]);
        }
        list->push_back(arg[iarg]);
        ++iarg;
      }
    } else if (strcmp(kw, "mesh_wall") == 0) {
      need(iarg, 2, kw, "a fix ID and noslip | freeslip | partial f | sticky f | shear delta f");
      mpm::MeshWallSpec ms;
      ms.fix_id = arg[iarg + 1];
      ms.side = mpm::SIDE_AUTO;
      const char *k = arg[iarg + 2];
      iarg += 3;
      if (strcmp(k, "noslip") == 0) ms.kind = mpm::WALL_NOSLIP;
      else if (strcmp(k, "freeslip") == 0) ms.kind = mpm::WALL_FREESLIP;
      else if (strcmp(k, "partial") == 0 || strcmp(k, "sticky") == 0) {
        const bool sticky_kind = strcmp(k, "sticky") == 0;
        const char *kwname = sticky_kind ? "mesh_wall sticky" : "mesh_wall partial";
        need(iarg - 1, 1, kwname, "a sticky fraction");
        ms.kind = sticky_kind ? mpm::WALL_STICKY : mpm::WALL_PARTIAL;
        if (!parse_double(arg[iarg], ms.sticky)) bad_arg(kwname, "a sticky fraction in [0,1]", arg[iarg]);
        ++iarg;
      } else if (strcmp(k, "shear") == 0) {
        // wall shear stress mu (f w_t - v_t) / delta: an unresolved viscous layer of thickness delta
        need(iarg - 1, 2, "mesh_wall shear", "a wall layer thickness delta (length) and a fraction f in [0,1]");
        ms.kind = mpm::WALL_SHEAR;
        if (!parse_double(arg[iarg], ms.delta) || !(ms.delta > 0.0))
          bad_arg("mesh_wall shear", "a positive wall layer thickness delta (length)", arg[iarg]);
        if (!parse_double(arg[iarg + 1], ms.sticky) || ms.sticky < 0.0 || ms.sticky > 1.0)
          bad_arg("mesh_wall shear", "a fraction f in [0,1] of the wall's tangential velocity", arg[iarg + 1]);
        iarg += 2;
      } else bad_arg("mesh_wall", "noslip, freeslip, partial f, sticky f or shear delta f", k);
      if (iarg + 1 < narg && strcmp(arg[iarg], "side") == 0) {
        const char *sd = arg[iarg + 1];
        if (strcmp(sd, "auto") == 0) ms.side = mpm::SIDE_AUTO;
        else if (strcmp(sd, "normal") == 0) ms.side = mpm::SIDE_NORMAL;
        else if (strcmp(sd, "opposite") == 0) ms.side = mpm::SIDE_OPPOSITE;
        else if (strcmp(sd, "both") == 0) ms.side = mpm::SIDE_BOTH;
        else bad_arg("mesh_wall side", "auto, normal, opposite or both", sd);
        iarg += 2;
      }
      mesh_specs.push_back(ms);
    } else {
      std::string msg = std::string("Fix mpm/fluid: unknown keyword '") + kw +
                        "' (see docs/fix_mpm_fluid.md for the keywords)";
      error->all(FLERR, msg.c_str());
    }
  }
  if (!have_cell) error->all(FLERR, "Fix mpm/fluid: keyword 'cell' (cell size) is required");
  if (!have_density) error->all(FLERR, "Fix mpm/fluid: keyword 'density' (reference density) is required");
  if (!have_bulk) error->all(FLERR, "Fix mpm/fluid: keyword 'bulk' (bulk modulus) is required");
  if (coupled && !(viscosity > 0.0))
    error->all(FLERR, "Fix mpm/fluid: keyword 'couple' needs keyword 'viscosity' > 0 (the drag laws scale with it)");

  // Grid: cubic cells fitted exactly into the bounds.
  double b[6];
  for (int d = 0; d < 3; ++d) {
    b[2 * d] = grid_bounds_given ? gbounds[2 * d] : domain->boxlo[d];
    b[2 * d + 1] = grid_bounds_given ? gbounds[2 * d + 1] : domain->boxhi[d];
    const double n = (b[2 * d + 1] - b[2 * d]) / gspec.dx;
    const long nr = std::lround(n);
    if (nr < 1 || std::fabs(n - nr) > 1e-6 * std::max(1.0, n)) {
      std::ostringstream os;
      os << "Fix mpm/fluid: keyword 'cell' expects a cell size that divides the grid extent in "
         << "xyz"[d] << " (" << b[2 * d + 1] - b[2 * d] << "), got " << gspec.dx << " (" << n << " cells)";
      error->all(FLERR, os.str().c_str());
    }
    gspec.origin[d] = b[2 * d];
    gspec.ncell[d] = static_cast<int>(nr);
    gspec.periodic[d] = domain->periodicity[d] != 0;
    if (gspec.periodic[d] && (std::fabs(b[2 * d] - domain->boxlo[d]) > 1e-9 * gspec.dx ||
                              std::fabs(b[2 * d + 1] - domain->boxhi[d]) > 1e-9 * gspec.dx))
      error->all(FLERR, "Fix mpm/fluid: keyword 'grid' must span the whole box in a periodic dimension");
    if (!gspec.periodic[d] && (b[2 * d] < domain->boxlo[d] - 1e-9 * gspec.dx ||
                               b[2 * d + 1] > domain->boxhi[d] + 1e-9 * gspec.dx))
      error->all(FLERR, "Fix mpm/fluid: keyword 'grid' bounds must lie inside the simulation box");
  }
  gspec.pad = shape == mpm::ShapeKind::QuadraticBSpline ? 1 : 0;
  if (!wall_pos_given) wall_pos = gspec.origin[wall_axis];
  if (gate.active && !gspec.periodic[gate.dim] &&
      (gate.pos <= gspec.origin[gate.dim] || gate.pos >= gspec.upper(gate.dim)))
    error->all(FLERR, "Fix mpm/fluid: keyword 'gate' expects a position inside the grid");
}

void FixMpmFluid::parse_face(const char *name, const char *kind, int narg, char **arg, int &iarg) {
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
    fc.kind = BC_NOSLIP;
    fc.sticky = 1.0;
  } else if (strcmp(kind, "freeslip") == 0) {
    fc.kind = BC_FREESLIP;
    fc.sticky = 0.0;
  } else if (strcmp(kind, "partial") == 0) {
    if (iarg + 3 >= narg) bad_arg("boundary partial", "a sticky fraction in [0,1]", nullptr);
    if (!parse_double(arg[iarg + 3], fc.sticky) || fc.sticky < 0.0 || fc.sticky > 1.0)
      bad_arg("boundary partial", "a sticky fraction in [0,1]", arg[iarg + 3]);
    fc.kind = BC_PARTIAL;
    used = 4;
  } else if (strcmp(kind, "shear") == 0) {
    if (iarg + 3 >= narg) bad_arg("boundary shear", "a positive wall layer thickness delta (length)", nullptr);
    if (!parse_double(arg[iarg + 3], fc.delta) || !(fc.delta > 0.0))
      bad_arg("boundary shear", "a positive wall layer thickness delta (length)", arg[iarg + 3]);
    fc.kind = BC_SHEAR;
    fc.sticky = 0.0;
    used = 4;
  } else
    bad_arg("boundary", "'noslip', 'freeslip', 'partial f' or 'shear delta'", kind);
  for (int f = f0; f <= f1; ++f) face[f] = fc;
  iarg += used;
}

/* ---------------------------------------------------------------------- */

bool FixMpmFluid::is_point(int i) const { return (atom->mask[i] & groupbit) != 0; }

double FixMpmFluid::sim_time() const {
  return update->atime + (update->ntimestep - update->atimestep) * update->dt;
}

void FixMpmFluid::post_create() {
  // After a read_restart the points exist already (recent_restart is set
  // when our global state came from the restart file).
  if (!recent_restart && !fill_region.empty()) fill_points();
  // The fluid force on each grain as the per-atom vector 'dragforce', the
  // property/atom convention of LIGGGHTS/CFDEM (reused if the input made it).
  if (coupled) {
    const char *args[] = {"dragforce", "all", "property/atom", "dragforce", "vector", "yes", "no", "no",
                          "0", "0", "0"};
    fix_dragforce = static_cast<FixPropertyAtom *>(
        modify->find_fix_property("dragforce", "property/atom", "vector", 3, 0, style, false));
    if (!fix_dragforce)
      fix_dragforce = modify->add_fix_property_atom(11, const_cast<char **>(args), style);
  }
}

void FixMpmFluid::fill_points() {
  // checked here, not at parse time: after read_restart no region is needed
  const int iregion = domain->find_region(fill_region.c_str());
  if (iregion < 0) bad_arg("fill", "an existing region ID", fill_region.c_str());
  Region *region = domain->regions[iregion];
  const double dx = gspec.dx;
  double vol = dx * dx * dx;
  for (int d = 0; d < 3; ++d) {
    spacing[d] = dx / fill_ppc[d];
    vol /= fill_ppc[d];
  }
  const int nlocal_before = atom->nlocal;
  int lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::max(0, static_cast<int>(std::floor((domain->sublo[d] - gspec.origin[d]) / dx)) - 1);
    hi[d] = std::min(gspec.ncell[d] - 1,
                     static_cast<int>(std::floor((domain->subhi[d] - gspec.origin[d]) / dx)) + 1);
  }
  double x[3];
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i)
        for (int c = 0; c < fill_ppc[2]; ++c)
          for (int b = 0; b < fill_ppc[1]; ++b)
            for (int a = 0; a < fill_ppc[0]; ++a) {
              const int cell[3] = {i, j, k}, sub[3] = {a, b, c};
              for (int d = 0; d < 3; ++d)
                x[d] = gspec.origin[d] + cell[d] * dx + (sub[d] + 0.5) * spacing[d];
              if (!region->match(x[0], x[1], x[2])) continue;
              bool mine = true;
              for (int d = 0; d < 3; ++d)
                mine = mine && x[d] >= domain->sublo[d] && x[d] < domain->subhi[d];
              if (!mine) continue;
              atom->avec->create_atom(fill_type, x);
              const int n = atom->nlocal - 1;
              for (int m = 0; m < modify->nfix; ++m) {
                Fix *f = modify->fix[m];
                if (f && f->create_attribute && f != this) {
                  f->pre_set_arrays();
                  f->set_arrays(n);
                }
              }
              double rho = eos.rho0, p = 0.0;
              if (hydrostatic) {
                p = std::max(0.0, eos.rho0 * hydro_g * (hydro_surface - x[hydro_axis]));
                rho = eos.density(p);
              }
              atom->mask[n] |= groupbit;
              atom->v[n][0] = atom->v[n][1] = atom->v[n][2] = 0.0;
              // The point keeps the reference mass; a pre-compressed point is smaller.
              atom->rmass[n] = eos.rho0 * vol;
              atom->radius[n] = 0.5 * std::min(spacing[0], std::min(spacing[1], spacing[2]));
              if (atom->density_flag && atom->density) atom->density[n] = eos.rho0;
              double *s = pdata[n];
              std::fill(s, s + NCOL, 0.0);
              s[C_VOL] = atom->rmass[n] / rho;
              s[C_RHO] = rho;
              s[C_P] = p;
              s[C_THETA] = 1.0;
              s[C_FLAG] = 1.0;
            }

  bigint nnew = atom->nlocal - nlocal_before, nall = 0;
  MPI_Allreduce(&nnew, &nall, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  if (nall == 0) error->all(FLERR, "Fix mpm/fluid: keyword 'fill' created no material points (region empty?)");
  bigint nlocal = atom->nlocal;
  MPI_Allreduce(&nlocal, &atom->natoms, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  atom->tag_extend();
  if (atom->map_style) {
    atom->nghost = 0;
    atom->map_init();
    atom->map_set();
  }
  point_mass_ref = eos.rho0 * vol;
  filled = true;
  if (comm->me == 0) {
    std::ostringstream os;
    os << "fix mpm/fluid: created " << nall << " material points (" << fill_ppc[0] << "x" << fill_ppc[1]
       << "x" << fill_ppc[2] << " per cell of " << gspec.dx << "), grid " << gspec.ncell[0] << "x"
       << gspec.ncell[1] << "x" << gspec.ncell[2] << " cells\n";
    if (screen) fputs(os.str().c_str(), screen);
    if (logfile) fputs(os.str().c_str(), logfile);
  }
}

/* ---------------------------------------------------------------------- */

void FixMpmFluid::init() {
  if (!filled) error->all(FLERR, "Fix mpm/fluid: no material points; use keyword 'fill region-ID nx ny nz type T'");
  // Material points must not be integrated twice.
  for (int m = 0; m < modify->nfix; ++m) {
    Fix *f = modify->fix[m];
    if (f == this || !f->time_integrate) continue;
    int clash = 0;
    for (int i = 0; i < atom->nlocal; ++i)
      if (is_point(i) && (atom->mask[i] & f->groupbit)) clash = 1;
    int any = 0;
    MPI_Allreduce(&clash, &any, 1, MPI_INT, MPI_MAX, world);
    if (any) {
      std::string msg = std::string("Fix mpm/fluid: fix ") + f->id + " (" + f->style +
                        ") also integrates material points; restrict it to the grain group";
      error->all(FLERR, msg.c_str());
    }
  }
  int bad = 0;
  for (int i = 0; i < atom->nlocal; ++i)
    if (is_point(i) && pdata[i][C_FLAG] != 1.0) bad = 1;
  int anybad = 0;
  MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_MAX, world);
  if (anybad)
    error->all(FLERR, "Fix mpm/fluid: the fix group contains atoms that are not material points of this fix "
                      "(use a group of the fill type only)");
  if (theta_transport && !coupled)
    error->all(FLERR, "Fix mpm/fluid: keyword 'theta_transport yes' needs keyword 'couple' (there is no "
                      "fluid fraction to transport without grains)");
  if (theta_transport && !musl)
    error->all(FLERR, "Fix mpm/fluid: keyword 'theta_transport yes' needs 'update musl' (the divergence of "
                      "theta u is taken in the MUSL remap)");
  if (coupled) {
    integrated_groupbits = 0;
    for (int m = 0; m < modify->nfix; ++m)
      if (modify->fix[m] != this && modify->fix[m]->time_integrate) integrated_groupbits |= modify->fix[m]->groupbit;
    const int ig = group->find(couple_group.c_str());
    if (ig < 0) bad_arg("couple", "an existing group-ID of the DEM grains", couple_group.c_str());
    couple_groupbit = group->bitmask[ig];
    double dmax = 0.0;
    int overlap = 0;
    for (int i = 0; i < atom->nlocal; ++i) {
      if (!(atom->mask[i] & couple_groupbit)) continue;
      if (is_point(i)) overlap = 1;
      dmax = std::max(dmax, 2.0 * atom->radius[i]);
    }
    double gd = 0.0;
    int go = 0;
    MPI_Allreduce(&dmax, &gd, 1, MPI_DOUBLE, MPI_MAX, world);
    MPI_Allreduce(&overlap, &go, 1, MPI_INT, MPI_MAX, world);
    if (go) error->all(FLERR, "Fix mpm/fluid: keyword 'couple' expects a grain group without material points");
    if (gd > gspec.dx) {
      std::ostringstream os;
      os << "Fix mpm/fluid: keyword 'cell' (" << gspec.dx << ") is smaller than the largest grain of group '"
         << couple_group << "' (diameter " << gd << "); the volume fraction (8-11) needs cells that hold grains";
      if (cell_check) {
        os << " (keyword 'cell_check no' overrides)";
        error->all(FLERR, os.str().c_str());
      } else if (comm->me == 0)
        error->warning(FLERR, os.str().c_str());
    }
  }
  vector_step = -1;
}

bool FixMpmFluid::is_grain(int i) const { return coupled && (atom->mask[i] & couple_groupbit) != 0; }

// Node volume for the grains' volume fraction (8-13) with shape functions
// reflected at the grid faces: half a cell on a wall, a full cell inside,
// none outside (the text's (8-13) integrates the unreflected shape function
// over the inside, which leaves the padding node 1/48 of a cell).
double FixMpmFluid::solid_node_volume(int i, int j, int k) const {
  const int idx[3] = {i, j, k};
  double v = gspec.dx * gspec.dx * gspec.dx;
  for (int d = 0; d < 3; ++d) {
    if (gspec.periodic[d]) continue;
    if (idx[d] < 0 || idx[d] > gspec.ncell[d]) return 0.0;
    if (idx[d] == 0 || idx[d] == gspec.ncell[d]) v *= 0.5;
  }
  return v;
}

void FixMpmFluid::setup_grid() {
  // Halo: support of the shape function plus the distance a point may travel
  // before LIGGGHTS re-neighbours and migrates it (half the skin), rounded up.
  const int halo = mpm::support(shape) + static_cast<int>(std::ceil(neighbor->skin / gspec.dx)) + 1;
  grid.setup(gspec, world, domain->sublo, domain->subhi, halo);
  g_p2g.assign(grid.size() * kP2g, 0.0);
  g_vel.assign(grid.size() * kVel, 0.0);
  g_cell.assign(grid.size() * kCell, 0.0);
  th_prev_valid = false;
  if (musl) g_aux.assign(grid.size() * kAux, 0.0);
  if (coupled) {
    g_cpl.assign(grid.size() * kPfit, 0.0);
    g_sol.assign(grid.size(), 0.0);
    g_need.assign(grid.size(), 0.0);
    g_th.assign(grid.size(), 1.0);
    if (theta_transport) g_th_prev.assign(grid.size(), 1.0);
    g_st.assign(grid.size() * kSt, 0.0);
    g_rx.assign(grid.size() * 3, 0.0);
    g_dr.assign(grid.size() * kDr, 0.0);
  }
  grid_ready = true;
}

void FixMpmFluid::mesh_refresh() {
  if (!mesh_walls) return;
  const mpm::IndexBox &pb = grid.patch();
  double lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = gspec.origin[d] + pb.lo[d] * gspec.dx;
    hi[d] = gspec.origin[d] + pb.hi[d] * gspec.dx;
  }
  try {
    mesh_walls->refresh(lo, hi, 2.0 * gspec.dx);
  } catch (const std::exception &e) {
    error->all(FLERR, e.what());
  }
  // the walls moved: the nodes' constraints are collected anew at their first use
  ++mw_epoch;
  mw_cache.clear();
  if (mw_stamp.size() != grid.size()) {
    mw_stamp.assign(grid.size(), -1);
    mw_first.assign(grid.size(), 0);
    mw_count.assign(grid.size(), 0);
    mw_near.assign(grid.size(), 1);
  }
}

void FixMpmFluid::setup(int) {
  setup_grid();
  if (!mesh_specs.empty()) {
    try {
      std::vector<mpm::MeshWallSpec> sp = mesh_specs;
      if (mesh_walls) for (size_t k = 0; k < sp.size(); ++k) sp[k].side = mesh_walls->side(k);
      mesh_walls.reset(new mpm::MeshWalls(lmp, sp));
      mesh_walls->set_kinematic_viscosity(viscosity / eos.rho0);
    } catch (const std::exception &e) {
      error->all(FLERR, (std::string("Fix mpm/fluid: ") + e.what()).c_str());
    }
    mesh_refresh();
    std::vector<const double *> pts;
    for (int i = 0; i < atom->nlocal; ++i) if (is_point(i)) pts.push_back(atom->x[i]);
    try {
      std::string log = mesh_walls->infer_sides(pts.data(), (int)pts.size(), 1.0 * gspec.dx);
      if (comm->me == 0 && !log.empty()) { if (screen) fputs(log.c_str(), screen); if (logfile) fputs(log.c_str(), logfile); }
    } catch (const std::exception &e) {
      error->all(FLERR, (std::string("Fix mpm/fluid: ") + e.what()).c_str());
    }
  }
  if (coupled && !theta_initialized) {
    init_theta();
  } else if (coupled && theta_transport) {
    // the nodes' fraction of the grains' present positions, from which the next sub-step's
    // change is taken (the points keep their own theta, also across a restart)
    compute_shapes();
    fluid_fraction();
  }
  check_timestep(true);
  if (out_every > 0 && update->ntimestep % out_every == 0) write_output();
  run_time_start[0] = time_fluid;
  run_time_start[1] = time_couple;
}

/* Where the fix's time went in the run just finished (slowest rank), next
   to LIGGGHTS' "Loop time": the fluid's own work and the coupling. */
void FixMpmFluid::post_run() {
  double t[2] = {time_fluid - run_time_start[0], time_couple - run_time_start[1]}, g[2];
  MPI_Allreduce(t, g, 2, MPI_DOUBLE, MPI_MAX, world);
  if (comm->me != 0) return;
  std::ostringstream os;
  os << "fix mpm/fluid: wall time in this run: fluid " << g[0] << " s";
  if (coupled) os << ", coupling " << g[1] << " s (" << (g[0] > 0.0 ? g[1] / g[0] : 0.0) << " of the fluid time)";
  os << "\n";
  if (screen) fputs(os.str().c_str(), screen);
  if (logfile) fputs(os.str().c_str(), logfile);
}

/* ----------------------------------------------------------------------
   stable time step: acoustic (CFL) and viscous limits (collective)
------------------------------------------------------------------------- */

double FixMpmFluid::stable_dt() {
  // max |v|, max density, -min density; with couple: max of rho (1 - theta) / theta over the
  // points, -min theta, -min density of the grains an integrator moves
  double loc[6] = {0.0, eos.rho0, -eos.rho0, 0.0, -1.0, -HUGE_VAL};
  for (int i = 0; i < atom->nlocal; ++i) {
    if (is_point(i)) {
      const double *v = atom->v[i];
      loc[0] = std::max(loc[0], std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
      loc[1] = std::max(loc[1], pdata[i][C_RHO]);
      loc[2] = std::max(loc[2], -pdata[i][C_RHO]);
      const double th = pdata[i][C_THETA];
      if (coupled && th > 0.0 && th < 1.0) {
        loc[3] = std::max(loc[3], pdata[i][C_RHO] * (1.0 - th) / th);
        loc[4] = std::max(loc[4], -th);
      }
    } else if (is_grain(i) && (atom->mask[i] & integrated_groupbits) && atom->radius[i] > 0.0) {
      const double r = atom->radius[i];
      loc[5] = std::max(loc[5], -atom->rmass[i] / (4.0 / 3.0 * M_PI * r * r * r));
    }
  }
  double glob[6];
  MPI_Allreduce(loc, glob, 6, MPI_DOUBLE, MPI_MAX, world);
  // Sound speed: largest over the density range (Tait stiffens under
  // compression, the linear law under tension).
  c_max = std::sqrt(std::max(eos.sound_speed_sq(glob[1]), eos.sound_speed_sq(-glob[2])));
  const double c = c_max;
  const double dt_ac = mpm::acoustic_dt_limit(cfl, gspec.dx, c, glob[0]);
  const double dt_visc = mpm::viscous_dt_limit(gspec.dx, eos.rho0, viscosity, domain->dimension);
  // Grains an integrator moves: the pore-pressure wave. Fluid and grains pushed by the same
  // pressure form one wave, c^2 = c_f^2 (1 + rho_f (1 - theta) / (theta rho_p)), that limits
  // the fluid step when the fluid is not sub-cycled; with sub-cycling the fluid follows the
  // grains within the step and the grains' own wave, c_g^2 = c_f^2 rho_f (1 - theta) /
  // (theta rho_p), limits the grains' step (docs/coupled_stability.md). Largest
  // rho_f (1 - theta) / theta over the points against the lightest moving grain.
  couple_theta_min = glob[4] < 0.0 ? -glob[4] : 1.0;
  couple_rho_grain = glob[5] > -HUGE_VAL ? -glob[5] : 0.0;
  c_couple = c_grain = 0.0;
  dt_couple_last = dt_grain_last = HUGE_VAL;
  if (couple_rho_grain > 0.0) {
    const double r = glob[3] / couple_rho_grain;
    c_couple = c * std::sqrt(1.0 + r);
    c_grain = c * std::sqrt(r);
    dt_couple_last = mpm::acoustic_dt_limit(cfl, gspec.dx, c_couple, glob[0]);
    dt_grain_last = c_grain > 0.0 ? mpm::acoustic_dt_limit(cfl, gspec.dx, c_grain, glob[0]) : HUGE_VAL;
  }
  return std::min(dt_ac, dt_visc);
}

void FixMpmFluid::check_timestep(bool at_setup) {
  dt_stable_last = stable_dt();
  const double dt = fluid_every * update->dt;
  if (!std::isfinite(dt_stable_last) || dt_stable_last <= 0.0 || std::isnan(dt_couple_last) ||
      std::isnan(dt_grain_last))
    error->all(FLERR, "Fix mpm/fluid: the fluid state is not finite (NaN velocity or density); "
                      "the run was unstable before this check");
  const char *what = fluid_every > 1 ? "fluid step (every x timestep) " : "timestep ";
  // a coupled limit exceeded: the error names the wave, its speed and the step to use
  auto coupled_error = [&](double limit, const char *whose, const char *wave, const char *csym,
                           const char *cformula, double cval, const char *before, const char *after) {
    std::ostringstream os;
    os.precision(4);
    os << "Fix mpm/fluid: " << what << dt << " exceeds the largest stable time step " << limit << " of the "
       << whose << " (" << wave << ": cfl*dx/(" << csym << "+|v|max) with cfl = " << cfl << ", dx = " << gspec.dx
       << ", " << csym << " = " << cformula << " = " << cval << ", fluid sound speed c_f = " << c_max
       << ", lowest fluid fraction theta = " << couple_theta_min << ", lightest moving grain rho_p = "
       << couple_rho_grain << "); " << before << "reduce the timestep to " << limit / fluid_every << after
       << " (docs/coupled_stability.md)" << (at_setup ? "" : " (limit reached during the run)");
    error->all(FLERR, os.str().c_str());
  };
  // the grains' wave: sub-cycling the fluid does not help, the grains move once per step
  if (subcycle && dt > dt_grain_last)
    coupled_error(dt_grain_last, "grains coupled with the fluid",
                  "pore-pressure wave of the grains with the fluid sub-cycled", "c_g",
                  "c_f*sqrt(rho_f*(1-theta)/(theta*rho_p))", c_grain,
                  "the grains move once per timestep, so 'subcycle yes' cannot help: ", "");
  // without sub-cycling, fluid and grains together: the coupled wave
  if (!subcycle && dt > dt_couple_last)
    coupled_error(dt_couple_last, "fluid coupled with the grains", "pore-pressure wave of fluid and grains", "c",
                  "c_f*sqrt(1 + rho_f*(1-theta)/(theta*rho_p))", c_couple, "", " or use keyword 'subcycle yes'");
  // the fluid (sub-)step: its own limit and, so that a step that is not sub-cycled also
  // satisfies it, the coupled one
  const double dt_sub = std::min(dt_stable_last, dt_couple_last);
  if (dt <= dt_sub) {
    nsub_last = 1;
    return;
  }
  if (!subcycle) {
    std::ostringstream os;
    os.precision(4);
    os << "Fix mpm/fluid: " << what << dt
       << " exceeds the largest stable time step " << dt_stable_last
       << " (acoustic limit cfl*dx/(c+|v|max) with cfl = " << cfl << ", dx = " << gspec.dx
       << ", c = " << c_max
       << ", or viscous limit dx^2 rho/(2 dim eta)); reduce the timestep to " << dt_stable_last / fluid_every
       << " or use keyword 'subcycle yes'" << (at_setup ? "" : " (limit reached during the run)");
    error->all(FLERR, os.str().c_str());
  }
  const int nsub = static_cast<int>(std::ceil(dt / dt_sub));
  if (nsub > max_subcycle) {
    std::ostringstream os;
    os << "Fix mpm/fluid: 'subcycle yes' would need " << nsub << " sub-steps per timestep (more than "
       << max_subcycle << "); reduce the timestep to at most " << max_subcycle * dt_sub;
    error->all(FLERR, os.str().c_str());
  }
  if (at_setup && comm->me == 0 && nsub != nsub_last) {
    std::ostringstream os;
    os << "fix mpm/fluid: sub-cycling with " << nsub << " fluid sub-steps of " << dt / nsub
       << " per timestep (stable limit " << dt_sub << ")\n";
    if (screen) fputs(os.str().c_str(), screen);
    if (logfile) fputs(os.str().c_str(), logfile);
  }
  nsub_last = nsub;
}

/* ----------------------------------------------------------------------
   one LIGGGHTS time step: all external forces on the points (fix gravity,
   fix addforce, ...) are in atom->f; the DEM integrator runs after us
------------------------------------------------------------------------- */

void FixMpmFluid::pre_final_integrate() {
  if (!grid_ready) setup_grid();
  if (gate.active && gate.release_time >= 0.0 && sim_time() >= gate.release_time - 0.5 * update->dt) {
    gate.active = false;
    if (comm->me == 0) {
      std::ostringstream os;
      os << "fix mpm/fluid: gate removed at time " << sim_time() << " (step " << update->ntimestep << ")\n";
      if (screen) fputs(os.str().c_str(), screen);
      if (logfile) fputs(os.str().c_str(), logfile);
    }
  }
  // between two fluid steps the grains get no fluid force: the fluid step gave them the
  // whole impulse of its N steps at once (below)
  if (fluid_every > 1 && update->ntimestep % fluid_every != 0) return;
  check_timestep(false);
  mesh_refresh();
  const double h = fluid_every * update->dt / nsub_last;
  if (coupled) grain_force.assign(3 * static_cast<std::size_t>(atom->nlocal), 0.0);
  for (int s = 0; s < nsub_last; ++s) substep(h);
  if (coupled) {
    // fluid force on the grains (mean over the sub-steps), for final_integrate. With every N
    // the grains get the impulse of the N steps, N h F, in this step (force N F): velocity
    // Verlet then advances them as one symplectic step of N dt. Keeping F for N steps
    // instead spreads the kick over the drift and makes every undamped coupled oscillation
    // grow (docs/coupled_stability.md, "every N").
    for (int k = 0; k < atom->nlocal; ++k) {
      if (!is_grain(k)) continue;
      for (int d = 0; d < 3; ++d) {
        atom->f[k][d] += fluid_every * grain_force[3 * k + d];
        pdata[k][C_FGRAIN + d] = grain_force[3 * k + d];
        if (fix_dragforce) fix_dragforce->array_atom[k][d] = grain_force[3 * k + d];
      }
    }
  }
  vector_step = -1;
}

void FixMpmFluid::substep(double h) {
  // wall time of the fluid's own work and of the coupling (f_ID[14], f_ID[15])
  const double t0 = MPI_Wtime();
  compute_shapes();
  double t1 = MPI_Wtime(), t2 = t1;
  if (coupled) {
    fluid_fraction();
    t2 = MPI_Wtime();
  }
  particles_to_grid();
  double t3 = MPI_Wtime(), t4 = t3;
  if (coupled) {
    couple_fluid_grains(h);
    t4 = MPI_Wtime();
  }
  update_grid(h);
  grid_to_particles(h);
  if (musl) remap_velocity_musl(h);
  update_stress(h);
  advance_positions(h);
  const double t5 = MPI_Wtime();
  time_fluid += (t1 - t0) + (t3 - t2) + (t5 - t4);
  time_couple += (t2 - t1) + (t4 - t3);
}

void FixMpmFluid::compute_shapes() {
  const int nlocal = atom->nlocal;
  if (static_cast<int>(shapes.size()) < nlocal) {
    shapes.resize(nlocal);
    vpic.resize(3 * static_cast<std::size_t>(nlocal));
    velgrad.resize(9 * static_cast<std::size_t>(nlocal));
  }
  plist.clear();
  double **x = atom->x;
  for (int i = 0; i < nlocal; ++i) {
    if (!is_point(i)) continue;
    plist.push_back(i);
    if (!shape_of(x[i], shapes[i])) {
      std::ostringstream os;
      os << "Fix mpm/fluid: material point " << atom->tag[i] << " at (" << x[i][0] << ", " << x[i][1] << ", "
         << x[i][2] << ") left the grid [" << gspec.origin[0] << ", " << gspec.upper(0) << "] x ["
         << gspec.origin[1] << ", " << gspec.upper(1) << "] x [" << gspec.origin[2] << ", " << gspec.upper(2)
         << "] at step " << update->ntimestep << " (enlarge 'grid' or check for an unstable run)";
      fail_one(os.str());
    }
  }
}

// Weights and gradients of the nodes around x; false if x is outside the grid.
bool FixMpmFluid::shape_of(const double *x, PointShape &ps) {
  const int ns = mpm::support(shape);
  const double inv = 1.0 / gspec.dx;
  const mpm::IndexBox &pb = grid.patch();
  for (int d = 0; d < 3; ++d) {
    const double xi = (x[d] - gspec.origin[d]) * inv;
    if (!gspec.periodic[d] && (xi < 0.0 || xi > gspec.ncell[d])) return false;
    mpm::Shape1D s;
    mpm::shape_eval(shape, xi, s);
    ps.base[d] = s.base;
    for (int a = 0; a < 3; ++a) {
      ps.w[d][a] = s.w[a];
      ps.dw[d][a] = s.dw[a] * inv;
    }
    if (s.base < pb.lo[d] || s.base + ns - 1 > pb.hi[d]) {
      std::ostringstream os;
      os << "Fix mpm/fluid: atom at (" << x[0] << ", " << x[1] << ", " << x[2]
         << ") is outside the grid patch of rank " << comm->me
         << "; it moved too far between re-neighbourings (use neigh_modify every 1 check yes)";
      fail_one(os.str());
    }
  }
  ps.n0 = grid.index(ps.base[0], ps.base[1], ps.base[2]);
  return true;
}

// fn(n, w) for the nodes a stencil reaches (the fix's shape functions)
template <class Fn>
void FixMpmFluid::for_nodes(const PointShape &ps, Fn &&fn) const {
  const std::size_t sy = grid.stride_y(), sz = grid.stride_z();
  auto body = [&](std::size_t n, int, int, int, double w, double, double, double) { fn(n, w); };
  if (shape == mpm::ShapeKind::QuadraticBSpline)
    mpm::for_stencil<3>(ps, sy, sz, body);
  else
    mpm::for_stencil<2>(ps, sy, sz, body);
}

/* particles to grid: mass (8-19), momentum (8-10), internal force (8-24),
   external forces (gravity (8-18) and whatever LIGGGHTS fixes add) */
void FixMpmFluid::particles_to_grid() {
  std::fill(g_p2g.begin(), g_p2g.end(), 0.0);
  const bool affine = transfer == TR_APIC;
  if (shape == mpm::ShapeKind::QuadraticBSpline)
    affine ? p2g_kernel<3, true>() : p2g_kernel<3, false>();
  else
    affine ? p2g_kernel<2, true>() : p2g_kernel<2, false>();
  grid.reverse_sum(g_p2g.data(), kP2g);
}

// Offsets x_i - x_p of the stencil's node planes from the point, per direction.
static inline void stencil_offsets(const mpm::GridSpec &gs, const mpm::Stencil &ps, const double *xp,
                                   double o[3][3]) {
  for (int d = 0; d < 3; ++d)
    for (int a = 0; a < 3; ++a) o[d][a] = gs.origin[d] + (ps.base[d] + a) * gs.dx - xp[d];
}

// APIC: the affine part m C (x_i - x_p) of the momentum a point gives node (a, b, c) of its
// stencil, from mC = m C (row-major) and the node-plane offsets o.
static inline void affine_momentum(const double mC[9], const double o[3][3], int a, int b, int c, double d[3]) {
  const double ox = o[0][a], oy = o[1][b], oz = o[2][c];
  for (int r = 0; r < 3; ++r) d[r] = mC[3 * r] * ox + mC[3 * r + 1] * oy + mC[3 * r + 2] * oz;
}

template <int NS, bool AFFINE>
void FixMpmFluid::p2g_kernel() {
  double **x = atom->x, **v = atom->v, **f = atom->f;
  const double *rmass = atom->rmass;
  double *const g = g_p2g.data();
  const std::size_t sy = grid.stride_y(), sz = grid.stride_z();
  const bool traction = wall_traction && shape == mpm::ShapeKind::QuadraticBSpline;
  for (const int i : plist) {
    const PointShape &ps = shapes[i];
    const double *s = pdata[i];
    const double m = rmass[i], V = s[C_VOL], p = s[C_P];
    const double *t = s + C_TAU;
    // -V sigma with sigma = -p I + tau (tau in Voigt order xx yy zz yz xz xy)
    const double sxx = -V * (t[0] - p), syy = -V * (t[1] - p), szz = -V * (t[2] - p);
    const double syz = -V * t[3], sxz = -V * t[4], sxy = -V * t[5];
    // Node record m, m v (3), f (3), pad: each update is two 4-wide rows
    // (mass and momentum; force) that the compiler vectorizes.
    const mpm::Row4 mv = {m, m * v[i][0], m * v[i][1], m * v[i][2]};
    const mpm::Row4 fe = {f[i][0], f[i][1], f[i][2], 0.0};
    const mpm::Row4 sx = {sxx, sxy, sxz, 0.0}, sy_ = {sxy, syy, syz, 0.0}, sz_ = {sxz, syz, szz, 0.0};
    double mC[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, o[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    if (AFFINE) {
      for (int c = 0; c < 9; ++c) mC[c] = m * s[C_AFF + c];
      stencil_offsets(gspec, ps, x[i], o);
    }
    mpm::for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double gx, double gy,
                                         double gz) {
      mpm::Row4 u = mv;
      if (AFFINE) {
        double d[3];
        affine_momentum(mC, o, a, b, c, d);
        for (int r = 0; r < 3; ++r) u[1 + r] += d[r];
      }
      double *gn = g + kP2g * n;
      mpm::row4(gn) += w * u;
      mpm::row4(gn + 4) += w * fe + gx * sx + gy * sy_ + gz * sz_;
    });
    if (traction) {
      add_wall_traction(ps, x[i], V, p);
      if (mesh_walls) add_mesh_wall_traction(x[i], V, p);
    }
  }
}

/* Wall traction, the boundary term (8-23) f_j = int_wall S_j sigma n ds, for
   the quadratic B-spline. Its shape function of the first node inside a wall
   is 1/8 on the wall, so that node must carry 1/8 of the wall's pressure
   push; the internal force (8-24) alone pulls it towards the wall by exactly
   that much (in a uniformly pressurised box the fluid would be drawn to the
   walls). The wall and padding nodes get their share from the velocity
   condition anyway. Quadrature: the points of the cell next to the wall,
   each standing for the wall area V_p / dx, with their in-plane weights. */
void FixMpmFluid::add_wall_traction(const PointShape &ps, const double *xp, double V, double p) {
  const double inv = 1.0 / gspec.dx;
  for (int d = 0; d < 3; ++d) {
    if (gspec.periodic[d]) continue;
    const double xi = (xp[d] - gspec.origin[d]) * inv;
    int node, dir;
    if (xi < 1.0) {
      node = 1;
      dir = 1;  // the low wall pushes towards +d
    } else if (xi > gspec.ncell[d] - 1.0) {
      node = gspec.ncell[d] - 1;
      dir = -1;
    } else
      continue;
    const int e = (d + 1) % 3, f = (d + 2) % 3;
    const double push = dir * 0.125 * p * V * inv;
    for (int b = 0; b < 3; ++b)
      for (int c = 0; c < 3; ++c) {
        int idx[3];
        idx[d] = node;
        idx[e] = ps.base[e] + b;
        idx[f] = ps.base[f] + c;
        g_p2g[kP2g * grid.index(idx[0], idx[1], idx[2]) + 4 + d] += push * ps.w[e][b] * ps.w[f][c];
      }
  }
}

/* Fluid fraction (8-11)-(8-14) at the nodes from the grains' volumes (with
   the optional smoothing) and at the points (8-16), then the points'
   density and pressure for it. Done at the start of each sub-step, before
   the particles-to-grid map and the forces on the grains, so that the
   pressure with which the fluid and the grains push each other belongs to
   the grains' present positions: with the pressure of the previous
   sub-step (theta of the grains' old positions) the restoring force of
   the fluid on a grain lags one step behind its displacement, which feeds
   energy into the grain-fluid oscillation (stiff: K / theta per unit
   volume change) and made the moving dense bed of C3 blow up. */
void FixMpmFluid::fluid_fraction() {
  const int nlocal = atom->nlocal;
  double **x = atom->x;
  double *radius = atom->radius;
  if (static_cast<int>(grain_shapes.size()) < nlocal) grain_shapes.resize(nlocal);
  std::fill(g_sol.begin(), g_sol.end(), 0.0);
  std::fill(g_need.begin(), g_need.end(), 0.0);
  for (int k = 0; k < nlocal; ++k) {
    if (!is_grain(k)) continue;
    PointShape &ps = grain_shapes[k];
    if (!shape_of(x[k], ps)) {
      ps.base[0] = INT_MIN;  // outside the grid: no fluid there
      continue;
    }
    const double Vk = 4.0 / 3.0 * M_PI * radius[k] * radius[k] * radius[k];
    for_nodes(ps, [&](std::size_t n, double w) {
      g_sol[n] += w * Vk;
      g_need[n] = 1.0;
    });
  }
  grid.reverse_sum(g_need.data(), 1);  // nodes some grain reads (fit of the pressure only there)
  // Walls: the solid volume mapped to a node outside a grid face is folded
  // onto its mirror node inside (reflected shape functions), so that no node
  // has the sliver volume that (8-13) gives the padding nodes (1/48 of a
  // cell for the B-spline: one grain near the wall would swing its theta by
  // tens of per cent, and the pressure of the points next to the wall with
  // it, by K dtheta/theta). Node volumes: half a cell on the wall, full
  // inside; a padding node takes the fraction of its mirror.
  auto mirror = [&](int c, int d) {
    if (gspec.periodic[d]) return c;
    return c < 0 ? -c : (c > gspec.ncell[d] ? 2 * gspec.ncell[d] - c : c);
  };
  const mpm::IndexBox &pb = grid.patch();
  for (int d = 0; d < 3; ++d) {
    if (gspec.periodic[d]) continue;
    // only the patch's padding layers outside the low and the high face
    const int layers[2][2] = {{pb.lo[d], std::min(pb.hi[d], -1)},
                              {std::max(pb.lo[d], gspec.ncell[d] + 1), pb.hi[d]}};
    for (const auto &L : layers) {
      mpm::IndexBox b = pb;
      b.lo[d] = L[0];
      b.hi[d] = L[1];
      for (int k = b.lo[2]; k <= b.hi[2]; ++k)
        for (int j = b.lo[1]; j <= b.hi[1]; ++j)
          for (int i = b.lo[0]; i <= b.hi[0]; ++i) {
            const std::size_t n = grid.index(i, j, k);
            int idx[3] = {i, j, k};
            idx[d] = mirror(idx[d], d);
            if (g_sol[n] != 0.0 && grid.in_patch(idx[0], idx[1], idx[2])) {
              g_sol[grid.index(idx[0], idx[1], idx[2])] += g_sol[n];
              g_sol[n] = 0.0;
            }
          }
    }
  }
  grid.reverse_sum(g_sol.data(), 1);
  if (theta_smooth > 0.0) smooth_solid_volume();
  grid.for_owned([&](int i, int j, int k, std::size_t n) {
    const int mi[3] = {mirror(i, 0), mirror(j, 1), mirror(k, 2)};
    const double Vj = solid_node_volume(mi[0], mi[1], mi[2]);
    const std::size_t m = grid.in_patch(mi[0], mi[1], mi[2]) ? grid.index(mi[0], mi[1], mi[2]) : n;
    g_th[n] = std::min(1.0, std::max(theta_min, 1.0 - g_sol[m] / Vj));  // (8-11), (8-14)
  });
  grid.forward(g_th.data(), 1);
  const double *const gth = g_th.data();
  if (!theta_transport || !theta_initialized) {
    for (const int i : plist) {
      double th = 0.0;
      for_nodes(shapes[i], [&](std::size_t n, double w) { th += w * gth[n]; });
      pdata[i][C_THETA] = th;
    }
  } else if (th_prev_valid) {
    // theta_transport: the point keeps its own fluid fraction; here it takes the change of the
    // nodes' fraction since the last sub-step (the grains moved), the fluid's motion enters in
    // update_stress through the divergence of theta u (docs/fix_mpm_fluid.md)
    const double *const gprev = g_th_prev.data();
    for (const int i : plist) {
      double dth = 0.0;
      for_nodes(shapes[i], [&](std::size_t n, double w) { dth += w * (gth[n] - gprev[n]); });
      pdata[i][C_THETA] = std::min(1.0, std::max(theta_min, pdata[i][C_THETA] + dth));
    }
  }
  if (theta_transport) {
    g_th_prev = g_th;
    th_prev_valid = true;
  }
  if (theta_initialized) update_stress(0.0, true);
}

/* The same boundary term (8-23) at mesh walls: a point closer than one
   cell to a triangle face stands for the wall area V_p / dx at its nearest
   point q on the face (the points of the layer next to the wall tile it),
   and the wall pushes the fluid with p V_p / dx along the face normal
   towards the fluid, shared among the nodes by their weights at q. Nodes
   behind the wall take their share out again through the velocity
   condition; the nodes in front get the push that the internal force
   (8-24) alone lacks there (without it a curved mesh wall draws the fluid
   in: docs/mesh_walls.md). */
void FixMpmFluid::add_mesh_wall_traction(const double *xp, double V, double p) {
  double q[3], nrm[3];
  if (p == 0.0 || !near_mesh_wall(xp) || !mesh_walls->nearest_face(xp, gspec.dx, q, nrm)) return;
  const double inv = 1.0 / gspec.dx;
  const mpm::IndexBox &pb = grid.patch();
  int base[3];
  double w[3][3];
  for (int d = 0; d < 3; ++d) {
    double xi = (q[d] - gspec.origin[d]) * inv;
    if (!gspec.periodic[d]) xi = std::min(std::max(xi, 0.0), static_cast<double>(gspec.ncell[d]));
    mpm::Shape1D sh;
    mpm::shape_eval(shape, xi, sh);
    if (sh.base < pb.lo[d] || sh.base + 2 > pb.hi[d]) return;
    base[d] = sh.base;
    for (int a = 0; a < 3; ++a) w[d][a] = sh.w[a];
  }
  const double push = p * V * inv;
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b)
      for (int a = 0; a < 3; ++a) {
        const double wt = push * w[0][a] * w[1][b] * w[2][c];
        double *g = &g_p2g[kP2g * grid.index(base[0] + a, base[1] + b, base[2] + c) + 4];
        for (int d = 0; d < 3; ++d) g[d] += wt * nrm[d];
      }
}

/* Moments of the points' pressures for the linear least-squares fit at each
   node (couple_fluid_grains): with e = (1, x_s - x_j) for the point's
   sample position x_s, the node collects r = sum S V p e and the normal
   matrix M = sum S V e e^T (rows of g_cpl: r, then M's four rows). */
template <int NS>
void FixMpmFluid::pressure_moments() {
  double **x = atom->x;
  double *const g = g_cpl.data();
  const double *const need = g_need.data();
  const std::size_t sy = grid.stride_y(), sz = grid.stride_z();
  for (const int i : plist) {
    const PointShape &ps = shapes[i];
    const double V = pdata[i][C_VOL], p = pdata[i][C_P];
    if (!grad_p_fit) {
      // grad_p nodal: only the volume-weighted mean, sum S V p / sum S V
      mpm::for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double, double, double) {
        double *cn = g + kPfit * n;
        cn[0] += w * V * p;
        cn[4] += w * V;
      });
      continue;
    }
    const double *xp = x[i];
    // With anti-locking the pressure is the cell's (its mean density): it
    // belongs to the cell's centre, not to the point (a fit to the points'
    // own positions sees a staircase and, near a wall, a flat one).
    double dn[3][3];  // x_s - x_j per direction, for the stencil's node planes
    for (int a = 0; a < 3; ++a) {
      double xs = xp[a];
      if (antilock) {
        int c = static_cast<int>(std::floor((xp[a] - gspec.origin[a]) / gspec.dx));
        if (!gspec.periodic[a]) c = std::min(std::max(c, 0), gspec.ncell[a] - 1);
        xs = gspec.origin[a] + (c + 0.5) * gspec.dx;
      }
      for (int q = 0; q < 3; ++q) dn[a][q] = xs - (gspec.origin[a] + (ps.base[a] + q) * gspec.dx);
    }
    mpm::for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double, double, double) {
      if (need[n] == 0.0) return;
      const mpm::Row4 e = {1.0, dn[0][a], dn[1][b], dn[2][c]};
      const mpm::Row4 we = (w * V) * e;
      double *cn = g + kPfit * n;
      mpm::row4(cn) += p * we;
      mpm::row4(cn + 4) += we;
      mpm::row4(cn + 8) += e[1] * we;
      mpm::row4(cn + 12) += e[2] * we;
      mpm::row4(cn + 16) += e[3] * we;
    });
  }
}

/* Two-way coupling with the DEM grains (chapter 7.2, 8.1-8.2):
   fluid fraction at the nodes from the grains' volumes (8-11)-(8-14) and at
   the points (8-16); fluid velocity, fraction and pressure gradient at each
   grain; drag (7-7) integrated exactly over the sub-step for the two-body
   system grain + fluid seen by it (stable for any stiffness) and the
   pressure-gradient force -V grad p (7-15); the reaction of both goes to the
   nodes with the same shape functions (8-25), (8-26), so momentum is kept. */
void FixMpmFluid::couple_fluid_grains(double h) {
  if (shape == mpm::ShapeKind::QuadraticBSpline)
    couple_kernel<3>(h);
  else
    couple_kernel<2>(h);
}

template <int NS>
void FixMpmFluid::couple_kernel(double h) {
  const int nlocal = atom->nlocal;
  const std::size_t sy = grid.stride_y(), sz = grid.stride_z();
  const double *const gst = g_st.data();
  double *const gdr = g_dr.data();
  double **v = atom->v;
  double *radius = atom->radius, *rmass = atom->rmass;
  if (static_cast<int>(grain_shapes.size()) < nlocal) grain_shapes.resize(nlocal);

  // Pressure at the nodes for the force on the grains: a linear least-squares
  // fit p_j + b.(x - x_j) to the pressures of the points around node j,
  // weighted by S_j V_p. A plain weighted mean would be the pressure of the
  // points' centre, which next to a wall or the bed's floor lies up to a cell
  // off the node: the gradient at a grain resting on the floor was then a
  // fraction of the hydrostatic one (39 % of Archimedes at z = r, cell = 3 d;
  // docs/drag.md). The fit reproduces any linear pressure field exactly.
  std::fill(g_cpl.begin(), g_cpl.end(), 0.0);
  pressure_moments<NS>();
  grid.reverse_sum(g_cpl.data(), kPfit);

  const double mmin = mass_threshold * point_mass_ref;
  grid.for_owned([&](int, int, int, std::size_t n) {
    const double *c = &g_cpl[kPfit * n];
    const double *g = &g_p2g[kP2g * n];
    double *st = &g_st[kSt * n];
    for (int q = 0; q < kSt; ++q) st[q] = 0.0;
    st[S_TH] = g_th[n];
    st[S_P] = c[4] > 0.0 ? c[0] / c[4] : 0.0;
    if (grad_p_fit && c[4] > 0.0 && g_need[n] > 0.0) {
      Eigen::Matrix4d M;
      for (int r = 0; r < 4; ++r)
        for (int q = 0; q < 4; ++q) M(r, q) = c[4 + 4 * r + q];
      const Eigen::Vector4d r(c[0], c[1], c[2], c[3]);
      // scale the offsets by the cell so that the system is well conditioned
      const double s = 1.0 / gspec.dx;
      const Eigen::Vector4d D(1.0, s, s, s);
      const Eigen::Matrix4d Ms = D.asDiagonal() * M * D.asDiagonal();
      Eigen::LDLT<Eigen::Matrix4d> ldlt(Ms);
      if (ldlt.info() == Eigen::Success && ldlt.rcond() > 1e-6) {
        const Eigen::Vector4d sol = D.asDiagonal() * ldlt.solve(D.asDiagonal() * r);
        if (std::isfinite(sol[0]) && std::isfinite(sol[1]) && std::isfinite(sol[2]) && std::isfinite(sol[3])) {
          st[S_P] = sol[0];
          for (int a = 0; a < 3; ++a) st[S_FIT + a] = sol[1 + a];
          st[S_FIT + 3] = 1.0;  // the fit (value and gradient) is determined
        }
      }
    }
    st[S_M] = g[0];
    if (g[0] > mmin) {  // only nodes that hold fluid carry its velocity
      for (int d = 0; d < 3; ++d) st[S_U + d] = g[1 + d] / g[0];
      st[S_U + 3] = 1.0;
    }
  });
  grid.forward(g_st.data(), kSt);

  // Drag, exchanged node by node. Each grain k has the coefficient K_k
  // (frozen over the sub-step) and touches node j with weight S_jk. At every
  // node the fluid (mass M_j, velocity u_j) and the grains' share of it
  // (coefficient K_j = sum_k S_jk K_k, mass sum_k S_jk m_k, K-weighted mean
  // velocity) exchange the backward-Euler two-body impulse J_j over h: the
  // slip decays without overshoot however many grains share the node (a dense
  // bed) and however stiff the drag, the fluid loses exactly what the grains
  // gain, and a grain advanced by LIGGGHTS' velocity Verlet keeps the right
  // terminal slip (see mpm::drag_implicit_impulse). Grain k
  // receives the share S_jk K_k / K_j of J_j. The pressure-gradient force
  // (7-15) is explicit (not stiff); its reaction goes to the nodes too.
  const double mu = viscosity, rho_f = eos.rho0;
  const std::size_t ng = static_cast<std::size_t>(nlocal);
  std::vector<double> Kgrain(ng, 0.0);
  std::fill(g_dr.begin(), g_dr.end(), 0.0);
  for (int k = 0; k < nlocal; ++k) {
    if (!is_grain(k) || grain_shapes[k].base[0] == INT_MIN) continue;
    const PointShape &ps = grain_shapes[k];
    // one pass over the stencil: velocity of the wet nodes (and their total
    // weight, the record's 4th entry), fitted gradients of the determined
    // nodes (and their weight), fluid fraction, gradient of the nodal pressures
    mpm::Row4 uw = {0, 0, 0, 0}, fw = {0, 0, 0, 0};
    double th = 0.0, gradp[3] = {0, 0, 0};
    mpm::for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double gx, double gy, double gz) {
      const double *st = gst + kSt * n;
      uw += w * mpm::row4(st + S_U);
      fw += w * mpm::row4(st + S_FIT);
      th += w * st[S_TH];
      gradp[0] += st[S_P] * gx;
      gradp[1] += st[S_P] * gy;
      gradp[2] += st[S_P] * gz;
    });
    const double wet = uw[3], wfit = fw[3];
    double u[3] = {uw[0], uw[1], uw[2]};
    // Pressure gradient at the grain: the fitted nodal gradients interpolated
    // (exact for a linear pressure field, also next to walls where a node's
    // own fit is undetermined: all its points in one layer); the gradient of
    // the interpolated nodal pressures where no fit is determined.
    if (wfit > 0.5)
      for (int d = 0; d < 3; ++d) gradp[d] = fw[d] / wfit;
    const double d_k = 2.0 * radius[k];
    const double Vk = M_PI / 6.0 * d_k * d_k * d_k;
    double K = 0.0;
    if (wet > 0.0) {
      for (int d = 0; d < 3; ++d) u[d] /= wet;
      const double urel = std::sqrt((u[0] - v[k][0]) * (u[0] - v[k][0]) + (u[1] - v[k][1]) * (u[1] - v[k][1]) +
                                    (u[2] - v[k][2]) * (u[2] - v[k][2]));
      K = mpm::drag_coefficient(drag_law, drag_form, rho_f, mu, d_k, Vk, th, urel, theta_min);
    }
    Kgrain[k] = K;
    double Fp[3];
    mpm::pressure_gradient_force(Vk, gradp, Fp);
    if (wet <= 0.0) Fp[0] = Fp[1] = Fp[2] = 0.0;
    for (int d = 0; d < 3; ++d) grain_force[3 * static_cast<std::size_t>(k) + d] += Fp[d] / nsub_last;
    // the grain's other accelerations (contacts, gravity: atom->f so far, and
    // the pressure force), held over the step in the exact exchange
    double ak[3];
    for (int d = 0; d < 3; ++d) ak[d] = (atom->f[k][d] + Fp[d]) / rmass[k];
    // a grain no integrator moves (a fixed bed) has, for the exchange, infinite mass
    const bool mobile = (atom->mask[k] & integrated_groupbits) != 0;
    if (!mobile) ak[0] = ak[1] = ak[2] = 0.0;
    // record: K, K v (3); m, -Fp (3); K a (3), K of a fixed grain
    const mpm::Row4 r0 = {K, K * v[k][0], K * v[k][1], K * v[k][2]};
    const mpm::Row4 r1 = {rmass[k], -Fp[0], -Fp[1], -Fp[2]};
    const mpm::Row4 r2 = {K * ak[0], K * ak[1], K * ak[2], mobile ? 0.0 : K};
    mpm::for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double, double, double) {
      double *q = gdr + kDr * n;
      mpm::row4(q) += w * r0;
      mpm::row4(q + 4) += w * r1;
      mpm::row4(q + 8) += w * r2;
    });
  }
  grid.reverse_sum(g_dr.data(), kDr);

  // node-wise exact exchange; the fluid's share of it stays on the owner
  std::fill(g_rx.begin(), g_rx.end(), 0.0);
  grid.for_owned([&](int i, int j, int k, std::size_t n) {
    double *q = &g_dr[kDr * n];
    const double *st = &g_st[kSt * n];
    double *rx = &g_rx[3 * n];
    double J[3] = {0, 0, 0};
    if (q[0] > 0.0 && st[S_M] > mmin) {
      const double vg[3] = {q[1] / q[0], q[2] / q[0], q[3] / q[0]};
      const double ag[3] = {q[8] / q[0], q[9] / q[0], q[10] / q[0]};
      const double *f = &g_p2g[kP2g * n + 4];
      const double mf = st[S_M];
      const double af[3] = {(f[0] + q[5]) / mf, (f[1] + q[6]) / mf, (f[2] + q[7]) / mf};
      const double mg = q[11] > 0.0 ? HUGE_VAL : q[4];
      mpm::drag_implicit_impulse(vg, st + S_U, mg, mf, q[0], h, J, ag, af);
    }
    for (int d = 0; d < 3; ++d) {
      rx[d] = q[5 + d] - J[d] / h;                    // force on the fluid
      q[1 + d] = q[0] > 0.0 ? J[d] / q[0] : 0.0;      // impulse per unit K, to the grains
    }
  });
  grid.forward(g_dr.data(), kDr);
  for (int k = 0; k < nlocal; ++k) {
    if (!is_grain(k) || grain_shapes[k].base[0] == INT_MIN || Kgrain[k] <= 0.0) continue;
    const PointShape &ps = grain_shapes[k];
    mpm::Row4 J = {0, 0, 0, 0};  // J[1..3]: the impulse per unit K of the nodes, weighted
    mpm::for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double, double, double) {
      J += w * mpm::row4(gdr + kDr * n);
    });
    for (int d = 0; d < 3; ++d)
      grain_force[3 * static_cast<std::size_t>(k) + d] += Kgrain[k] * J[1 + d] / h / nsub_last;
  }
}

/* Smoothing of the grains' volume at the owned nodes (g_sol) by a
   discrete diffusion of the solid fraction phi_j = S_j / V_j: passes of the
   filter [1/4 1/2 1/4] along each direction; the flux between neighbours
   j, n is (phi_n - phi_j) min(V_j, V_n) / 4, so the total solid volume is
   kept exactly, a uniform fraction stays uniform, nodes outside a wall
   (V = 0) take no part and each pass is stable. A pass adds dx^2/2 to the
   variance of the kernel, so ceil(2 L^2 / dx^2) passes give a Gaussian of
   standard deviation L (docs/drag.md, "Smoothing the fluid fraction"). */
void FixMpmFluid::smooth_solid_volume() {
  const double dx = gspec.dx;
  const int passes = static_cast<int>(std::ceil(2.0 * theta_smooth * theta_smooth / (dx * dx) - 1e-9));
  if (passes <= 0) return;
  g_phi.assign(2 * grid.size(), 0.0);  // phi, node volume
  grid.for_owned([&](int i, int j, int k, std::size_t n) {
    const double V = solid_node_volume(i, j, k);
    g_phi[2 * n] = V > 0.0 ? g_sol[n] / V : 0.0;
    g_phi[2 * n + 1] = V;
  });
  grid.forward(g_phi.data(), 2);
  g_phi_new.resize(grid.size());
  for (int pass = 0; pass < passes; ++pass)
    for (int d = 0; d < 3; ++d) {
      if (!gspec.periodic[d] && gspec.ncell[d] < 2) continue;
      grid.for_owned([&](int i, int j, int k, std::size_t n) {
        const double V = g_phi[2 * n + 1], phi = g_phi[2 * n];
        double S = phi * V;
        for (int side = -1; side <= 1; side += 2) {
          int idx[3] = {i, j, k};
          idx[d] += side;
          if (!grid.in_patch(idx[0], idx[1], idx[2])) continue;
          const std::size_t m = grid.index(idx[0], idx[1], idx[2]);
          S += 0.25 * std::min(V, g_phi[2 * m + 1]) * (g_phi[2 * m] - phi);
        }
        g_phi_new[n] = V > 0.0 ? S / V : 0.0;
      });
      grid.for_owned([&](int, int, int, std::size_t n) { g_phi[2 * n] = g_phi_new[n]; });
      grid.forward(g_phi.data(), 2);
    }
  grid.for_owned([&](int, int, int, std::size_t n) { g_sol[n] = g_phi[2 * n] * g_phi[2 * n + 1]; });
}

// At the first run with grains: the fluid present in a point's volume is
// theta of it, so its mass is reduced once to theta rho0 V (8-3): otherwise
// the grains' volume would be counted as compressed fluid.
void FixMpmFluid::init_theta() {
  compute_shapes();
  fluid_fraction();
  for (int i = 0; i < atom->nlocal; ++i) {
    if (!is_point(i)) continue;
    atom->rmass[i] *= pdata[i][C_THETA];
    pdata[i][C_RHO] = atom->rmass[i] / (pdata[i][C_THETA] * pdata[i][C_VOL]);
  }
  theta_initialized = true;
}

// Wall, gate: velocity v of node (i,j,k) after the momentum update.
void FixMpmFluid::apply_grid_bc(double *vel, int i, int j, int k, double h) {
  const int idx[3] = {i, j, k};
  for (int d = 0; d < 3; ++d) {
    if (gspec.periodic[d]) continue;
    int fc = -1;
    if (idx[d] <= 0)
      fc = 2 * d;
    else if (idx[d] >= gspec.ncell[d])
      fc = 2 * d + 1;
    if (fc < 0) continue;
    // normal component: no penetration; tangential: keep (1 - sticky) of it, or for a shear
    // face the exact decay over h under the wall stress mu v_t / delta on the fluid within a cell
    // of the face, rate nu / (delta dx) (as mesh_wall ... shear, docs/mesh_walls.md)
    const double keep = face[fc].kind == BC_SHEAR
                            ? std::exp(-h * mpm::wall_layer_rate(viscosity / eos.rho0, face[fc].delta, gspec.dx))
                            : 1.0 - face[fc].sticky;
    for (int e = 0; e < 3; ++e) vel[e] = (e == d) ? 0.0 : keep * vel[e];
  }
  if (mesh_walls) {
    // The triangles near a node and the closest points do not change between two refreshes
    // (one per fluid step): the grid update and the MUSL remap, and every sub-step, reuse the
    // node's constraints (node_walls).
    const std::size_t n = node_walls(i, j, k);
    mpm::MeshWalls::impose(mw_cache.data() + mw_first[n], mw_count[n], vel, h);
  }
  if (gate.active) {
    const int d = gate.dim;
    const double xn = gspec.origin[d] + idx[d] * gspec.dx;
    if (gate.fluid_below && xn >= gate.pos - 1e-9 * gspec.dx) vel[d] = std::min(vel[d], 0.0);
    if (!gate.fluid_below && xn <= gate.pos + 1e-9 * gspec.dx) vel[d] = std::max(vel[d], 0.0);
  }
}

/* The mesh-wall constraints of node (i, j, k) (in the patch) for the wall positions of the last
   refresh, collected at the node's first use after it: entries mw_first[n] .. + mw_count[n] of
   mw_cache, and mw_near[n] = some triangle within 2 cells of the node. Returns the flat index. */
std::size_t FixMpmFluid::node_walls(int i, int j, int k) {
  const std::size_t n = grid.index(i, j, k);
  if (mw_stamp[n] != mw_epoch) {
    const double xn[3] = {gspec.origin[0] + i * gspec.dx, gspec.origin[1] + j * gspec.dx,
                          gspec.origin[2] + k * gspec.dx};
    mpm::WallConstraint c[mpm::MeshWalls::kMaxConstraints];
    bool near = true;
    const int nc = mesh_walls->collect(xn, 1.0 * gspec.dx, 2.0 * gspec.dx, c, &near);
    mw_stamp[n] = mw_epoch;
    mw_first[n] = static_cast<int>(mw_cache.size());
    mw_count[n] = nc;
    mw_near[n] = near ? 1 : 0;
    mw_cache.insert(mw_cache.end(), c, c + nc);
  }
  return n;
}

/* False if no triangle comes within 2 cells of the node nearest to x, which then lies more than
   1.1 cells from every wall: no wall traction (reach 1 cell) and, for a point that moved less than
   half a cell (the acoustic limit), no crossing to undo. True if unsure (outside the patch). */
bool FixMpmFluid::near_mesh_wall(const double *x) {
  int c[3];
  for (int d = 0; d < 3; ++d) c[d] = static_cast<int>(std::floor((x[d] - gspec.origin[d]) / gspec.dx + 0.5));
  if (!grid.in_patch(c[0], c[1], c[2])) return true;
  return mw_near[node_walls(c[0], c[1], c[2])] != 0;
}

/* grid momentum update (8-35), velocity (8-36), boundary conditions */
void FixMpmFluid::update_grid(double h) {
  const double mmin = mass_threshold * point_mass_ref;
  grid.for_owned([&](int i, int j, int k, std::size_t n) {
    const double *g = &g_p2g[kP2g * n];
    double *gv = &g_vel[kVel * n];
    for (int c = 0; c < kVel; ++c) gv[c] = 0.0;
    // Nearly empty node at the free surface: its velocity would be a ratio
    // of two round-off-sized numbers; it carries no information.
    if (g[0] <= mmin || g[0] <= 0.0) return;
    const double inv = 1.0 / g[0];
    double vnew[3];
    for (int d = 0; d < 3; ++d) {
      gv[4 + d] = g[1 + d] * inv;
      const double f = g[4 + d] + (coupled ? g_rx[3 * n + d] : 0.0);
      // damping is implicit in time so that any rate is stable
      vnew[d] = (gv[4 + d] + h * f * inv) / (1.0 + h * damping);
    }
    apply_grid_bc(vnew, i, j, k, h);
    for (int d = 0; d < 3; ++d) gv[d] = vnew[d];
  });
  grid.forward(g_vel.data(), kVel);
}

/* grid to particles: velocity (8-37)/(8-40), affine velocity, velocity
   gradient; with MUSL also the first half of the remap (the updated point
   momentum back to the nodes), in the same pass over the points */
void FixMpmFluid::grid_to_particles(double) {
  const bool quad = shape == mpm::ShapeKind::QuadraticBSpline;
  const bool apic = transfer == TR_APIC;
  if (musl) std::fill(g_aux.begin(), g_aux.end(), 0.0);
  // The velocity gradient of the new grid velocity is the USL stress
  // update's (MUSL takes it from the remapped velocity instead) and the
  // affine field of APIC with linear shapes; B (APIC) needs the node offsets.
  if (quad) {
    if (apic)
      musl ? g2p_kernel<3, false, true, true, true>() : g2p_kernel<3, true, true, false, false>();
    else
      musl ? g2p_kernel<3, false, false, true, false>() : g2p_kernel<3, true, false, false, false>();
  } else {
    if (apic)
      musl ? g2p_kernel<2, true, false, true, true>() : g2p_kernel<2, true, false, false, false>();
    else
      musl ? g2p_kernel<2, false, false, true, false>() : g2p_kernel<2, true, false, false, false>();
  }
}

template <int NS, bool NEED_L, bool NEED_B, bool SCATTER, bool SCATTER_AFFINE>
void FixMpmFluid::g2p_kernel() {
  double **x = atom->x, **v = atom->v;
  const double *rmass = atom->rmass;
  const double *const gvel = g_vel.data();
  double *const ga = g_aux.data();
  const std::size_t sy = grid.stride_y(), sz = grid.stride_z();
  const double dinv = mpm::apic_dinv_bspline2() / (gspec.dx * gspec.dx);
  const bool flip = transfer == TR_FLIP;
  for (const int i : plist) {
    const PointShape &ps = shapes[i];
    double *s = pdata[i];
    // 4-wide accumulators (the node record is v_new (3), pad, v_old (3), pad);
    // L and B by columns: Lc[e][d] = sum v_d dS/dx_e
    mpm::Row4 vp = {0, 0, 0, 0}, dv = {0, 0, 0, 0};
    mpm::Row4 Lc[3] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}}, Bc[3] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}};
    double o[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    if (NEED_B) stencil_offsets(gspec, ps, x[i], o);
    mpm::for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double gx, double gy,
                                         double gz) {
      const mpm::Row4 un = mpm::row4(gvel + kVel * n), uo = mpm::row4(gvel + kVel * n + 4);
      vp += w * un;
      dv += w * (un - uo);
      if (NEED_L) {
        Lc[0] += gx * un;
        Lc[1] += gy * un;
        Lc[2] += gz * un;
      }
      if (NEED_B) {
        const double ox = w * o[0][a], oy = w * o[1][b], oz = w * o[2][c];
        Bc[0] += ox * un;
        Bc[1] += oy * un;
        Bc[2] += oz * un;
      }
    });
    double L[9], B[9];
    for (int d = 0; d < 3; ++d)
      for (int e = 0; e < 3; ++e) {
        L[3 * d + e] = Lc[e][d];
        B[3 * d + e] = Bc[e][d];
      }
    for (int d = 0; d < 3; ++d) vpic[3 * i + d] = vp[d];
    if (flip) {
      for (int d = 0; d < 3; ++d) v[i][d] = flip_alpha * (v[i][d] + dv[d]) + (1.0 - flip_alpha) * vp[d];
    } else {
      for (int d = 0; d < 3; ++d) v[i][d] = vp[d];
    }
    // Affine field: B D^-1 for the quadratic B-spline (exact inertia), the
    // velocity gradient for linear shape functions and for FLIP/PIC without
    // MUSL; with MUSL, FLIP/PIC store the remapped gradient there.
    if (NEED_B)
      for (int c = 0; c < 9; ++c) s[C_AFF + c] = B[c] * dinv;
    else if (NEED_L)
      for (int c = 0; c < 9; ++c) s[C_AFF + c] = L[c];
    if (!(std::isfinite(v[i][0]) && std::isfinite(v[i][1]) && std::isfinite(v[i][2]))) {
      std::ostringstream os;
      os << "Fix mpm/fluid: velocity of material point " << atom->tag[i] << " is not finite at step "
         << update->ntimestep << "; the fluid became unstable (reduce the timestep or the bulk modulus)";
      fail_one(os.str());
    }
    // velocity gradient for the stress update (USL; MUSL recomputes it)
    if (NEED_L) std::copy(L, L + 9, &velgrad[9 * static_cast<std::size_t>(i)]);
    if (SCATTER) {
      // MUSL remap, first half: the point's new momentum (with its new affine
      // field for APIC) to the same nodes
      const double m = rmass[i];
      const mpm::Row4 mv = {m * v[i][0], m * v[i][1], m * v[i][2], 0.0};
      double mC[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
      if (SCATTER_AFFINE) {
        for (int c = 0; c < 9; ++c) mC[c] = m * s[C_AFF + c];
        if (!NEED_B) stencil_offsets(gspec, ps, x[i], o);
      }
      mpm::for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double, double, double) {
        mpm::Row4 u = mv;
        if (SCATTER_AFFINE) {
          double d[3];
          affine_momentum(mC, o, a, b, c, d);
          for (int r = 0; r < 3; ++r) u[r] += d[r];
        }
        mpm::row4(ga + kAux * n) += w * u;
      });
    }
  }
}

/* MUSL (Buzzi et al. 2008, text after (8-41)): the updated point momentum,
   mapped back to the grid by grid_to_particles, gives the velocity gradient
   for the stress update, still at the positions of the start of the step. */
void FixMpmFluid::remap_velocity_musl(double h) {
  if (shape == mpm::ShapeKind::QuadraticBSpline)
    musl_kernel<3>(h);
  else
    musl_kernel<2>(h);
}

template <int NS>
void FixMpmFluid::musl_kernel(double h) {
  const std::size_t sy = grid.stride_y(), sz = grid.stride_z();
  const double *const ga = g_aux.data();
  grid.reverse_sum(g_aux.data(), kAux);
  const double mmin = mass_threshold * point_mass_ref;
  grid.for_owned([&](int i, int j, int k, std::size_t n) {
    const double m = g_p2g[kP2g * n];
    double *g = &g_aux[kAux * n];
    if (m <= mmin || m <= 0.0) {
      g[0] = g[1] = g[2] = 0.0;
      return;
    }
    const double inv = 1.0 / m;
    for (int d = 0; d < 3; ++d) g[d] *= inv;
    // the remapped velocity moves the points and gives their velocity gradient; the momentum of
    // the points is not changed here, so the wall conditions (a shear wall's stress over h too)
    // are those of the grid update
    apply_grid_bc(g, i, j, k, h);
  });
  grid.forward(g_aux.data(), kAux);
  const bool store_affine = transfer != TR_APIC;
  const bool transport = coupled && theta_transport;
  const double *const gth = transport ? g_th.data() : nullptr;
  if (transport && divthu.size() < static_cast<std::size_t>(atom->nlocal)) divthu.resize(atom->nlocal);
  for (const int i : plist) {
    const PointShape &ps = shapes[i];
    mpm::Row4 Lc[3] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}};  // Lc[e][d] = sum v_d dS/dx_e
    double dtu = 0.0;  // divergence of theta u (theta_transport)
    mpm::for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double, double gx, double gy, double gz) {
      const mpm::Row4 u = mpm::row4(ga + kAux * n);
      Lc[0] += gx * u;
      Lc[1] += gy * u;
      Lc[2] += gz * u;
      if (transport) dtu += gth[n] * (gx * u[0] + gy * u[1] + gz * u[2]);
    });
    if (transport) divthu[i] = dtu;
    double L[9];
    for (int d = 0; d < 3; ++d)
      for (int e = 0; e < 3; ++e) L[3 * d + e] = Lc[e][d];
    std::copy(L, L + 9, &velgrad[9 * static_cast<std::size_t>(i)]);
    if (store_affine) std::copy(L, L + 9, pdata[i] + C_AFF);
  }
}

/* Continuity (7-21) as a volume update, equation of state (7-23) or Tait,
   Navier-Poisson (7-24). Anti-locking: the dilatation rate is averaged over
   each grid cell and the cell's pressure follows from the cell's mean
   density, so all points of a cell carry one pressure (Mast et al. 2012). */
void FixMpmFluid::update_stress(double h, bool theta_only) {
  const int nlocal = atom->nlocal;
  double **x = atom->x;
  double *rmass = atom->rmass;
  const double inv = 1.0 / gspec.dx;
  // theta_transport: the fluid volume theta V changes by h V div(theta u) (grid operators), so
  // that flow through a fixed irregular bed keeps it; else theta stays, V changes by h V div u
  const bool transport = coupled && theta_transport && theta_initialized && !theta_only;
  auto cell_node = [&](int i) {
    int c[3];
    for (int d = 0; d < 3; ++d) c[d] = static_cast<int>(std::floor((x[i][d] - gspec.origin[d]) * inv));
    for (int d = 0; d < 3; ++d)
      if (!gspec.periodic[d]) c[d] = std::min(std::max(c[d], 0), gspec.ncell[d] - 1);
    return grid.index(c[0], c[1], c[2]);
  };
  if (antilock) {
    std::fill(g_cell.begin(), g_cell.end(), 0.0);
    for (int i = 0; i < nlocal; ++i) {
      if (!is_point(i)) continue;
      const double *s = pdata[i];
      double *c = &g_cell[kCell * cell_node(i)];
      const double V = s[C_VOL];
      c[0] += V;
      if (!theta_only) {
        const double *L = &velgrad[9 * static_cast<std::size_t>(i)];
        c[1] += V * (L[0] + L[4] + L[8]);
        if (transport) c[4] += V * divthu[i];
      }
      c[2] += s[C_THETA] * V;
      c[3] += rmass[i];
    }
    grid.reverse_sum(g_cell.data(), kCell);
    grid.forward(g_cell.data(), kCell);
  }
  for (int i = 0; i < nlocal; ++i) {
    if (!is_point(i)) continue;
    double *s = pdata[i];
    // theta_only: the fluid fraction changed, the volume did not (velgrad
    // belongs to the last step's atom order then and is not read)
    const double *L = theta_only ? nullptr : &velgrad[9 * static_cast<std::size_t>(i)];
    double div = theta_only ? 0.0 : L[0] + L[4] + L[8];
    double p;
    double fgrow = transport ? 1.0 + h * divthu[i] / s[C_THETA] : 1.0;  // growth of theta V
    if (antilock) {
      const double *c = &g_cell[kCell * cell_node(i)];
      div = c[1] / c[0];
      if (transport) fgrow = 1.0 + h * c[4] / c[2];
      const double rho_cell = transport ? c[3] / (c[2] * fgrow) : c[3] / (c[2] * (1.0 + h * div));
      p = eos.pressure(rho_cell);
    }
    const double J = 1.0 + h * div;
    s[C_VOL] *= J;
    if (transport) s[C_THETA] = std::min(1.0, std::max(theta_min, s[C_THETA] * fgrow / J));
    s[C_RHO] = rmass[i] / (s[C_THETA] * s[C_VOL]);
    if (!antilock) p = eos.pressure(s[C_RHO]);
    // Liquid cannot carry tension beyond its cavitation pressure: without the
    // cut a stretched surface layer would hold itself together (and to walls).
    p = std::max(p, pmin);
    if (!(J > 0.0) || !std::isfinite(p)) {
      std::ostringstream os;
      os << "Fix mpm/fluid: material point " << atom->tag[i] << " was compressed to a non-positive volume at step "
         << update->ntimestep << "; the fluid became unstable (reduce the timestep)";
      fail_one(os.str());
    }
    s[C_P] = p;
    if (theta_only) continue;
    const double Lm[3][3] = {{L[0], L[1], L[2]}, {L[3], L[4], L[5]}, {L[6], L[7], L[8]}};
    mpm::newtonian_deviatoric_stress(viscosity, Lm, s + C_TAU);
  }
}

/* position update (8-41) with the grid velocity; a point that crossed a wall
   (or the closed gate) by less than a cell is put back on the fluid side */
void FixMpmFluid::advance_positions(double h) {
  const int nlocal = atom->nlocal;
  double **x = atom->x, **v = atom->v;
  const double eps = 1e-6 * gspec.dx;
  for (int i = 0; i < nlocal; ++i) {
    if (!is_point(i)) continue;
    const double xold[3] = {x[i][0], x[i][1], x[i][2]};
    for (int d = 0; d < 3; ++d) x[i][d] += h * vpic[3 * i + d];
    if (mesh_walls && near_mesh_wall(x[i]) && mesh_walls->push_back(x[i], v[i], 1.0 * gspec.dx, xold))
      n_clamped += 1.0;
    for (int d = 0; d < 3; ++d) {
      if (gspec.periodic[d]) continue;
      const double lo = gspec.origin[d], hi = gspec.upper(d);
      if (x[i][d] < lo || x[i][d] > hi) {
        if (x[i][d] < lo - gspec.dx || x[i][d] > hi + gspec.dx) continue;  // compute_shapes reports it
        x[i][d] = x[i][d] < lo ? lo + eps : hi - eps;
        v[i][d] = 0.0;
        n_clamped += 1.0;
      }
    }
    if (gate.active) {
      const int d = gate.dim;
      if (gate.fluid_below && x[i][d] > gate.pos) {
        x[i][d] = gate.pos - eps;
        v[i][d] = std::min(v[i][d], 0.0);
        n_clamped += 1.0;
      } else if (!gate.fluid_below && x[i][d] < gate.pos) {
        x[i][d] = gate.pos + eps;
        v[i][d] = std::max(v[i][d], 0.0);
        n_clamped += 1.0;
      }
    }
  }
}

/* ----------------------------------------------------------------------
   global outputs f_ID[1..10]
------------------------------------------------------------------------- */

void FixMpmFluid::compute_outputs() {
  const int nlocal = atom->nlocal;
  double **x = atom->x, **v = atom->v;
  double *rmass = atom->rmass;
  double sum[4] = {0, 0, 0, n_clamped};  // mass, kinetic energy, points, clamped
  // |v|max, front, height, p max, wall time of the fluid and of the coupling (slowest rank)
  double mx[6] = {0.0, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL, time_fluid, time_couple};
  for (int i = 0; i < nlocal; ++i) {
    if (!is_point(i)) continue;
    const double v2 = v[i][0] * v[i][0] + v[i][1] * v[i][1] + v[i][2] * v[i][2];
    sum[0] += rmass[i];
    sum[1] += 0.5 * rmass[i] * v2;
    sum[2] += 1.0;
    mx[0] = std::max(mx[0], std::sqrt(v2));
    mx[1] = std::max(mx[1], x[i][front_axis] + 0.5 * spacing[front_axis]);
    if (std::fabs(x[i][wall_axis] - wall_pos) < gspec.dx)
      mx[2] = std::max(mx[2], x[i][height_axis] + 0.5 * spacing[height_axis]);
    mx[3] = std::max(mx[3], pdata[i][C_P]);
  }
  double fg[3] = {0, 0, 0}, gfg[3];
  if (coupled)
    for (int k = 0; k < nlocal; ++k)
      if (is_grain(k))
        for (int d = 0; d < 3; ++d) fg[d] += pdata[k][C_FGRAIN + d];
  MPI_Allreduce(fg, gfg, 3, MPI_DOUBLE, MPI_SUM, world);
  for (int d = 0; d < 3; ++d) vector_cache[10 + d] = gfg[d];
  double gsum[4], gmx[6];
  MPI_Allreduce(sum, gsum, 4, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(mx, gmx, 6, MPI_DOUBLE, MPI_MAX, world);
  vector_cache[0] = gsum[0];
  vector_cache[1] = gsum[1];
  vector_cache[2] = gmx[0];
  vector_cache[3] = std::isfinite(gmx[1]) ? gmx[1] : 0.0;
  vector_cache[4] = std::isfinite(gmx[2]) ? gmx[2] - gspec.origin[height_axis] : 0.0;
  vector_cache[5] = nsub_last;
  vector_cache[6] = std::min(dt_stable_last, dt_couple_last);
  vector_cache[7] = gsum[3];
  vector_cache[8] = gsum[2];
  vector_cache[9] = std::isfinite(gmx[3]) ? gmx[3] : 0.0;
  vector_cache[13] = gmx[4];
  vector_cache[14] = gmx[5];
  vector_step = update->ntimestep;
}

double FixMpmFluid::compute_vector(int n) {
  if (n < 0 || n >= size_vector) return 0.0;
  if (vector_step != update->ntimestep) compute_outputs();
  return vector_cache[n];
}

int FixMpmFluid::modify_param(int narg, char **arg) {
  if (strcmp(arg[0], "gate") == 0) {
    if (narg < 2 || strcmp(arg[1], "off") != 0) bad_arg("fix_modify gate", "'off'", narg < 2 ? nullptr : arg[1]);
    gate.active = false;
    return 2;
  }
  if (bool FixMpmFluid::*flag = find_flag(arg[0])) {
    if (narg < 2 || !parse_yesno(arg[1], this->*flag)) bad_arg(arg[0], "'yes' or 'no'", narg < 2 ? nullptr : arg[1]);
    return 2;
  }
  if (strcmp(arg[0], "damping") == 0 || strcmp(arg[0], "cfl") == 0) {
    const ScalarKeyword *sk = find_scalar(arg[0]);
    if (narg < 2) bad_arg(arg[0], sk->expected, nullptr);
    parse_scalar(*sk, arg[1]);
    return 2;
  }
  if (strcmp(arg[0], "boundary") == 0) {
    if (narg < 3) bad_arg("fix_modify boundary", "a face and 'noslip', 'freeslip', 'partial f' or 'shear delta'", nullptr);
    int iarg = 0;  // arg[0] is the keyword, as in the fix command
    parse_face(arg[1], arg[2], narg, arg, iarg);
    return iarg;
  }
  return 0;
}

/* ----------------------------------------------------------------------
   output: points (and grid) to HDF5 + XDMF, gathered on rank 0
------------------------------------------------------------------------- */

void FixMpmFluid::end_of_step() {
  if (out_every > 0 && update->ntimestep % out_every == 0) write_output();
}

void FixMpmFluid::write_output() {
  if (last_output_step == update->ntimestep) return;
  last_output_step = update->ntimestep;

  struct Spec { std::string name; int ncomp; };
  std::vector<Spec> fields;
  for (const auto &f : out_point_fields) {
    int nc = 1;
    if (f == "v") nc = 3;
    else if (f == "tau") nc = 6;
    else if (f == "affine") nc = 9;
    fields.push_back({f, nc});
  }
  int stride = 3;
  for (const auto &f : fields) stride += f.ncomp;

  std::vector<double> buf;
  const int nlocal = atom->nlocal;
  for (int i = 0; i < nlocal; ++i) {
    if (!is_point(i)) continue;
    const double *s = pdata[i];
    for (int d = 0; d < 3; ++d) buf.push_back(atom->x[i][d]);
    for (const auto &f : fields) {
      if (f.name == "v") for (int d = 0; d < 3; ++d) buf.push_back(atom->v[i][d]);
      else if (f.name == "p") buf.push_back(s[C_P]);
      else if (f.name == "rho") buf.push_back(s[C_RHO]);
      else if (f.name == "vol") buf.push_back(s[C_VOL]);
      else if (f.name == "tau") for (int c = 0; c < 6; ++c) buf.push_back(s[C_TAU + c]);
      else if (f.name == "theta") buf.push_back(s[C_THETA]);
      else if (f.name == "id") buf.push_back(static_cast<double>(atom->tag[i]));
      else if (f.name == "type") buf.push_back(static_cast<double>(atom->type[i]));
      else if (f.name == "affine") for (int c = 0; c < 9; ++c) buf.push_back(s[C_AFF + c]);
      else if (f.name == "mass") buf.push_back(atom->rmass[i]);
    }
  }
  int nmine = static_cast<int>(buf.size());
  std::vector<int> counts(comm->nprocs), displs(comm->nprocs, 0);
  MPI_Gather(&nmine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, world);
  std::vector<double> all;
  if (comm->me == 0) {
    for (int q = 1; q < comm->nprocs; ++q) displs[q] = displs[q - 1] + counts[q - 1];
    all.resize(displs.back() + counts.back());
  }
  MPI_Gatherv(buf.data(), nmine, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0, world);

  // Grid: owned real nodes (not the padding) as (global index, values).
  mpm::GridBlock gb;
  std::vector<double> gall;
  const bool want_grid = !out_grid_fields.empty();
  int gstride = 1;
  for (const auto &f : out_grid_fields) gstride += (f == "v") ? 3 : 1;
  if (want_grid) {
    std::vector<double> gbuf;
    int nn[3];
    for (int d = 0; d < 3; ++d) nn[d] = gspec.periodic[d] ? gspec.ncell[d] : gspec.ncell[d] + 1;
    const mpm::IndexBox &ob = grid.owned();
    for (int k = std::max(ob.lo[2], 0); k <= std::min(ob.hi[2], nn[2] - 1); ++k)
      for (int j = std::max(ob.lo[1], 0); j <= std::min(ob.hi[1], nn[1] - 1); ++j)
        for (int i = std::max(ob.lo[0], 0); i <= std::min(ob.hi[0], nn[0] - 1); ++i) {
          const std::size_t n = grid.index(i, j, k);
          gbuf.push_back(static_cast<double>((static_cast<long>(k) * nn[1] + j) * nn[0] + i));
          for (const auto &f : out_grid_fields) {
            if (f == "mass") gbuf.push_back(g_p2g[kP2g * n]);
            else for (int d = 0; d < 3; ++d) gbuf.push_back(g_vel[kVel * n + d]);
          }
        }
    int gm = static_cast<int>(gbuf.size());
    std::vector<int> gc(comm->nprocs), gd(comm->nprocs, 0);
    MPI_Gather(&gm, 1, MPI_INT, gc.data(), 1, MPI_INT, 0, world);
    if (comm->me == 0) {
      for (int q = 1; q < comm->nprocs; ++q) gd[q] = gd[q - 1] + gc[q - 1];
      gall.resize(gd.back() + gc.back());
    }
    MPI_Gatherv(gbuf.data(), gm, MPI_DOUBLE, gall.data(), gc.data(), gd.data(), MPI_DOUBLE, 0, world);
    for (int d = 0; d < 3; ++d) {
      gb.n[d] = nn[d];
      gb.origin[d] = gspec.origin[d];
      gb.spacing[d] = gspec.dx;
    }
  }

  if (comm->me != 0) return;
  mpm::PointBlock pb;
  pb.n = all.size() / stride;
  pb.xyz.resize(3 * pb.n);
  for (const auto &f : fields) pb.fields.push_back({f.name, f.ncomp, std::vector<double>(pb.n * f.ncomp)});
  for (std::size_t p = 0; p < pb.n; ++p) {
    const double *r = &all[p * stride];
    for (int d = 0; d < 3; ++d) pb.xyz[3 * p + d] = r[d];
    int off = 3;
    for (std::size_t fi = 0; fi < fields.size(); ++fi) {
      for (int c = 0; c < fields[fi].ncomp; ++c) pb.fields[fi].data[p * fields[fi].ncomp + c] = r[off + c];
      off += fields[fi].ncomp;
    }
  }
  if (want_grid) {
    const std::size_t nn = std::size_t(gb.n[0]) * gb.n[1] * gb.n[2];
    for (const auto &f : out_grid_fields) gb.fields.push_back({f, f == "v" ? 3 : 1, std::vector<double>(nn * (f == "v" ? 3 : 1), 0.0)});
    for (std::size_t r = 0; r + gstride <= gall.size(); r += gstride) {
      const std::size_t n = static_cast<std::size_t>(gall[r]);
      int off = 1;
      for (auto &fl : gb.fields) {
        for (int c = 0; c < fl.ncomp; ++c) fl.data[n * fl.ncomp + c] = gall[r + off + c];
        off += fl.ncomp;
      }
    }
  }
  try {
    if (!series) series.reset(new mpm::Hdf5Series(out_prefix));
    series->write_step(static_cast<long>(update->ntimestep), sim_time(), pb, want_grid ? &gb : nullptr);
  } catch (const std::exception &e) {
    std::string msg = std::string("Fix mpm/fluid: keyword 'output': ") + e.what();
    fail_one(msg);
  }
}

/* ----------------------------------------------------------------------
   per-point state: LIGGGHTS calls these when atoms grow, move between
   ranks or go to/come from a restart file
------------------------------------------------------------------------- */

void FixMpmFluid::grow_arrays(int nmax) {
  memory->grow(pdata, nmax, NCOL, "mpm/fluid:pdata");
  for (int i = pdata_rows; i < nmax; ++i) std::fill(pdata[i], pdata[i] + NCOL, 0.0);
  pdata_rows = std::max(pdata_rows, nmax);
  array_atom = pdata;
}

void FixMpmFluid::copy_arrays(int i, int j, int) {
  std::copy(pdata[i], pdata[i] + NCOL, pdata[j]);
}

void FixMpmFluid::set_arrays(int i) { std::fill(pdata[i], pdata[i] + NCOL, 0.0); }

int FixMpmFluid::pack_exchange(int i, double *buf) {
  std::copy(pdata[i], pdata[i] + NCOL, buf);
  return NCOL;
}

int FixMpmFluid::unpack_exchange(int nlocal, double *buf) {
  std::copy(buf, buf + NCOL, pdata[nlocal]);
  return NCOL;
}

int FixMpmFluid::pack_restart(int i, double *buf) {
  buf[0] = NCOL + 1;
  std::copy(pdata[i], pdata[i] + NCOL, buf + 1);
  return NCOL + 1;
}

void FixMpmFluid::unpack_restart(int nlocal, int nth) {
  double **extra = atom->extra;
  int m = 0;
  for (int i = 0; i < nth; ++i) m += static_cast<int>(extra[nlocal][m]);
  std::copy(&extra[nlocal][m + 1], &extra[nlocal][m + 1] + NCOL, pdata[nlocal]);
}

int FixMpmFluid::size_restart(int) { return NCOL + 1; }
int FixMpmFluid::maxsize_restart() { return NCOL + 1; }

namespace {
enum { R_FILLED, R_PMASS, R_SP0, R_SP1, R_SP2, R_CLAMPED, R_GATE, R_NSUB, R_THETA, R_COUNT };
}

void FixMpmFluid::write_restart(FILE *fp) {
  double list[R_COUNT];
  list[R_FILLED] = filled ? 1.0 : 0.0;
  list[R_PMASS] = point_mass_ref;
  for (int d = 0; d < 3; ++d) list[R_SP0 + d] = spacing[d];
  list[R_CLAMPED] = n_clamped;
  list[R_GATE] = gate.active ? 1.0 : 0.0;
  list[R_NSUB] = nsub_last;
  list[R_THETA] = theta_initialized ? 1.0 : 0.0;
  if (comm->me == 0) {
    int size = R_COUNT * sizeof(double);
    fwrite(&size, sizeof(int), 1, fp);
    fwrite(list, sizeof(double), R_COUNT, fp);
  }
}

void FixMpmFluid::restart(char *buf) {
  const double *list = reinterpret_cast<const double *>(buf);
  filled = list[R_FILLED] != 0.0;
  point_mass_ref = list[R_PMASS];
  for (int d = 0; d < 3; ++d) spacing[d] = list[R_SP0 + d];
  n_clamped = list[R_CLAMPED];
  // a gate removed before the restart stays removed
  if (list[R_GATE] == 0.0) gate.active = false;
  nsub_last = static_cast<int>(list[R_NSUB]);
  theta_initialized = list[R_THETA] != 0.0;
}

double FixMpmFluid::memory_usage() {
  double bytes = static_cast<double>(atom->nmax) * NCOL * sizeof(double);
  bytes += (g_p2g.size() + g_vel.size() + g_cell.size() + g_aux.size()) * sizeof(double);
  bytes += shapes.size() * sizeof(PointShape) + (vpic.size() + velgrad.size()) * sizeof(double);
  return bytes;
}
