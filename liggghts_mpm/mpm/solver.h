// The MPM fluid of fix mpm/fluid without LIGGGHTS: the grid, the per-point state and the time step
// of chapter 8, phase by phase (substep). The host (the LIGGGHTS adapter, fix_mpm_fluid.cpp) owns
// the atoms and gives the solver views of their arrays (Points) before each call, its MPI
// communicator and its clock; the solver throws mpm::Error / mpm::LocalError (mpm/error.h).
// Phases and files: docs/design.md.
#pragma once
#include <mpi.h>

#include <cmath>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "mpm/boundaries.h"
#include "mpm/coupling_model.h"
#include "mpm/grid.h"
#include "mpm/grid_fields.h"
#include "mpm/options.h"
#include "mpm/pressure_model.h"
#include "mpm/projection_state.h"
#include "mpm/solver_axes.h"
#include "mpm/stencil.h"

namespace mpm {

class Projection;

// Views of the host's per-atom arrays (valid until the host reallocates them).
struct Points {
  int nlocal = 0;
  double **x = nullptr, **v = nullptr, **f = nullptr;
  double *rmass = nullptr, *radius = nullptr;
  const int *mask = nullptr, *tag = nullptr, *type = nullptr;
  double **state = nullptr;  // per-point state rows (Column)
  int point_bit = 0;         // mask bit of the material points
  int grain_bit = 0;         // mask bit of the coupled grains (couple)
  int integrated_bits = 0;   // groups some integrator moves: other grains are fixed
};

// The host's clock, for the gate, messages and output.
struct Clock {
  long step = 0;
  double time = 0.0;  // simulation time
  double dt = 0.0;    // host time step
};

// The solver's state that a restart must keep.
struct SolverState {
  double point_mass_ref = 0.0;    // typical point mass, for the nodal mass threshold
  double spacing[3] = {0, 0, 0};  // initial point spacing per direction
  double n_clamped = 0;           // points put back inside a wall (cumulative)
  int nsub = 1;                   // fluid sub-steps per step (last check)
  bool theta_initialized = false; // fluid mass reduced by the grains' volume once
  // every auto: the host step of the next fluid step (-1: the next step), the N of the last one,
  // and the time left until the next volume correction
  long next_fluid_step = -1;
  int last_every = 1;
  double vc_due = 0.0;
  double grain_tau = HUGE_VAL;  // this rank's shortest drag response time m/K in the last fluid step
  double drive_gradient = 0.0;    // superficial_velocity: the driving pressure gradient of the last fluid step
  ProjectionState projection;     // from a restart file, until the grid is set up (whole grid)
  // inflow and outflow faces (flow_faces.cpp): per face the depth (length) the inflow's fluid has
  // entered beyond its last layer of points; the mass of the points created and removed, all ranks
  double inflow_depth[6] = {0, 0, 0, 0, 0, 0};
  double mass_in = 0.0, mass_out = 0.0;
};

class FluidSolver {
 public:
  FluidSolver(const Options &opt, MPI_Comm comm);
  ~FluidSolver();

  Options opt;        // fix_modify changes some of them between runs
  SolverState state;
  Points pts;         // set by the host before every call
  Clock clock;
  Boundaries bc;

  // Checks of the points and grains before a run (collective, throws mpm::Error): every point was
  // set up by the fix, the options fit together, grains are no points and fit into a cell.
  // Returns a warning (a grain larger than a cell with cell_check no) or "".
  std::string check_points();
  // The state row of a new point at x of reference volume vol (hydrostatic pre-compression);
  // returns its mass.
  double init_point(const double x[3], double vol, double *row) const;

  // Grid patch of this rank's subdomain, with a halo of the node layers that the stencil of a
  // point at most `skin` outside the subdomain reaches (stencil_reach), one more with mesh walls
  // (docs/design.md, "The halo"). A point farther out stops the run (outside_patch).
  void setup_grid(const double sublo[3], const double subhi[3], double skin, bool mesh_walls = false);
  bool grid_ready() const { return grid_ready_; }
  // the host moved the subdomain cuts inside a run (fix balance/mpm every N): setup_grid again
  void invalidate_grid() { grid_ready_ = false; }
  const IndexBox &patch() const { return grid_.patch(); }
  // pressure projection: the state of the last solve on the whole grid (collective), for the
  // restart file; before the grid is set up, the one read from a restart file (or none)
  ProjectionState projection_state();
  // First run with grains: the fluid mass reduced to theta rho0 V once.
  void setup_coupling();

  // Time-step check of the current state (collective, throws mpm::Error): the number of fluid
  // sub-steps of the next step (state.nsub), and with every auto the N of the next fluid step
  // (opt.fluid_every); returns a log line when it changed at setup.
  std::string check_timestep(bool at_setup);
  // every auto: the largest N accepted (a fluid at rest without gravity has no limit of its own),
  // and the limit that set N at the last check, in words with its value
  static constexpr int kMaxEvery = 1000;
  std::string every_auto_limit() const;

  // One fluid step of fluid_every * dt in state.nsub sub-steps; with couple, the fluid force on
  // the grains (mean over the sub-steps) goes to their state rows (C_FGRAIN) and grain_force(): the
  // host adds it to the grains' forces on each DEM step until the next fluid step.
  void step();
  const std::vector<double> &grain_force() const { return coup_->grain_force; }

  // f_ID[1..18] (collective): mass, kinetic energy, |v|max, front, height, sub-steps, stable dt,
  // clamped, points, p max, fluid force on the grains (3), wall time of the fluid and coupling,
  // iterations and relative residual of the last pressure solve (pressure projection; else 0),
  // wall time in the pressure solver (part of the fluid's)
  static constexpr int kGlobalSize = 19;
  // then, from index kGlobalSize (f_ID[20] on): per mesh wall k (in the order of the fix command)
  // the fluid's force on it (3) and its torque about the wall's reference point (3): minus the
  // momentum the wall gave the fluid over the last fluid step per time (wall_loads.cpp); then per probe the pressure averaged
  // over the last completed probe window; then, with superficial_velocity (drive), the driving
  // pressure gradient of the last fluid step. walls: the number of mesh walls of the host.
  // then, with inflow or outflow faces (flow), the mass of the points created and removed since the
  // fix was made (mass in, mass out; points that left and are not yet removed count as out)
  static int global_size(int walls, int probes, bool drive = false, bool flow = false) {
    return kGlobalSize + 6 * walls + probes + (drive ? 1 : 0) + (flow ? 2 : 0);
  }
  void global_vector(double *out, int walls);
  // wall_loads.cpp: the pressure field the probes read in this sub-step, added to the probes' sums
  // with weight h, and (projection) the pressure correction's momentum to the mesh walls' loads
  // (after update_grid; collective)
  void sample_pressure(double h);
  // HDF5 + XDMF output of the points (and grid) fields of keyword output (collective).
  void write_output();
  // wall time in write_output on this rank (s, cumulative) and the step files written
  double time_output() const { return io_.time_output; }
  long n_outputs() const { return io_.n_outputs; }
  // wall time of the fluid's own work and of the coupling on this rank (s, cumulative)
  double time_fluid() const { return io_.time_fluid; }
  double time_couple() const { return io_.time_couple; }
  // the wall time of the fluid and the coupling less the waits for the halo exchanges, since
  // construction: this rank's work (fix balance/mpm measured)
  double busy_seconds() const { return io_.time_fluid + io_.time_couple - grid_.wait_seconds(); }
  // pressure projection, this rank, cumulative: wall time in the pressure solver (hypre assembly,
  // setup, PCG; part of time_fluid), solves and their PCG iterations (0 with eos)
  double time_pressure_solver() const;
  long pressure_solves() const;
  long pressure_iterations_summed() const;
  // pressure projection: FLUID nodes (all ranks) and pockets of them sealed off from the free
  // surface by closed wall faces in the last solve (0 with eos)
  long pressure_sealed_nodes() const;
  long pressure_sealed_sets() const;
  std::size_t memory_bytes() const;

  // The phases of substep, in order; public so that a test (or another model) can run them one by
  // one. Each works on the points of pts and the node records of fields() (docs/design.md).
  void compute_shapes();            // shape functions of the points
  void fluid_fraction();            // coupling: theta at nodes and points (8-11)-(8-16)
  void refresh_pressure();          // coupling: density and pressure for the new theta
  void particles_to_grid();         // P2G (8-10), (8-19), (8-24), traction (8-23)
  void couple_fluid_grains(double h);  // coupling: pressure fit, drag exchange (8-25)-(8-29)
  // (8-35), (8-36), boundary conditions (projection: u*, solve, correction); vc_time > 0: the
  // volume correction is due and stands for that time (Projection::volume_correction_every)
  void update_grid(double h, double vc_time = 0.0);
  void point_pressure();            // the points' pressure from the nodes (projection; eos: none)
  // the nodal pressure gradient the grains feel (grad_p weak: gw; projection + couple: the last
  // solve's, read in place); nullptr where it does not cover the patch
  const double *grain_gradient() const;
  void grid_to_particles();         // G2P (8-37)-(8-40)
  void remap_velocity_musl(double h);  // MUSL remap of the updated point momentum
  void update_stress(double h, bool theta_only = false);  // (7-21)-(7-24)
  void advance_positions(double h); // (8-41), points put back
  // superficial_velocity (flow_drive.cpp): before the sub-steps, the driving gradient of the last
  // fluid step as a body force on the points; after them, the fluid's mean flux set to the target
  // by a uniform velocity increment, the gradient updated to the one that acted, the grains' share
  void drive_force();
  void drive_correct(double hf);
  // inflow faces (flow_faces.cpp): the fluid of a fluid step of length hf entered (inflow_depth)
  void inflow_advance(double hf);
  // the layers of points due at inflow face f (inflow_depth over the point spacing along its
  // normal), and the coordinate along the normal of layer j = 0 .. n-1 (j = 0 the farthest in)
  int inflow_layers(int f) const;
  double inflow_layer_position(int f, int j) const;
  // after the host created the layers due: inflow_depth less them
  void inflow_created(int f, int n);
  // points of this rank that left through an outflow face in the last fluid step (kPointGone)
  long points_gone() const { return pw_.gone; }
  void clear_gone() { pw_.gone = 0; }
  void substep(double h, double vc_time = 0.0);  // all of them
  GridFields &fields() { return g_; }
  const LocalGrid &grid() const { return grid_; }
  // sparse grid (keyword sparse; pure eos fluid): the active blocks of this sub-step, and whether
  // the grid phases run on them only
  bool sparse() const { return sparse_; }
  const ActiveBlocks &active_blocks() const { return blocks_; }
  // the values of the node arrays of fields() at nodes of inactive blocks that are not zero (the
  // sparse grid's invariant; 0 for the dense grid)
  long nonzero_outside_active() const;

 private:
  // the pressure models' work on the points and the grid (pressure_model.cpp)
  friend class PressureModel;
  friend class EosPressure;
  friend class ProjectionPressure;
  friend class GrainCoupling;
  void store_grain_force();     // the grains' force of the fluid step to their state rows
  void drive_grain_share(int a);  // superficial_velocity: the grains' share of the gradient
  // the phases' bodies per pressure model: eos / node_bc true for the equation of state (the
  // points' pressure in the internal force, the walls' traction, the nodes' boundary conditions)
  void p2g(bool eos);
  void grid_velocity(double h, bool node_bc);
  void project_velocity(Projection &proj, std::vector<double> &pvol, double h, double vc_time);
  void point_volume_to_grid(std::vector<double> &pvol);  // volume_correction: sum S V of the points
  void interpolate_pressure(const std::vector<double> &p);
  void eos_stress(double h, bool theta_only);
  void incompressible_stress(bool theta_only);
  // kernels (transfer.cpp, coupling.cpp), instantiated per stencil size and transfer policy
  template <int NS, class P, class Fn> void p2g_kernel(Fn &&after_point, bool eos);
  template <int NS, class P> void g2p_kernel();
  template <int NS, class P> void musl_scatter();
  template <int NS> void musl_gradient();
  template <int NS, bool VOL> void pressure_moments();  // VOL: also the points' volume (rq)
  template <int NS> void couple_kernel(double h);
  // couple_kernel's steps (coupling.cpp)
  template <int NS> void grain_pressure_inputs(bool proj, bool weak);
  void grain_node_state(const IndexBox &sbox, const IndexBox &rbox, bool weak);
  template <int NS> void grain_drag_sums(std::vector<double> &Kgrain, bool proj, bool weak);
  void drag_exchange(const IndexBox &dbox, double h);
  template <int NS> void grain_drag_forces(const std::vector<double> &Kgrain, double h);
  template <int NS> void point_sums();             // grad_p weak: WkRec (reaction points: rq)
  void weak_pressure_gradient();                   // grad_p weak
  void weak_face_copy();                           // grad_p weak: face and padding nodes
  template <int NS> void smooth_weak_gradient();   // grad_p weak: the points' view of it
  template <int NS> void route_reaction();         // reaction points
  // out_j = sum_p S_jp V_p sum_i S_ip q_i (3 per node, folded): a nodal field as the points see it
  template <int NS> void through_points(const double *q, std::vector<double> &out);
  void fold_to_mirror(std::vector<double> &a, int stride);
  void smooth_node_volume(std::vector<double> &a, int stride = 1);
  template <class Fn> void for_nodes(const Stencil &ps, Fn &&fn) const;
  // sparse grid: the active blocks of the points' stencils, retired blocks cleared
  void mark_active_blocks();
  // zeroes a node array (stride doubles per node): all of it, or the active blocks (sparse)
  void clear_nodes(std::vector<double> &a, int stride);
  // fn(i, j, k, n) for every owned node, or every owned node of an active block (sparse)
  template <class Fn> void for_owned_nodes(Fn &&fn) const {
    if (!sparse_) return grid_.for_owned(fn);
    for (const IndexBox &b : blocks_.owned_boxes()) grid_.for_box(b, fn);
  }

  bool shape_of(const double *x, Stencil &ps);
  // shape_of for one kind of shape function (QUAD: quadratic B-spline, else linear), with the grid's
  // constants taken once per grid set-up (shape_ctx_)
  template <bool QUAD> bool shape_at(const double *x, Stencil &ps) const;
  [[noreturn]] void outside_patch(const double *x) const;
  ShapeCtx shape_ctx_;
  // anti-locking: the node index of the cell that holds point i (clamped at non-periodic faces)
  std::size_t cell_node(int i) const;
  // anti-locking: point i's share of its cell's sums (CellRec) for the stress update, velocity
  // gradient L (9, row-major); stores pcell_[i]
  void sum_cell(int i, const double *L);
  void smooth_solid_volume();
  // smooth_node_volume's steps (fluid_fraction.cpp)
  const std::vector<double> &node_volumes();
  void smoothing_start(std::vector<double> &a, int stride, IndexBox &nzb);
  void smoothing_sweep(int d, int stride, const IndexBox &b, const double *V);
  double solid_node_volume(int i, int j, int k) const;
  void init_theta();
  double stable_dt();
  void coupled_limits(const double *glob);  // stable_dt: the pore-pressure wave limits
  std::string projection_limit(double dt, double dt_sub, const char *what, bool at_setup);  // check_timestep
  // a material point of the fluid (not one that left through an outflow face)
  bool is_point(int i) const { return (pts.mask[i] & pts.point_bit) != 0 && pts.state[i][C_FLAG] != kPointGone; }
  bool is_grain(int i) const { return opt.coupled && (pts.mask[i] & pts.grain_bit) != 0; }
  double mass_min() const { return opt.mass_threshold * state.point_mass_ref; }

  MPI_Comm comm_;
  int me_ = 0, nprocs_ = 1;
  LocalGrid grid_;
  GridFields g_;
  ActiveBlocks blocks_;
  bool sparse_ = false;
  bool grid_ready_ = false;
  IndexBox projection_work_box();
  // the state of each axis (solver_axes.h, pressure_model.h, coupling_model.h)
  PointWork pw_;                            // core: the points of this sub-step
  std::unique_ptr<PressureModel> pressure_; // pressure: eos or projection, chosen at construction
  std::unique_ptr<CouplingModel> coup_;    // coupling: none or grains, chosen at construction
  StepLimits lim_;                          // time step
  OutputState io_;                          // io
  const double *velgrad(int i) const {
    return pw_.grad_in_state ? pts.state[i] + C_AFF : &pw_.velgrad[9 * static_cast<std::size_t>(i)];
  }
  std::string range_warning();
  // finite position, velocity, mass (compute_shapes): q - q is 0 for a finite q and NaN for an
  // infinite or NaN one, one test for the usual case (the build does not assume finite math);
  // bad_point names the first bad value
  void check_point(int i) const {
    const double *x = pts.x[i], *v = pts.v[i];
    const double m = pts.rmass[i];
    const double z = ((x[0] - x[0]) + (x[1] - x[1]) + (x[2] - x[2])) + ((v[0] - v[0]) + (v[1] - v[1]) + (v[2] - v[2])) + (m - m);
    if (!(z == 0.0 && m > 0.0)) bad_point(i);
  }
  void bad_point(int i) const;
  bool grains_need_nodes() const;     // the pressure moments read need (grad_p nodal, fit; eos)
  void check_grain(int k) const;      // finite position, velocity, radius, mass (fluid_fraction)
  // the first of position, velocity, radius (when given) and mass that is not finite, or (radius,
  // mass) not positive; nullptr if none (bad_point, check_grain)
  static const char *first_bad(const double *x, const double *v, const double *radius, double mass);
  // a mesh wall with 'loads yes' or a probe: the sub-steps sample the pressure (else nothing is spent)
  bool samples_on() const { return walls_with_loads() || !opt.probes.empty(); }
  bool walls_with_loads() const {
    const WallGeometry *wg = bc.walls();
    if (wg)
      for (int k = 0; k < wg->walls(); ++k)
        if (wg->wall(k).loads) return true;
    return false;
  }
  void node_mass_pressure();
  void surface_pressure();
  bool pressure_at(const double *x, double &p, double *vel);
  bool owns_sample(const double *x) const;
  void wall_pressure_loads();
  void probe_sums(double h);
  void begin_samples();
  void end_samples();
  void choose_every();
  double wall_speed2() const;
  void auto_limits(const double *glob);
};

// The kernels' one dispatch on the stencil size: fn(std::integral_constant<int, NS>) with NS = 3
// for the quadratic B-spline, 2 for linear shape functions.
template <class Fn>
inline void with_stencil(ShapeKind k, Fn &&fn) {
  if (k == ShapeKind::QuadraticBSpline)
    fn(std::integral_constant<int, 3>());
  else
    fn(std::integral_constant<int, 2>());
}

// the anti-locking cell sums (update_stress, musl_gradient), inline in both hot loops
inline std::size_t FluidSolver::cell_node(int i) const {
  const GridSpec &gs = opt.grid;
  const double inv = 1.0 / gs.dx;
  const double *xi = pts.x[i];
  int c[3];
  for (int d = 0; d < 3; ++d) c[d] = static_cast<int>(std::floor((xi[d] - gs.origin[d]) * inv));
  for (int d = 0; d < 3; ++d)
    if (!gs.periodic[d]) c[d] = std::min(std::max(c[d], 0), gs.ncell[d] - 1);
  return grid_.index(c[0], c[1], c[2]);
}

// L == nullptr: the fluid fraction only (refresh_pressure), no divergence sums
inline void FluidSolver::sum_cell(int i, const double *L) {
  const double *s = pts.state[i];
  const std::size_t n = cell_node(i);
  pw_.pcell[i] = n;
  double *c = &g_.cell[CellRec::N * n];
  const double V = s[C_VOL];
  c[CellRec::V] += V;
  if (L) c[CellRec::VDIV] += V * (L[0] + L[4] + L[8]);
  c[CellRec::THV] += s[C_THETA] * V;
  c[CellRec::M] += pts.rmass[i];
}

}  // namespace mpm
