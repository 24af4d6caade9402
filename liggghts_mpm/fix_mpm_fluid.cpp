/* fix mpm/fluid: the LIGGGHTS adapter of mpm::FluidSolver (see fix_mpm_fluid.h, docs/design.md).
   The fluid's step, phase by phase, is FluidSolver::substep (mpm/solver.cpp). */

#include "fix_mpm_fluid.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "atom.h"
#include "atom_vec.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "fix_property_atom.h"
#include "group.h"
#include "memory.h"
#include "modify.h"
#include "neighbor.h"
#include "region.h"
#include "update.h"

#include "mpm/error.h"

using namespace LAMMPS_NS;
using namespace FixConst;
using mpm::NCOL;

/* ---------------------------------------------------------------------- */

FixMpmFluid::FixMpmFluid(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg) {
  if (domain->triclinic) error->all(FLERR, "Fix mpm/fluid requires an orthogonal simulation box");
  if (!atom->rmass_flag || !atom->radius_flag)
    error->all(FLERR, "Fix mpm/fluid requires atom_style sphere (per-atom mass and radius)");

  mpm::ParseEnv env;
  env.ntypes = atom->ntypes;
  env.dimension = domain->dimension;
  for (int d = 0; d < 3; ++d) {
    env.boxlo[d] = domain->boxlo[d];
    env.boxhi[d] = domain->boxhi[d];
    env.periodic[d] = domain->periodicity[d] != 0;
  }
  env.group_exists = [this](const char *name) { return group->find(name) >= 0; };
  env.mesh_wall = [this](int n, char **a, int i) { return parse_mesh_wall(n, a, i); };
  guarded([&] { solver.reset(new mpm::FluidSolver(mpm::parse_options(narg, arg, env), world)); });

  restart_global = 1;
  restart_peratom = 1;
  // no create_attribute: LIGGGHTS would call set_arrays() for every atom at
  // the first setup and wipe the points' state; new rows are zeroed in grow_arrays
  time_integrate = 1;  // the fix moves its material points itself
  vector_flag = 1;
  size_vector = mpm::FluidSolver::kGlobalSize;
  global_freq = 1;
  extvector = 0;
  peratom_flag = 1;
  size_peratom_cols = NCOL;
  peratom_freq = 1;
  nevery = solver->opt.out_every > 0 ? solver->opt.out_every : 1;

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
  if (solver->opt.out_every > 0) mask |= END_OF_STEP;
  return mask;
}

/* The solver's errors: mpm::Error is found by every rank (error->all); mpm::LocalError by one,
   which cannot wait for the others. error->one aborts without flushing stdio, so the message would
   be lost when the screen is a pipe or a file: print and flush first, then abort. */
template <class Fn>
void FixMpmFluid::guarded(Fn &&fn) {
  try {
    fn();
  } catch (const mpm::LocalError &e) {
    fail_one(e.what());
  } catch (const mpm::Error &e) {
    error->all(FLERR, e.what());
  } catch (const std::bad_alloc &) {
    fail_one("Fix mpm/fluid: out of memory on this rank (grid or points too large for the machine: a larger 'cell' or "
             "fewer points per cell)");
  }
}

void FixMpmFluid::fail_one(const std::string &msg) {
  for (FILE *f : {screen, logfile})
    if (f) {
      fprintf(f, "ERROR on proc %d: %s\n", comm->me, msg.c_str());
      fflush(f);
    }
  MPI_Abort(world, 1);
  std::abort();
}

void FixMpmFluid::print(const std::string &text) const {
  if (comm->me != 0) return;
  if (screen) fputs(text.c_str(), screen);
  if (logfile) fputs(text.c_str(), logfile);
}

bool FixMpmFluid::is_point(int i) const { return (atom->mask[i] & groupbit) != 0; }

double FixMpmFluid::sim_time() const {
  return time_offset + update->atime + (update->ntimestep - update->atimestep) * update->dt;
}

mpm::FluidSolver &FixMpmFluid::sync() {
  mpm::Points &p = solver->pts;
  p.nlocal = atom->nlocal;
  p.x = atom->x;
  p.v = atom->v;
  p.f = atom->f;
  p.rmass = atom->rmass;
  p.radius = atom->radius;
  p.mask = atom->mask;
  p.tag = atom->tag;
  p.type = atom->type;
  p.state = pdata;
  p.point_bit = groupbit;
  p.grain_bit = couple_groupbit;
  solver->clock.step = static_cast<long>(update->ntimestep);
  solver->clock.time = sim_time();
  solver->clock.dt = update->dt;
  return *solver;
}

/* mesh_wall fix-ID kind [value] [side s] (the meshes are LIGGGHTS fixes; docs/mesh_walls.md) */
int FixMpmFluid::parse_mesh_wall(int narg, char **arg, int iarg) {
  using mpm::bad_arg;
  using mpm::parse_double;
  const mpm::Args a{narg, arg, iarg};
  a.need(2, "mesh_wall", "a fix ID and noslip | freeslip | partial f | sticky f | shear delta f");
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
    if (iarg >= narg) bad_arg(kwname, "a sticky fraction", nullptr);
    ms.kind = sticky_kind ? mpm::WALL_STICKY : mpm::WALL_PARTIAL;
    if (!parse_double(arg[iarg], ms.sticky)) bad_arg(kwname, "a sticky fraction in [0,1]", arg[iarg]);
    ++iarg;
  } else if (strcmp(k, "shear") == 0) {
    // wall shear stress mu (f w_t - v_t) / delta: an unresolved viscous layer of thickness delta
    if (iarg + 1 >= narg)
      bad_arg("mesh_wall shear", "a wall layer thickness delta (length) and a fraction f in [0,1]", nullptr);
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
  return iarg;
}

/* ---------------------------------------------------------------------- */

void FixMpmFluid::post_create() {
  // After a read_restart the points exist already (recent_restart is set
  // when our global state came from the restart file).
  if (!recent_restart && !solver->opt.fill_region.empty()) fill_points();
  if (!recent_restart) point_type = solver->opt.fill_type;
  exclude_points_from_pairs();
  // The fluid force on each grain as the per-atom vector 'dragforce', the
  // property/atom convention of LIGGGHTS/CFDEM (reused if the input made it).
  if (solver->opt.coupled) {
    const char *args[] = {"dragforce", "all", "property/atom", "dragforce", "vector", "yes", "no", "no",
                          "0", "0", "0"};
    fix_dragforce = static_cast<FixPropertyAtom *>(
        modify->find_fix_property("dragforce", "property/atom", "vector", 3, 0, style, false));
    if (!fix_dragforce) fix_dragforce = modify->add_fix_property_atom(11, const_cast<char **>(args), style);
  }
}

/* The material points are the fluid, not grains: no pair style may act on them (a granular pair
   style would make a water column pile up like sand). Same as the input lines 'neigh_modify
   exclude type T t' for every type t; lines the input already has only repeat an exclusion. */
void FixMpmFluid::exclude_points_from_pairs() {
  if (point_type < 1 || point_type > atom->ntypes) return;
  const std::string T = std::to_string(point_type);
  for (int t = 1; t <= atom->ntypes; ++t) {
    const std::string ts = std::to_string(t);
    char *args[4] = {const_cast<char *>("exclude"), const_cast<char *>("type"), const_cast<char *>(T.c_str()),
                     const_cast<char *>(ts.c_str())};
    neighbor->modify_params(4, args);
  }
  print("fix mpm/fluid: material points (type " + T + ") excluded from pair interactions (neigh_modify exclude type " +
        T + " 1.." + std::to_string(atom->ntypes) + ")\n");
}

/* Before creating the points: an upper estimate of their number (the cells of the grid within the
   region's bounding box, times the points per cell) against half of the machine's physical memory,
   so that 'cell 0.002' in a 1 m box stops with a message instead of dying in the allocator. */
void FixMpmFluid::check_fill_memory(Region *region, const int lo[3], const int hi[3]) {
  const mpm::Options &o = solver->opt;
  const mpm::GridSpec &gs = o.grid;
  double ncells = 1.0;
  for (int d = 0; d < 3; ++d) {
    double a = lo[d], b = hi[d];
    if (region->bboxflag) {
      const double ext[2][3] = {{region->extent_xlo, region->extent_ylo, region->extent_zlo},
                                {region->extent_xhi, region->extent_yhi, region->extent_zhi}};
      a = std::max(a, std::floor((ext[0][d] - gs.origin[d]) / gs.dx));
      b = std::min(b, std::floor((ext[1][d] - gs.origin[d]) / gs.dx));
    }
    ncells *= std::max(0.0, b - a + 1.0);
  }
  double npts = ncells * o.fill_ppc[0] * o.fill_ppc[1] * o.fill_ppc[2], total = 0.0;
  MPI_Allreduce(&npts, &total, 1, MPI_DOUBLE, MPI_SUM, world);
  // bytes per point: LIGGGHTS' per-atom arrays (sphere style, neighbour bins) and the fix's state
  // and shape records, about 1 kB; the ranks of one node share its memory
  const double per_point = 1024.0;
  const double mem = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGESIZE));
  if (mem > 0.0 && total * per_point > 0.5 * mem) {
    std::ostringstream os;
    os.precision(3);
    os << "Fix mpm/fluid: keyword 'fill' would create up to " << total << " material points (keyword 'cell' " << gs.dx
       << ", " << o.fill_ppc[0] << "x" << o.fill_ppc[1] << "x" << o.fill_ppc[2] << " per cell), about "
       << total * per_point / 1e9 << " GB, more than half of this machine's " << mem / 1e9
       << " GB; use a larger cell or fewer points per cell";
    error->all(FLERR, os.str().c_str());
  }
}

void FixMpmFluid::fill_points() {
  const mpm::Options &o = solver->opt;
  const mpm::GridSpec &gs = o.grid;
  // checked here, not at parse time: after read_restart no region is needed
  const int iregion = domain->find_region(o.fill_region.c_str());
  if (iregion < 0) guarded([&] { mpm::bad_arg("fill", "an existing region ID", o.fill_region.c_str()); });
  Region *region = domain->regions[iregion];
  const double dx = gs.dx;
  double *spacing = solver->state.spacing;
  double vol = dx * dx * dx;
  for (int d = 0; d < 3; ++d) {
    spacing[d] = dx / o.fill_ppc[d];
    vol /= o.fill_ppc[d];
  }
  const int nlocal_before = atom->nlocal;
  int lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::max(0, static_cast<int>(std::floor((domain->sublo[d] - gs.origin[d]) / dx)) - 1);
    hi[d] = std::min(gs.ncell[d] - 1, static_cast<int>(std::floor((domain->subhi[d] - gs.origin[d]) / dx)) + 1);
  }
  check_fill_memory(region, lo, hi);
  double x[3];
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i)
        for (int c = 0; c < o.fill_ppc[2]; ++c)
          for (int b = 0; b < o.fill_ppc[1]; ++b)
            for (int a = 0; a < o.fill_ppc[0]; ++a) {
              const int cell[3] = {i, j, k}, sub[3] = {a, b, c};
              for (int d = 0; d < 3; ++d) x[d] = gs.origin[d] + cell[d] * dx + (sub[d] + 0.5) * spacing[d];
              if (!region->match(x[0], x[1], x[2])) continue;
              bool mine = true;
              for (int d = 0; d < 3; ++d) mine = mine && x[d] >= domain->sublo[d] && x[d] < domain->subhi[d];
              if (!mine) continue;
              atom->avec->create_atom(o.fill_type, x);
              const int n = atom->nlocal - 1;
              for (int m = 0; m < modify->nfix; ++m) {
                Fix *f = modify->fix[m];
                if (f && f->create_attribute && f != this) {
                  f->pre_set_arrays();
                  f->set_arrays(n);
                }
              }
              atom->mask[n] |= groupbit;
              atom->v[n][0] = atom->v[n][1] = atom->v[n][2] = 0.0;
              atom->rmass[n] = solver->init_point(x, vol, pdata[n]);
              atom->radius[n] = 0.5 * std::min(spacing[0], std::min(spacing[1], spacing[2]));
              if (atom->density_flag && atom->density) atom->density[n] = o.eos.rho0;
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
  solver->state.point_mass_ref = o.eos.rho0 * vol;
  filled = true;
  std::ostringstream os;
  os << "fix mpm/fluid: created " << nall << " material points (" << o.fill_ppc[0] << "x" << o.fill_ppc[1] << "x"
     << o.fill_ppc[2] << " per cell of " << gs.dx << "), grid " << gs.ncell[0] << "x" << gs.ncell[1] << "x"
     << gs.ncell[2] << " cells\n";
  print(os.str());
}

/* ---------------------------------------------------------------------- */

void FixMpmFluid::init() {
  const mpm::Options &o = solver->opt;
  if (!filled) error->all(FLERR, "Fix mpm/fluid: no material points; use keyword 'fill region-ID nx ny nz type T'");
  check_group_atoms();
  // Material points must not be integrated twice.
  int integrated = 0;  // groups moved by some other integrator: the coupled grains not in them are fixed
  for (int m = 0; m < modify->nfix; ++m) {
    Fix *f = modify->fix[m];
    if (f == this || !f->time_integrate) continue;
    integrated |= f->groupbit;
    int clash = 0, any = 0;
    for (int i = 0; i < atom->nlocal; ++i)
      if (is_point(i) && (atom->mask[i] & f->groupbit)) clash = 1;
    MPI_Allreduce(&clash, &any, 1, MPI_INT, MPI_MAX, world);
    if (any) {
      std::string msg = std::string("Fix mpm/fluid: fix ") + f->id + " (" + f->style +
                        ") also integrates material points; restrict it to the grain group";
      error->all(FLERR, msg.c_str());
    }
  }
  if (o.coupled) {
    const int ig = group->find(o.couple_group.c_str());
    if (ig < 0) guarded([&] { mpm::bad_arg("couple", "an existing group-ID of the DEM grains", o.couple_group.c_str()); });
    couple_groupbit = group->bitmask[ig];
  }
  mpm::FluidSolver &s = sync();
  s.pts.integrated_bits = integrated;
  std::string warning;
  guarded([&] { warning = s.check_points(); });
  if (!warning.empty() && comm->me == 0) error->warning(FLERR, warning.c_str());
  vector_step = -1;
}

/* The fix's group holds its material points only, and no other atom has their type (the
   exclusion from the pair styles is by type). Checked before the integrators, so that grains in
   the group are named as such, not as atoms some integrator also moves. */
void FixMpmFluid::check_group_atoms() {
  bigint loc[3] = {0, 0, 0}, glob[3];  // group atoms of other types; of the points' type without state; type shared
  for (int i = 0; i < atom->nlocal; ++i) {
    const bool same_type = atom->type[i] == point_type;
    if (is_point(i)) {
      if (pdata[i][mpm::C_FLAG] != 1.0) ++loc[same_type ? 1 : 0];
    } else if (same_type)
      ++loc[2];
  }
  MPI_Allreduce(loc, glob, 3, MPI_LMP_BIGINT, MPI_SUM, world);
  const std::string G = std::string("group '") + group->names[igroup] + "'";
  const std::string T = std::to_string(point_type);
  std::ostringstream os;
  if (glob[0] > 0)
    os << "Fix mpm/fluid: " << G << " of the fix holds " << glob[0] << " atoms of other types than the material points' type "
       << T << " (grains?); give the fix a group of the fill type only (e.g. 'group fluid type " << T << "')";
  else if (glob[1] > 0)
    os << "Fix mpm/fluid: " << glob[1] << " atoms of " << G << " have the material points' type " << T
       << " but no state of this fix (ID '" << id << "'): the restart file is truncated or was written without this fix "
       << "(or with another fix ID), or another command created atoms of type " << T;
  else if (glob[2] > 0)
    os << "Fix mpm/fluid: " << glob[2] << " atoms of type " << T << " are outside " << G
       << " of the fix: grains must not share the type of the material points (give them another atom type)";
  if (!os.str().empty()) error->all(FLERR, os.str().c_str());
}

// the mesh walls' triangles near this rank's grid patch, after the meshes moved
void FixMpmFluid::refresh_walls() {
  if (!mesh_walls) return;
  const mpm::GridSpec &gs = solver->opt.grid;
  const mpm::IndexBox &pb = solver->patch();
  double lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = gs.origin[d] + pb.lo[d] * gs.dx;
    hi[d] = gs.origin[d] + pb.hi[d] * gs.dx;
  }
  try {
    mesh_walls->refresh(lo, hi, 2.0 * gs.dx);
  } catch (const std::exception &e) {
    error->all(FLERR, e.what());
  }
  solver->bc.walls_moved();
}

void FixMpmFluid::setup(int) {
  mpm::FluidSolver &s = sync();
  s.setup_grid(domain->sublo, domain->subhi, neighbor->skin);
  if (!mesh_specs.empty()) {
    try {
      std::vector<mpm::MeshWallSpec> sp = mesh_specs;  // sides found in an earlier run are kept
      if (mesh_walls) for (size_t k = 0; k < sp.size(); ++k) sp[k].side = mesh_walls->side(k);
      mesh_walls.reset(new mpm::MeshWalls(lmp, sp));
      mesh_walls->set_kinematic_viscosity(s.opt.viscosity / s.opt.eos.rho0);
      s.bc.set_walls(&mesh_walls->geometry());
    } catch (const std::exception &e) {
      error->all(FLERR, (std::string("Fix mpm/fluid: ") + e.what()).c_str());
    }
    refresh_walls();
    std::vector<const double *> pts;
    for (int i = 0; i < atom->nlocal; ++i) if (is_point(i)) pts.push_back(atom->x[i]);
    try {
      print(mesh_walls->infer_sides(pts.data(), (int)pts.size(), 1.0 * s.opt.grid.dx));
    } catch (const std::exception &e) {
      error->all(FLERR, (std::string("Fix mpm/fluid: ") + e.what()).c_str());
    }
  }
  guarded([&] {
    s.setup_coupling();
    print(s.check_timestep(true));
  });
  // LIGGGHTS recomputed the grains' forces for this run; the fluid force of the last fluid step
  // (kept in the state rows, also across restart files) belongs to them as it did at the end of
  // that step, so that run N; run M (or a restart between them) equals run N+M
  if (s.opt.coupled && update->ntimestep % s.opt.fluid_every == 0)
    for (int k = 0; k < atom->nlocal; ++k)
      if (atom->mask[k] & couple_groupbit)
        for (int d = 0; d < 3; ++d) atom->f[k][d] += s.opt.fluid_every * pdata[k][mpm::C_FGRAIN + d];
  if (s.opt.out_every > 0 && update->ntimestep % s.opt.out_every == 0) guarded([&] { s.write_output(); });
  run_time_start[0] = s.time_fluid;
  run_time_start[1] = s.time_couple;
}

/* Where the fix's time went in the run just finished (slowest rank), next
   to LIGGGHTS' "Loop time": the fluid's own work and the coupling. */
void FixMpmFluid::post_run() {
  double t[2] = {solver->time_fluid - run_time_start[0], solver->time_couple - run_time_start[1]}, g[2];
  MPI_Allreduce(t, g, 2, MPI_DOUBLE, MPI_MAX, world);
  std::ostringstream os;
  os << "fix mpm/fluid: wall time in this run: fluid " << g[0] << " s";
  if (solver->opt.coupled) os << ", coupling " << g[1] << " s (" << (g[0] > 0.0 ? g[1] / g[0] : 0.0) << " of the fluid time)";
  os << "\n";
  print(os.str());
}

/* ----------------------------------------------------------------------
   one LIGGGHTS time step: all external forces on the points (fix gravity,
   fix addforce, ...) are in atom->f; the DEM integrator runs after us
------------------------------------------------------------------------- */

void FixMpmFluid::pre_final_integrate() {
  mpm::FluidSolver &s = sync();
  if (!s.grid_ready()) s.setup_grid(domain->sublo, domain->subhi, neighbor->skin);
  mpm::Gate &gate = s.opt.gate;
  if (gate.active && gate.release_time >= 0.0 && sim_time() >= gate.release_time - 0.5 * update->dt) {
    gate.active = false;
    std::ostringstream os;
    os << "fix mpm/fluid: gate removed at time " << sim_time() << " (step " << update->ntimestep << ")\n";
    print(os.str());
  }
  // between two fluid steps the grains get no fluid force: the fluid step gave them the
  // whole impulse of its N steps at once (FluidSolver::step)
  if (s.opt.fluid_every > 1 && update->ntimestep % s.opt.fluid_every != 0) return;
  guarded([&] { print(s.check_timestep(false)); });
  refresh_walls();
  guarded([&] { s.step(); });
  if (s.opt.coupled && fix_dragforce)
    for (int k = 0; k < atom->nlocal; ++k)
      if (atom->mask[k] & couple_groupbit)
        for (int d = 0; d < 3; ++d) fix_dragforce->array_atom[k][d] = s.grain_force()[3 * k + d];
  vector_step = -1;
}

double FixMpmFluid::compute_vector(int n) {
  if (n < 0 || n >= size_vector) return 0.0;
  if (vector_step != update->ntimestep) {
    sync().global_vector(vector_cache);
    vector_step = update->ntimestep;
  }
  return vector_cache[n];
}

int FixMpmFluid::modify_param(int narg, char **arg) {
  int used = 0;
  guarded([&] { used = mpm::modify_option(solver->opt, narg, arg); });
  return used;
}

void FixMpmFluid::end_of_step() {
  const int every = solver->opt.out_every;
  if (every > 0 && update->ntimestep % every == 0) guarded([&] { sync().write_output(); });
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

void FixMpmFluid::copy_arrays(int i, int j, int) { std::copy(pdata[i], pdata[i] + NCOL, pdata[j]); }

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
enum { R_FILLED, R_PMASS, R_SP0, R_SP1, R_SP2, R_CLAMPED, R_GATE, R_NSUB, R_THETA, R_TIME, R_TYPE, R_COUNT };
}

void FixMpmFluid::write_restart(FILE *fp) {
  const mpm::SolverState &st = solver->state;
  double list[R_COUNT];
  list[R_FILLED] = filled ? 1.0 : 0.0;
  list[R_PMASS] = st.point_mass_ref;
  for (int d = 0; d < 3; ++d) list[R_SP0 + d] = st.spacing[d];
  list[R_CLAMPED] = st.n_clamped;
  list[R_GATE] = solver->opt.gate.active ? 1.0 : 0.0;
  list[R_NSUB] = st.nsub;
  list[R_THETA] = st.theta_initialized ? 1.0 : 0.0;
  list[R_TIME] = sim_time();
  list[R_TYPE] = point_type;
  if (comm->me == 0) {
    int size = R_COUNT * sizeof(double);
    fwrite(&size, sizeof(int), 1, fp);
    fwrite(list, sizeof(double), R_COUNT, fp);
  }
}

void FixMpmFluid::restart(char *buf) {
  const double *list = reinterpret_cast<const double *>(buf);
  mpm::SolverState &st = solver->state;
  filled = list[R_FILLED] != 0.0;
  st.point_mass_ref = list[R_PMASS];
  for (int d = 0; d < 3; ++d) st.spacing[d] = list[R_SP0 + d];
  st.n_clamped = list[R_CLAMPED];
  // a gate removed before the restart stays removed
  if (list[R_GATE] == 0.0) solver->opt.gate.active = false;
  st.nsub = static_cast<int>(list[R_NSUB]);
  st.theta_initialized = list[R_THETA] != 0.0;
  // LIGGGHTS' time starts again at 0 here; the fix's time goes on from the saved one
  time_offset = 0.0;
  time_offset = list[R_TIME] - sim_time();
  point_type = static_cast<int>(list[R_TYPE]);
}

double FixMpmFluid::memory_usage() {
  return static_cast<double>(atom->nmax) * NCOL * sizeof(double) + static_cast<double>(solver->memory_bytes());
}
