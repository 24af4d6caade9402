// The coupling axis of the fluid (keyword couple): one interface, chosen once when the solver is
// made (CouplingModel::make), with two implementations. NoCoupling: a fluid without grains, whose
// phases do nothing and cost nothing. GrainCoupling: the fluid fraction of the grains' volume
// (8-11)-(8-16), the pressure force on the grains and the implicit drag exchange (8-25)-(8-29)
// (coupling.cpp, fluid_fraction.cpp). The object owns the coupling's per-grain arrays; FluidSolver's
// step and sub-step call it once per phase (docs/design.md, "The solver's axes").
#pragma once
#include <memory>
#include <vector>

#include "mpm/options.h"
#include "mpm/stencil.h"

namespace mpm {

class FluidSolver;
struct GridFields;

class CouplingModel {
 public:
  static std::unique_ptr<CouplingModel> make(const Options &opt);
  virtual ~CouplingModel();

  // set-up, before the first fluid step of a run: the fluid mass reduced to theta rho0 V once
  virtual void setup(FluidSolver &s) {}
  // fluid step: the grains' force cleared before the sub-steps; after them (and after the driving
  // gradient's share, drive_share) the mean over the sub-steps to the grains' state rows
  virtual void begin_step(FluidSolver &s) {}
  virtual void end_step(FluidSolver &s) {}
  // superficial_velocity: the grains' share G V_k of the driving gradient along axis a
  virtual void drive_share(FluidSolver &s, int a) {}
  // sub-step phases, their wall time added to timer: the fluid fraction at nodes and points (and the
  // points' pressure for it) before P2G; the pressure force and the drag exchange after P2G
  virtual void fraction(FluidSolver &s, double &timer) {}
  virtual void exchange(FluidSolver &s, double h, double &timer) {}
  // the grid update's: the exchange's nodal force on the fluid (nullptr: none) and the nodal fluid
  // fraction (nullptr: 1 everywhere)
  virtual const double *fluid_force(const GridFields &g) const { return nullptr; }
  virtual const double *node_theta(const GridFields &g) const { return nullptr; }

  // the state of the coupling phases: the grains' stencils and the fluid force on them (3 per local
  // grain, averaged over the sub-steps); fluid_fraction's smallest and largest stencil base of this
  // rank's grains inside the grid (couple_kernel's box of the grains' nodes)
  std::vector<Stencil> grain_shapes;
  std::vector<double> grain_force;
  int base_lo[3] = {0, 0, 0}, base_hi[3] = {-1, -1, -1};
};

}  // namespace mpm
