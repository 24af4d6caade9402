/* fix mpm/fluid: a Material Point Method fluid (dissertation chapters 7-8)
   whose material points are LIGGGHTS atoms of their own group. LIGGGHTS
   migrates them between ranks, writes them to restart and dump files and
   keeps them in regions; this fix owns the background grid and the per-point
   state (volume, density, pressure, deviatoric stress, affine velocity).
   See docs/fix_mpm_fluid.md and docs/design.md. */

#ifdef FIX_CLASS

FixStyle(mpm/fluid,FixMpmFluid)

#else

#ifndef LMP_FIX_MPM_FLUID_H
#define LMP_FIX_MPM_FLUID_H

#include "fix.h"

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "mpm/drag_laws.h"
#include "mpm/fluid_laws.h"
#include "mpm/grid.h"
#include "mpm/shape_functions.h"
#include "mpm/stencil.h"
#include "mesh_walls.h"

namespace mpm { class Hdf5Series; }

namespace LAMMPS_NS {

class FixMpmFluid : public Fix {
 public:
  // Columns of the per-point state (also the fix's per-atom array, 1-based in f_ID[n]).
  enum Column {
    C_VOL = 0,     // current volume of the point, m3
    C_RHO = 1,     // fluid (micro) density, kg/m3
    C_P = 2,       // pressure, Pa
    C_TAU = 3,     // deviatoric stress xx yy zz yz xz xy (6), Pa
    C_AFF = 9,     // APIC affine velocity / velocity gradient, row-major (9), 1/s
    C_THETA = 18,  // fluid volume fraction at the point
    C_FLAG = 19,   // 1 for a point set up by this fix
    C_FGRAIN = 20, // on a grain of the coupled group: force of the fluid on it (3), N
    NCOL = 23
  };

  FixMpmFluid(class LAMMPS *, int, char **);
  ~FixMpmFluid() override;
  int setmask() override;
  void post_create() override;
  void init() override;
  void setup(int) override;
  void post_run() override;
  void pre_final_integrate() override;
  void end_of_step() override;

  double compute_vector(int) override;
  int modify_param(int, char **) override;

  void grow_arrays(int) override;
  void copy_arrays(int, int, int) override;
  void set_arrays(int) override;
  int pack_exchange(int, double *) override;
  int unpack_exchange(int, double *) override;
  int pack_restart(int, double *) override;
  void unpack_restart(int, int) override;
  int size_restart(int) override;
  int maxsize_restart() override;
  void write_restart(FILE *) override;
  void restart(char *) override;
  double memory_usage() override;

  // Time-step limits of the current state (collective), for reports and tests.
  double stable_dt();

 private:
  using PointShape = mpm::Stencil;
  enum BcKind { BC_NOSLIP, BC_FREESLIP, BC_PARTIAL, BC_SHEAR };
  // BC_SHEAR: wall stress mu v_t / delta of an unresolved wall layer delta (docs/mesh_walls.md)
  struct Face { int kind = BC_NOSLIP; double sticky = 1.0; double delta = 0.0; };
  struct Gate {
    bool active = false;
    int dim = 0;
    double pos = 0.0;
    bool fluid_below = true;   // fluid held on the low-coordinate side
    double release_time = -1;  // simulation time of removal; < 0 = only by fix_modify
  };
  enum Transfer { TR_APIC, TR_PIC, TR_FLIP };

  // numeric keywords: one table (find_scalar) says target, range and message
  struct ScalarKeyword {
    const char *name;
    double FixMpmFluid::*target;
    double lo, hi;
    bool open_lo, open_hi;
    const char *expected;
  };
  static const ScalarKeyword *find_scalar(const char *kw);
  void parse_scalar(const ScalarKeyword &k, const char *value);
  static bool FixMpmFluid::*find_flag(const char *kw);  // yes/no keywords

  // settings
  double cell_size = 0.0, rho0_arg = 1000.0, bulk_arg = 2.2e9;  // copied into gspec / eos
  mpm::GridSpec gspec;
  bool grid_bounds_given = false;
  double gbounds[6];
  mpm::ShapeKind shape = mpm::ShapeKind::QuadraticBSpline;
  mpm::Eos eos;
  double viscosity = 0.0;
  double pmin = -HUGE_VAL;     // cavitation pressure: no tension below it
  Transfer transfer = TR_FLIP;  // the text's MUSL: FLIP velocity (8-40), grid velocity for x (8-41)
  double flip_alpha = 1.0;      // FLIP fraction of a FLIP/PIC blend
  bool musl = true;
  bool antilock = true;
  bool wall_traction = true;  // (8-23) at grid-face walls for bspline2
  bool grad_p_fit = true;       // grad p at the grains: fitted nodal gradients (fit) or of the nodal means (nodal)
  bool theta_transport = false;  // points carry theta (updated by div(theta u)) instead of re-interpolating it
  Face face[6];
  Gate gate;
  std::vector<mpm::MeshWallSpec> mesh_specs;
  std::unique_ptr<mpm::MeshWalls> mesh_walls;
  // per node: the mesh-wall constraints of the current wall positions (apply_grid_bc)
  long mw_epoch = 0;
  std::vector<long> mw_stamp;
  std::vector<int> mw_first, mw_count;
  std::vector<char> mw_near;
  std::size_t node_walls(int i, int j, int k);
  bool near_mesh_wall(const double *x);
  std::vector<mpm::WallConstraint> mw_cache;
  bool mesh_sides_done = false;
  void mesh_refresh();
  double damping = 0.0;
  double cfl = 0.5;
  bool subcycle = false;
  int max_subcycle = 1000;
  int fluid_every = 1;          // the fluid advances every N-th time step, by N dt (keyword every)
  double mass_threshold = 1e-5;
  int front_axis = 0;
  int height_axis = 2, wall_axis = 0;
  double wall_pos = 0.0;
  bool wall_pos_given = false;

  // filling
  std::string fill_region;
  int fill_ppc[3] = {2, 2, 2};
  int fill_type = 1;
  bool hydrostatic = false;
  int hydro_axis = 2;
  double hydro_surface = 0.0, hydro_g = 9.81;

  // two-way coupling with DEM grains (keyword couple); none of it runs without
  bool coupled = false;
  std::string couple_group;
  int couple_groupbit = 0;
  mpm::DragLaw drag_law = mpm::DragLaw::ErgunWenYu;
  mpm::DragForm drag_form = mpm::DragForm::Consistent;
  double theta_min = mpm::kDragThetaMin;
  double theta_smooth = 0.0;    // standard deviation of the smoothing of the solid fraction (0: none)
  std::vector<double> g_phi, g_phi_new;  // smoothing work arrays (per node)
  bool cell_check = true;
  bool theta_initialized = false;  // fluid mass reduced by the grains' volume once (restart)
  std::vector<PointShape> grain_shapes;
  static constexpr int kPfit = 20;
  std::vector<double> g_cpl;    // per node: moments of the points' pressure for its linear fit: r (4), M (4 x 4)
  std::vector<double> g_sol;    // per node: solid volume of the grains (reverse-summed, smoothed)
  std::vector<double> g_th;     // per node: fluid fraction (forwarded)
  std::vector<double> g_need;   // per node: > 0 where a grain's shape functions reach (reverse-summed)
  // per node (forwarded): u (3) and 1 where the node holds fluid; fitted grad p (3) and 1 where
  // the fit is determined; theta, p, m, pad
  enum { S_U = 0, S_FIT = 4, S_TH = 8, S_P = 9, S_M = 10 };
  static constexpr int kSt = 12;
  std::vector<double> g_st;
  std::vector<double> g_rx;     // per node: force of the grains on the fluid (3), owned nodes
  static constexpr int kDr = 12;
  int integrated_groupbits = 0;   // groups moved by some integrator: other grains are fixed
  std::vector<double> g_dr;     // per node: sum S K, sum S K v (3), sum S m, pressure reaction (3), sum S K a (3), sum S K of fixed grains
  std::vector<double> grain_force;  // per local grain: fluid force averaged over sub-steps (3)
  class FixPropertyAtom *fix_dragforce = nullptr;  // per-atom vector 'dragforce' (LIGGGHTS convention)

  // output
  int out_every = 0;
  std::string out_prefix;
  std::vector<std::string> out_point_fields, out_grid_fields;
  std::unique_ptr<mpm::Hdf5Series> series;
  bigint last_output_step = -1;

  // state (restart)
  bool filled = false;
  double point_mass_ref = 0.0;   // typical point mass, for the nodal mass threshold
  double spacing[3] = {0, 0, 0}; // initial point spacing per direction
  double n_clamped = 0;          // points put back inside a wall (cumulative)
  double time_fluid = 0.0;       // wall time of the fluid's own work on this rank (s, cumulative)
  double time_couple = 0.0;      // wall time of the coupling on this rank (s, cumulative)
  double run_time_start[2] = {0.0, 0.0};  // time_fluid, time_couple at the setup of the run

  // per-point state
  double **pdata = nullptr;
  int pdata_rows = 0;

  // grid work arrays
  mpm::LocalGrid grid;
  bool grid_ready = false;
  // node records padded to 4-wide rows for vectorized transfers
  static constexpr int kP2g = 8, kVel = 8, kAux = 4;
  std::vector<double> g_p2g;    // per node: m, mv(3), f(3), pad
  std::vector<double> g_vel;    // per node: v_new(3), pad, v_old(3), pad
  static constexpr int kCell = 5;
  std::vector<double> g_cell;   // per cell (keyed by its low node): V, V div, theta V, m, V div(theta u)
  std::vector<double> g_th_prev;  // theta_transport: nodal fraction of the last sub-step
  bool th_prev_valid = false;
  std::vector<double> divthu;   // theta_transport: div(theta u) at the points (MUSL pass)
  std::vector<double> g_aux;    // per node: remapped momentum (3), pad (MUSL)
  std::vector<PointShape> shapes;
  std::vector<int> plist;       // local indices of the material points (this sub-step)
  std::vector<double> vpic;     // grid (PIC) velocity at the points, for the position update
  std::vector<double> velgrad;  // velocity gradient at the points, for the stress update
  int nsub_last = 1;
  double dt_stable_last = 0.0;
  double c_max = 0.0;           // sound speed used by the last time-step check
  double dt_couple_last = HUGE_VAL;  // stable step of fluid and moving grains together (couple)
  double dt_grain_last = HUGE_VAL;   // stable step of the moving grains with the fluid sub-cycled
  double c_couple = 0.0;            // pore-pressure wave speed of fluid and grains, last check
  double c_grain = 0.0;             // its grains' part (fluid held), last check
  double couple_theta_min = 1.0;    // lowest fluid fraction at a point at the last check
  double couple_rho_grain = 0.0;    // lightest moving grain's density at the last check (0: none)

  // cached global outputs
  bigint vector_step = -1;
  double vector_cache[16];

  void parse_args(int narg, char **arg);
  void parse_face(const char *name, const char *kind, int narg, char **arg, int &iarg);
  void fill_points();
  void setup_grid();
  void check_timestep(bool at_setup);
  void substep(double h);
  void compute_shapes();
  bool shape_of(const double *x, PointShape &ps);
  void couple_fluid_grains(double h);
  void smooth_solid_volume();
  void add_mesh_wall_traction(const double *xp, double V, double p);
  void fluid_fraction();
  void init_theta();
  double solid_node_volume(int i, int j, int k) const;
  bool is_grain(int i) const;
  void particles_to_grid();
  void add_wall_traction(const PointShape &ps, const double *xp, double V, double p);
  void update_grid(double h);
  // h: time step of the grid update (the stress of shear mesh walls acts over h)
  void apply_grid_bc(double *v, int nodeidx_i, int nodeidx_j, int nodeidx_k, double h);
  void grid_to_particles(double h);
  void remap_velocity_musl(double h);
  // transfer kernels, instantiated per stencil size and transfer (docs/performance.md)
  template <int NS, bool AFFINE> void p2g_kernel();
  template <int NS, bool NEED_L, bool NEED_B, bool SCATTER, bool SCATTER_AFFINE> void g2p_kernel();
  template <int NS> void musl_kernel(double h);
  template <int NS> void pressure_moments();
  template <int NS> void couple_kernel(double h);
  template <class Fn> void for_nodes(const PointShape &ps, Fn &&fn) const;
  void update_stress(double h, bool theta_only = false);
  void advance_positions(double h);
  void write_output();
  void compute_outputs();
  bool is_point(int i) const;
  double sim_time() const;
  [[noreturn]] void fail_one(const std::string &msg);
  [[noreturn]] void bad_arg(const char *keyword, const char *expected, const char *given);
};

}  // namespace LAMMPS_NS

#endif
#endif
