// The pressure axis of the fluid (keyword pressure): one interface, chosen once when the solver is
// made (PressureModel::make), with two implementations. EosPressure: the weakly compressible fluid,
// whose points carry the pressure of the equation of state (7-23) as a stress of the internal force,
// with the walls' traction and the grid faces' conditions on the nodes' velocity. ProjectionPressure:
// the incompressible fluid, whose pressure the projection's solve gives (mpm/projection.h); it owns
// its Projection and the state that a new grid patch or a restart carries on. The phases of
// FluidSolver call the model once per phase (docs/design.md, "The solver's axes").
#pragma once
#include <mpi.h>

#include <memory>
#include <vector>

#include "mpm/fluid_laws.h"
#include "mpm/options.h"
#include "mpm/projection_state.h"

namespace mpm {

class FluidSolver;
class LocalGrid;
class Projection;
struct Clock;
struct SolverState;

class PressureModel {
 public:
  static std::unique_ptr<PressureModel> make(const Options &opt);
  virtual ~PressureModel();

  // incompressible: the solve's pressure corrects the velocity u*; the points' pressure is no
  // stress of the internal force, the walls take no traction of the points, the grid faces'
  // conditions and the grains' pressure reaction come with the solve (the kernels' switches)
  bool incompressible() const { return incompressible_; }
  // what the coupling and the MUSL pass take from the model (constant for the model's life):
  // the points' pressure is a stress of the internal force (eos: its anti-locking cell sums are
  // taken in the MUSL pass, its grains' pressure reaction is a force on the fluid)
  bool pressure_is_stress() const { return !incompressible_; }
  // the grains' pressure reaction goes to the solve, and the fluid's acceleration held over the
  // drag exchange includes the last solve's gradient (projection)
  bool reaction_in_solve() const { return incompressible_; }
  // the density of a point pre-compressed to pressure p (hydrostatic set-up)
  virtual double density(const Eos &eos, double p) const = 0;
  // the sound speed over the points' density range (0: no sound waves, no acoustic limit)
  virtual double sound_speed(const Eos &eos, double rho_lo, double rho_hi) const = 0;

  // setup_grid: before the patch changes, and on the new patch (collective)
  virtual void leave_patch() {}
  virtual void enter_patch(LocalGrid &grid, MPI_Comm comm, const Options &opt, SolverState &state) {}
  // the state a restart file keeps, on the whole grid (collective)
  virtual ProjectionState restart_state(const Options &opt, MPI_Comm comm, SolverState &state) {
    return ProjectionState();
  }
  // the time the volume correction of this fluid step stands for (0: not due)
  virtual double volume_correction_due(const Options &opt, const Clock &clock, SolverState &state) { return 0.0; }

  // the phases' pressure work: P2G (the points' pressure in the internal force, the walls'
  // traction), the grid update (the nodes' boundary conditions; u* and the projection), after it
  // (the points' pressure from the nodes), the stress update
  virtual void particles_to_grid(FluidSolver &s) = 0;
  virtual void update_grid(FluidSolver &s, double h, double vc_time) = 0;
  virtual void point_pressure(FluidSolver &s) {}
  virtual void update_stress(FluidSolver &s, double h, bool theta_only) = 0;

  // the solve (nullptr: none) and its counters since the solver was made (0 without a solve)
  virtual Projection *solve() { return nullptr; }
  virtual const std::vector<double> *volume_drift() const { return nullptr; }
  virtual double solver_seconds() const { return 0.0; }
  virtual long solves() const { return 0; }
  virtual long iterations_summed() const { return 0; }

 protected:
  explicit PressureModel(bool incompressible) : incompressible_(incompressible) {}

 private:
  const bool incompressible_;
};

}  // namespace mpm
