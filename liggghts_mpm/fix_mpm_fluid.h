/* fix mpm/fluid: a Material Point Method fluid (dissertation chapters 7-8) whose material points
   are LIGGGHTS atoms of their own group. LIGGGHTS migrates them between ranks, writes them to
   restart and dump files and keeps them in regions; the fluid itself is mpm::FluidSolver
   (mpm/solver.h), which knows nothing of LIGGGHTS. This class is the adapter: the fix's hooks, the
   per-point state rows (grow, copy, pack, restart), views of the atom arrays for the solver, the
   filling, the mesh walls, and the translation of the solver's errors into LIGGGHTS errors.
   See docs/fix_mpm_fluid.md and docs/design.md. */

#ifdef FIX_CLASS

FixStyle(mpm/fluid,FixMpmFluid)

#else

#ifndef LMP_FIX_MPM_FLUID_H
#define LMP_FIX_MPM_FLUID_H

#include "fix.h"

#include <memory>
#include <string>
#include <vector>

#include "mesh_walls.h"
#include "mpm/run_stats.h"
#include "mpm/solver.h"

namespace LAMMPS_NS {

class FixMpmFluid : public Fix {
 public:
  FixMpmFluid(class LAMMPS *, int, char **);
  ~FixMpmFluid() override;
  int setmask() override;
  void post_create() override;
  void init() override;
  void setup(int) override;
  void post_run() override;
  void pre_final_integrate() override;
  // inflow and outflow faces (fix_mpm_fluid_flow.cpp): points removed and created
  void setup_pre_exchange() override;
  void pre_exchange() override;
  // fix balance/mpm moved the subdomain cuts inside a run: the grid patch follows at the next step
  void subdomain_changed();
  // this rank's work in the fluid and the coupling since the fix was made: their wall time less
  // the waits for the halo exchanges (s; fix balance/mpm measured)
  double busy_seconds() const;
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

 private:
  std::unique_ptr<mpm::FluidSolver> solver;
  std::vector<mpm::MeshWallSpec> mesh_specs;
  bool grain_walls_checked = false;  // warn_unheld: the meshes checked (first setup)
  bool uncoupled_warned = false;     // warn_unheld: uncoupled atoms among the points named
  bool overlap_checked = false;      // warn_unheld: other fixes' grids compared (first setup)
  std::unique_ptr<mpm::MeshWalls> mesh_walls;
  int couple_groupbit = 0;
  class FixPropertyAtom *fix_dragforce = nullptr;  // per-atom vector 'dragforce' (LIGGGHTS convention)
  bool filled = false;
  // the solver's fluid, coupling and pressure-solver wall time, solves and PCG iterations at the setup of the run
  double run_time_start[8] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};  // [7]: halo waits (this rank)
  mpm::RunStatsStart run_stats_start;  // the halo exchanges' counters at the setup of the run (mpm/run_stats.h)
  double every_run[3] = {0.0, 0.0, 0.0};  // every auto: least and largest N, fluid steps in this run
  bool fluid_step_due(const mpm::FluidSolver &s) const;
  void note_every(mpm::FluidSolver &s);
  void mark_run_start();
  double **pdata = nullptr;  // per-point state rows (mpm::Column)
  int pdata_rows = 0;
  bigint vector_step = -1;   // f_ID[] cached for this step
  bool sealed_noted = false;  // the note on pockets sealed off from the free surface (printed once)
  std::vector<double> vector_cache;  // f_ID[] (FluidSolver::global_size)

  int parse_mesh_wall(int narg, char **arg, int iarg);
  void fill_points();
  void create_point(const double *x, double vol);
  void finish_fill(int nlocal_before, double vol);
  void check_fill_memory(class Region *region, const int lo[3], const int hi[3]);
  // inflow and outflow faces: the points that left removed, the inflow's layers due created (all
  // ranks, on a step that exchanges atoms); schedule_flow: after a fluid step, such a step next if
  // there is work for it
  void flow_exchange();
  void schedule_flow();
  int create_inflow_layer(int f, double pos);
  void refresh_walls();
  void add_grain_force();
  void fluid_step_ahead(mpm::FluidSolver &s);  // every N > 1: the fluid step with the grains (N-1)/2 steps ahead
  std::vector<double> shifted;  // the grains' positions while fluid_step_ahead moved them  // F of the last fluid step onto the coupled grains' f (every DEM step)
  void check_gate_side();
  void warn_unheld();
  void warn_fill_beyond_grid(class Region *region);
  mpm::FluidSolver &sync();  // the solver with views of the current atom arrays and clock
  template <class Fn> void guarded(Fn &&fn);  // runs fn, translating the solver's errors
  void print(const std::string &text) const;  // rank 0: to screen and log file
  [[noreturn]] void fail_one(const std::string &msg);
  bool is_point(int i) const;
  double sim_time() const;
  void exclude_points_from_pairs();
  void check_group_atoms();
  // The fix's own clock: LIGGGHTS' time restarts at 0 after read_restart, the fix's time goes on
  // (saved in the restart file); sim_time() = LIGGGHTS' time + time_offset.
  double time_offset = 0.0;
  double restart_time = 0.0;          // the fix's time in the restart file, applied at init()
  bool restart_time_pending = false;
  int point_type = 0;  // atom type of the material points (fill type, or from the restart file)
  // superficial_velocity v_name: the variable's index (looked up at init and before each fluid
  // step), its value the target of the step
  int drive_var = -1;
  void find_drive_variable();
  void drive_target();
};

}  // namespace LAMMPS_NS

#endif
#endif
