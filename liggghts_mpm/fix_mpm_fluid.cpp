/* fix mpm/fluid: the LIGGGHTS adapter of mpm::FluidSolver (see fix_mpm_fluid.h, docs/design.md).
   The fluid's step, phase by phase, is FluidSolver::substep (mpm/solver.cpp). */

#include "fix_mpm_fluid.h"

#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include "atom.h"
#include "atom_vec.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "fix_property_atom.h"
#include "group.h"
#include "input.h"
#include "memory.h"
#include "modify.h"
#include "neighbor.h"
#include "region.h"
#include "update.h"
#include "variable.h"

#include "mpm/error.h"
#include "fix_mpm_fluid_guarded.h"
#include "restart_guard.h"

using namespace LAMMPS_NS;
using namespace FixConst;
using mpm::NCOL;

/* ---------------------------------------------------------------------- */

FixMpmFluid::FixMpmFluid(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg) {
  if (domain->triclinic) error->all(FLERR, "Fix mpm/fluid requires an orthogonal simulation box");
  if (!atom->rmass_flag || !atom->radius_flag)
    error->all(FLERR, "Fix mpm/fluid requires atom_style sphere (per-atom mass and radius)");
  // the defaults are SI quantities (density 1000 kg/m3, g = 9.81 m/s^2 of the volume correction's
  // rate and of hydrostatic): any other unit style would read them wrongly
  if (!update->unit_style || std::strcmp(update->unit_style, "si") != 0) {
    std::string msg = std::string("Fix mpm/fluid requires 'units si' (its defaults are SI quantities: density ") +
                      "1000 kg/m3, g = 9.81 m/s^2); the input has 'units " +
                      (update->unit_style ? update->unit_style : "?") + "'" +
                      (update->unit_style && std::strcmp(update->unit_style, "lj") == 0
                           ? " (LIGGGHTS' default when the input has no units command)"
                           : "");
    error->all(FLERR, msg.c_str());
  }

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
  if (comm->me == 0)
    for (const std::string &w : solver->opt.warnings) error->warning(FLERR, w.c_str());

  restart_global = 1;
  restart_peratom = 1;
  // no create_attribute: LIGGGHTS would call set_arrays() for every atom at
  // the first setup and wipe the points' state; new rows are zeroed in grow_arrays
  time_integrate = 1;  // the fix moves its material points itself
  vector_flag = 1;
  size_vector = mpm::FluidSolver::global_size(static_cast<int>(mesh_specs.size()),
                                              static_cast<int>(solver->opt.probes.size()), solver->opt.drive.active,
                                              solver->opt.flow_faces());
  // inflow and outflow faces: points are created and removed on steps that exchange atoms
  force_reneighbor = solver->opt.flow_faces() ? 1 : 0;
  next_reneighbor = -1;
  vector_cache.assign(size_vector, 0.0);
  global_freq = 1;
  extvector = 0;
  peratom_flag = 1;
  size_peratom_cols = NCOL;
  peratom_freq = 1;
  nevery = 1;  // end_of_step every step: the output's own steps, and the restart files (restart_guard.h)

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
  return PRE_FINAL_INTEGRATE | END_OF_STEP | (solver->opt.flow_faces() ? PRE_EXCHANGE : 0);
}

// the screen of liggghts_mpm copies a line "ERROR on proc" into the log file (main.cpp); a rank
// without screen and log file (ranks other than 0) writes to stderr
void FixMpmFluid::fail_one(const std::string &msg) {
  FILE *f = screen ? screen : logfile ? logfile : stderr;
  fprintf(f, "ERROR on proc %d: %s\n", comm->me, msg.c_str());
  fflush(f);
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


/* ---------------------------------------------------------------------- */

void FixMpmFluid::init() {
  const mpm::Options &o = solver->opt;
  if (restart_time_pending) {
    time_offset = 0.0;
    time_offset = restart_time - sim_time();
    restart_time_pending = false;
  }
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
  find_drive_variable();
  mpm::FluidSolver &s = sync();
  s.pts.integrated_bits = integrated;
  std::string warning;
  guarded([&] { warning = s.check_points(); });
  if (!warning.empty() && comm->me == 0) error->warning(FLERR, warning.c_str());
  vector_step = -1;
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
  bool changed = true;
  try {
    changed = mesh_walls->refresh(lo, hi, 2.0 * gs.dx);
  } catch (const std::exception &e) {
    error->all(FLERR, e.what());
  }
  // walls at rest keep the constraints the nodes collected (a new grid patch renews them:
  // FluidSolver::setup_grid)
  if (changed) solver->bc.walls_moved();
}

void FixMpmFluid::setup(int) {
  // The points have radius 0: a LIGGGHTS mesh wall (fix wall/gran ... mesh) acts on every atom
  // within its radius of the wall whatever the wall fix's group (a primitive one of group all as
  // well), and a point of finite radius got contact forces from them (a turning drum's lifters pushed the water's points with the beads'
  // contact law, and the drum's stress output counted them). A restart file of an earlier build
  // holds points of finite radius: set here for every run.
  for (int i = 0; i < atom->nlocal; ++i)
    if (is_point(i)) atom->radius[i] = 0.0;
  mpm::FluidSolver &s = sync();
  s.setup_grid(domain->sublo, domain->subhi, neighbor->skin, !mesh_specs.empty());
  check_gate_side();
  warn_unheld();
  if (!mesh_specs.empty()) {
    const bool first = !mesh_walls;  // the sides given in the fix command are checked at the first setup
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
      print(mesh_walls->infer_sides(pts.data(), (int)pts.size(), 1.0 * s.opt.grid.dx, first));
    } catch (const std::exception &e) {
      error->all(FLERR, (std::string("Fix mpm/fluid: ") + e.what()).c_str());
    }
    s.bc.walls_moved();  // the constraints depend on the sides set now
  }
  guarded([&] {
    s.setup_coupling();
    print(s.check_timestep(true));
  });
  if (s.opt.every_auto) {
    // the N the state asks for now, for the log (the next fluid step chooses again; one already
    // scheduled by an earlier run or a restart file stays where it is)
    const int n_now = s.opt.fluid_every;
    s.opt.fluid_every = s.state.last_every;
    std::ostringstream os;
    os << "fix mpm/fluid: every auto: the fluid advances by N x timestep, N at most " << mpm::FluidSolver::kMaxEvery
       << " and within the smallest limit of the state (now N = " << n_now << ", " << s.every_auto_limit() << ")\n";
    print(os.str());
  }
  // LIGGGHTS recomputed the grains' forces for this run; the fluid force of the last fluid step
  // (kept in the state rows, also across restart files) acts on them on this step as it did when
  // the step was first taken, so that run N; run M (or a restart between them, on a fluid step or
  // between two) equals run N+M
  add_grain_force();
  if (s.opt.out_every > 0 && update->ntimestep % s.opt.out_every == 0) guarded([&] { s.write_output(); });
  mark_run_start();
}

/* The gate holds the fluid on one side and puts back the points that crossed it by less than a
   cell. Points found at a setup farther than a cell on its other side would all be pressed against
   it (the whole fluid, for a gate on the wrong side or at a grid face with the fluid beyond it):
   an error naming the gate, the sides and how much fluid is where. */
void FixMpmFluid::check_gate_side() {
  const mpm::Options &o = solver->opt;
  const mpm::Gate &g = o.gate;
  if (!g.active) return;
  double loc[4] = {0.0, 0.0, 0.0, 0.0}, glob[4];  // points and mass on the held side, beyond a cell on the other
  for (int i = 0; i < atom->nlocal; ++i) {
    if (!is_point(i)) continue;
    const double beyond = g.fluid_below ? atom->x[i][g.dim] - g.pos : g.pos - atom->x[i][g.dim];
    const int k = beyond <= 0.0 ? 0 : beyond > o.grid.dx ? 2 : -1;
    if (k < 0) continue;
    loc[k] += 1.0;
    loc[k + 1] += atom->rmass[i];
  }
  MPI_Allreduce(loc, glob, 4, MPI_DOUBLE, MPI_SUM, world);
  if (glob[2] == 0.0) return;
  const char *held = g.fluid_below ? "lower" : "upper", *other = g.fluid_below ? "upper" : "lower";
  std::ostringstream os;
  os.precision(6);
  os << "Fix mpm/fluid: keyword 'gate' (" << "xyz"[g.dim] << " " << g.pos << " " << held << ") holds the fluid on its "
     << held << " side, but " << glob[2] << " material points (mass " << glob[3] << ") lie on its " << other
     << " side farther than one cell (" << o.grid.dx << ") from it, against " << glob[0] << " points (mass " << glob[1]
     << ") on the " << held << " side: the gate puts back only points within one cell, the others would be pressed "
     << "against it; give '" << other << "' or move the gate";
  error->all(FLERR, os.str().c_str());
}

// the counters at the start of a run ('run N pre no' skips setup(): post_run marks it as well)
void FixMpmFluid::mark_run_start() {
  const mpm::FluidSolver &s = *solver;
  run_time_start[0] = s.time_fluid();
  run_time_start[1] = s.time_couple();
  run_time_start[2] = s.time_pressure_solver();
  run_time_start[3] = static_cast<double>(s.pressure_solves());
  run_time_start[4] = static_cast<double>(s.pressure_iterations_summed());
  run_time_start[5] = s.time_output();
  run_time_start[6] = static_cast<double>(s.n_outputs());
  run_time_start[7] = s.grid().wait_seconds();
  run_stats_start = mpm::run_stats_start(s.grid());
  every_run[0] = every_run[1] = every_run[2] = 0.0;
}

/* Where the fix's time went in the run just finished (slowest rank), next
   to LIGGGHTS' "Loop time": the fluid's own work and the coupling. */
void FixMpmFluid::post_run() {
  mpm::periodic_restarts().settle(lmp);
  const mpm::FluidSolver &s = *solver;
  double t[4] = {s.time_fluid() - run_time_start[0], s.time_couple() - run_time_start[1],
                 s.time_pressure_solver() - run_time_start[2], s.time_output() - run_time_start[5]},
         g[4];
  MPI_Allreduce(t, g, 4, MPI_DOUBLE, MPI_MAX, world);
  std::ostringstream os;
  os << "fix mpm/fluid: wall time in this run: fluid " << g[0] << " s";
  if (s.opt.projection) {
    // the same on every rank (one collective solve per fluid step)
    const double nsolve = static_cast<double>(s.pressure_solves()) - run_time_start[3];
    const double nit = static_cast<double>(s.pressure_iterations_summed()) - run_time_start[4];
    os << " (pressure solver " << g[2] << " s = " << (g[0] > 0.0 ? g[2] / g[0] : 0.0) << " of it, " << nsolve
       << " solves, " << (nsolve > 0.0 ? nit / nsolve : 0.0) << " PCG iterations per solve)";
  }
  if (s.opt.coupled) os << ", coupling " << g[1] << " s (" << (g[0] > 0.0 ? g[1] / g[0] : 0.0) << " of the fluid time)";
  if (s.opt.every_auto && every_run[2] > 0.0)
    os << "; every auto: " << every_run[2] << " fluid steps, N from " << every_run[0] << " to " << every_run[1];
  const double nout = static_cast<double>(s.n_outputs()) - run_time_start[6];  // the same on every rank
  if (nout > 0.0) os << ", output " << g[3] << " s (" << nout << " files, " << g[3] / nout << " s per file)";
  if (comm->nprocs > 1) {
    // the balance as it held: each rank's fluid and coupling time less its waits for halo
    // messages (busy, what fix balance/mpm measured yes cuts by), and the waits
    const double wait = s.grid().wait_seconds() - run_time_start[7];
    const double busy = t[0] + t[1] - wait;
    double r[4] = {busy, -busy, wait, -wait}, rg[4], sum = 0.0;
    MPI_Allreduce(r, rg, 4, MPI_DOUBLE, MPI_MAX, world);
    MPI_Allreduce(&busy, &sum, 1, MPI_DOUBLE, MPI_SUM, world);
    const double mean = sum / comm->nprocs;
    os << "; per rank: busy " << -rg[1] << " to " << rg[0] << " s (max/mean " << (mean > 0.0 ? rg[0] / mean : 1.0)
       << "), waits for halo messages " << -rg[3] << " to " << rg[2] << " s";
  }
  long npoints = 0;  // this rank's material points
  for (int i = 0; i < atom->nlocal; ++i) npoints += is_point(i) ? 1 : 0;
  os << "\n" << mpm::run_stats_lines(world, s.grid(), run_stats_start, npoints);
  print(os.str());
  mark_run_start();
}

/* ----------------------------------------------------------------------
   one LIGGGHTS time step: all external forces on the points (fix gravity,
   fix addforce, ...) are in atom->f; the DEM integrator runs after us
------------------------------------------------------------------------- */

void FixMpmFluid::pre_final_integrate() {
  mpm::periodic_restarts().settle(lmp);
  mpm::FluidSolver &s = sync();
  if (!s.grid_ready()) {
    // a new grid patch inside a run (fix balance/mpm every N): as at the setup of a run, the
    // projection's last solve goes on into it and theta_transport takes its nodal reference again
    s.setup_grid(domain->sublo, domain->subhi, neighbor->skin, !mesh_specs.empty());
    guarded([&] { s.setup_coupling(); });
  }
  mpm::Gate &gate = s.opt.gate;
  if (gate.active && gate.release_time >= 0.0 && sim_time() >= gate.release_time - 0.5 * update->dt) {
    gate.active = false;
    std::ostringstream os;
    os << "fix mpm/fluid: gate removed at time " << sim_time() << " (step " << update->ntimestep << ")\n";
    print(os.str());
  }
  // the fluid advances on every N-th step by N dt (keyword every); the grains receive the force of
  // the last fluid step on each DEM step, this one included
  if (fluid_step_due(s)) {
    guarded([&] { print(s.check_timestep(false)); });
    if (s.opt.every_auto) note_every(s);
    refresh_walls();
    drive_target();
    if (s.opt.coupled && s.opt.fluid_every > 1) {
      // the fluid sees the grains (N-1)/2 steps ahead, where they are halfway through the N steps
      // that will receive its force: see fluid_step_ahead
      fluid_step_ahead(s);
    } else {
      guarded([&] { s.step(); });
    }
    if (!sealed_noted && s.pressure_sealed_nodes() > 0) {
      sealed_noted = true;
      std::ostringstream os;
      os << "fix mpm/fluid: at step " << update->ntimestep << " " << s.pressure_sealed_nodes()
         << " fluid nodes in " << s.pressure_sealed_sets()
         << " pocket(s) are sealed off from the free surface by closed wall faces: each pocket's pressure is "
            "solved with its own mean (the water in it cannot be compressed; noted once)\n";
      print(os.str());
    }
    schedule_flow();
    if (s.opt.coupled && fix_dragforce)
      for (int k = 0; k < atom->nlocal; ++k)
        if (atom->mask[k] & couple_groupbit)
          for (int d = 0; d < 3; ++d) fix_dragforce->array_atom[k][d] = s.grain_force()[3 * k + d];
    vector_step = -1;
  }
  add_grain_force();
}

/* Whether the fluid steps on this step: every N-th step (every N), or (every auto) when the N
   steps of the last fluid step are over; the N of the fluid step about to be taken is chosen in
   check_timestep (note_every ends it with the run). The schedule is in restart files, so that a
   run resumed from one written during a run (restart N) continues bit for bit. */
bool FixMpmFluid::fluid_step_due(const mpm::FluidSolver &s) const {
  if (!s.opt.every_auto) return s.opt.fluid_every == 1 || update->ntimestep % s.opt.fluid_every == 0;
  // a step more than N ahead: the step count was reset (reset_timestep); the fluid steps now
  const long next = s.state.next_fluid_step, now = static_cast<long>(update->ntimestep);
  return next < 0 || now >= next || next > now + s.state.last_every;
}

// every auto: N ends the fluid step at the last step of the run (what a run, a fix_modify or a
// restart file between runs changes acts from the next run's first step) and at the gate's release
// time; the next fluid step's host step, and the range of N over the run (post_run)
void FixMpmFluid::note_every(mpm::FluidSolver &s) {
  const long now = static_cast<long>(update->ntimestep);
  long cap = static_cast<long>(update->laststep) - now + 1;
  const mpm::Gate &gate = s.opt.gate;
  if (gate.active && gate.release_time >= 0.0) {
    const double k = std::floor((gate.release_time - sim_time()) / update->dt + 0.5);
    if (k >= 1.0 && k < cap) cap = static_cast<long>(k);
  }
  if (cap >= 1 && s.opt.fluid_every > cap) s.opt.fluid_every = static_cast<int>(cap);
  const int n = s.opt.fluid_every;
  s.state.next_fluid_step = now + n;
  s.state.last_every = n;
  every_run[0] = every_run[2] == 0.0 ? n : std::min(every_run[0], double(n));
  every_run[1] = std::max(every_run[1], double(n));
  every_run[2] += 1.0;
}

/* every N > 1: the fluid step at step n gives its force F to the N DEM steps n .. n+N-1. With F
   taken at the grains' positions of step n, a force F(x) kept for N steps is not a symplectic map
   (det = 1 + N(N-1)/2 (w dt)^2 for F/m = -w^2 x; docs/theory/coupled_stability.md, "every N"): the
   coupled pore-pressure oscillation grows. Taken at x + (N-1)/2 dt v, where the grains are halfway
   through those steps, the map over the N steps has det = 1 (the midpoint rule of the N steps):
   the grains are moved there for the fluid step and put back after it. Their velocities are
   unchanged; with N = 1 the shift is 0 and the fluid step sees the grains where they are. */
void FixMpmFluid::fluid_step_ahead(mpm::FluidSolver &s) {
  const double ahead = 0.5 * (s.opt.fluid_every - 1) * update->dt;
  const int nlocal = atom->nlocal;
  double **x = atom->x, **v = atom->v;
  shifted.resize(3 * static_cast<std::size_t>(nlocal));
  for (int k = 0; k < nlocal; ++k)
    for (int d = 0; d < 3; ++d) {
      shifted[3 * k + d] = x[k][d];
      if (atom->mask[k] & couple_groupbit) x[k][d] += ahead * v[k][d];
    }
  guarded([&] { s.step(); });
  for (int k = 0; k < nlocal; ++k)
    if (atom->mask[k] & couple_groupbit)
      for (int d = 0; d < 3; ++d) x[k][d] = shifted[3 * k + d];
}

/* The fluid force on the grains, F of the last fluid step (state rows, C_FGRAIN), added on each DEM
   step: with every N the fluid step at step n covers the steps n .. n+N-1, and velocity Verlet turns
   the N forces into the impulse N dt F that the fluid gave up in its step. A grain that came to
   this rank carries its F in its row (pack_exchange); one inserted after the fluid step has F = 0
   until the next one (rows are zeroed when made or vacated: grow_arrays, copy_arrays), as the fluid
   did not see it either. */
void FixMpmFluid::add_grain_force() {
  if (!solver->opt.coupled) return;
  double **f = atom->f;
  for (int k = 0; k < atom->nlocal; ++k)
    if (atom->mask[k] & couple_groupbit)
      for (int d = 0; d < 3; ++d) f[k][d] += pdata[k][mpm::C_FGRAIN + d];
}

/* superficial_velocity v_name: the equal-style variable, looked up at every run's init (an error
   before the run) and before each fluid step (fix_modify may have named another between runs
   that skip the setup), then evaluated. */
void FixMpmFluid::find_drive_variable() {
  const mpm::FlowDrive &dr = solver->opt.drive;
  drive_var = -1;
  if (!dr.active || dr.variable.empty()) return;
  drive_var = input->variable->find(const_cast<char *>(dr.variable.c_str()));
  if (drive_var < 0 || !input->variable->equalstyle(drive_var)) {
    const std::string m = "Fix mpm/fluid: keyword 'superficial_velocity' expects an equal-style variable, got 'v_" +
                          dr.variable + "' (" + (drive_var < 0 ? "no such variable" : "not equal-style") + ")";
    error->all(FLERR, m.c_str());
  }
}

void FixMpmFluid::drive_target() {
  const mpm::FlowDrive &dr = solver->opt.drive;
  if (!dr.active || dr.variable.empty()) return;
  find_drive_variable();
  const double u = input->variable->compute_equal(drive_var);
  if (!std::isfinite(u)) {
    std::ostringstream os;
    os << "Fix mpm/fluid: keyword 'superficial_velocity' expects a finite superficial velocity (velocity), got " << u
       << " from variable v_" << dr.variable << " at step " << update->ntimestep;
    error->all(FLERR, os.str().c_str());
  }
  solver->opt.drive.target = u;
}

double FixMpmFluid::busy_seconds() const { return solver ? solver->busy_seconds() : 0.0; }

void FixMpmFluid::subdomain_changed() {
  if (solver) solver->invalidate_grid();
}

double FixMpmFluid::compute_vector(int n) {
  if (n < 0 || n >= size_vector) return 0.0;
  const int k = (n - mpm::FluidSolver::kGlobalSize) / 6;
  if (n >= mpm::FluidSolver::kGlobalSize && k < static_cast<int>(mesh_specs.size()) && !mesh_specs[k].loads) {
    const std::string m = "Fix mpm/fluid: f_" + std::string(id) + "[" + std::to_string(n + 1) +
                          "] is a load of mesh_wall " + mesh_specs[k].fix_id +
                          ", whose loads are off: give it 'loads yes' in the fix command";
    error->all(FLERR, m.c_str());
  }
  if (vector_step != update->ntimestep) {
    sync().global_vector(vector_cache.data(), static_cast<int>(mesh_specs.size()));
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
  // restart files of the restart command due now: LIGGGHTS writes them after this, through FIFOs;
  // settled (renamed into place or removed with an error) at the next step or the end of the run
  mpm::periodic_restarts().arm(lmp);
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

// LIGGGHTS copies atom i into the slot j and vacates i (exchange and deletion: the last atom into
// the slot of one that left, itself when it is the one that left; sorting): i's grain force is
// cleared, so that an atom inserted into the vacated slot starts with none
void FixMpmFluid::copy_arrays(int i, int j, int) {
  if (i != j) std::copy(pdata[i], pdata[i] + NCOL, pdata[j]);
  std::fill(pdata[i] + mpm::C_FGRAIN, pdata[i] + mpm::C_FGRAIN + 3, 0.0);
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

double FixMpmFluid::memory_usage() {
  return static_cast<double>(atom->nmax) * NCOL * sizeof(double) + static_cast<double>(solver->memory_bytes());
}
