// The pressure equation of the projection, (L p)_n = rhs_n at the FLUID nodes
// (L of projection_ops.h), solved with hypre's Struct interface on the node
// lattice: one box per rank (its owned box of the LocalGrid), periodic
// dimensions as hypre periodicity, the 7-point operator stored symmetric,
// PCG preconditioned by one PFMG V-cycle (or SMG). EMPTY and SOLID nodes are
// identity rows with their couplings removed and their known values moved to
// the right-hand side, so the matrix stays symmetric positive (semi)definite.
// docs/theory/projection.md has the design and the measurements.
#pragma once
#include <mpi.h>

#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "mpm/grid.h"
#include "mpm/projection_ops.h"

namespace mpm {

struct PressureSettings {
  enum class Preconditioner { PFMG, SMG, None };
  double tolerance = 1e-8;   // relative residual ||b - A p|| / ||b|| (2-norms) at convergence
  int max_iterations = 200;  // PCG iterations
  Preconditioner preconditioner = Preconditioner::PFMG;
  // hypre's grid covers the FLUID nodes' bounding box (grown by kActiveMargin nodes) of each
  // rank's owned box, not the whole box (false: the whole owned box, as before)
  bool active_box = true;
};
constexpr int kActiveMargin = 3;

struct PressureResult {
  int iterations = 0;
  double relative_residual = 0.0;
  bool rebuilt = false;        // matrix assembled and preconditioner set up in this call
  bool singular = false;       // no EMPTY node anywhere: p fixed to zero mean over the FLUID nodes
  double rhs_mean_removed = 0.0;  // singular: the mean of the rhs made compatible (see solve); with
                                  // sealed sets only: the sum of |rhs sum| over the sets
  long sealed = 0;             // FLUID nodes (all ranks) in sets sealed off from every EMPTY node
  long sealed_sets = 0;        // the number of such sets (each made compatible, one node held at 0)
  double setup_seconds = 0.0;  // matrix assembly + preconditioner setup (rebuilt only)
  double solve_seconds = 0.0;  // PCG
  long enclosed = 0;           // FLUID nodes of this rank without an open face, solved as SOLID (p = 0)
};

// Thrown when PCG stops above the tolerance; what() names the iterations and
// the residual (the fix adds the step).
class PressureSolveError : public std::runtime_error {
 public:
  PressureSolveError(const std::string &msg, int iterations, double residual)
      : std::runtime_error(msg), iterations(iterations), residual(residual) {}
  int iterations;
  double residual;
};

class PressureSolver {
 public:
  // The grid must outlive the solver; collective over comm (the grid's).
  PressureSolver(LocalGrid &grid, MPI_Comm comm, const PressureSettings &settings,
                 const ProjectionGeometry &geometry);
  ~PressureSolver();
  PressureSolver(const PressureSolver &) = delete;
  PressureSolver &operator=(const PressureSolver &) = delete;

  /* Collective. labels: valid on owned nodes + one halo layer (NodeLabels::exchange),
     beta = theta / rho per node (owned + one halo layer), rhs per owned node (pressure_rhs),
     p: in, the first guess at the owned FLUID nodes (warm start: last step's pressure);
     out, the pressure on the owned nodes and the halos (forward()): the solution at FLUID
     nodes, p_empty (0 when null) at EMPTY nodes, 0 at SOLID nodes.
     The hypre grid is rebuilt when the owned boxes change, the matrix and the
     preconditioner when labels, beta or the geometry differ from the last call.
     Without any EMPTY node the operator has the constants as null space: the mean of rhs
     over the FLUID nodes is removed (reported) and p is returned with zero mean.
     beta3 (null: beta in every direction): per node and direction (3 n + d) the coefficient of the
     faces along d (the face's coefficient the mean of its two nodes', as with beta). */
  PressureResult solve(const NodeLabels &labels, const double *beta, const double *rhs, double *p,
                       const double *p_empty = nullptr, const double *beta3 = nullptr);

  const PressureSettings &settings() const { return settings_; }
  const ProjectionGeometry &geometry() const { return geo_; }

 private:
  struct Hypre;
  void build_grid(const IndexBox &box);
  bool assemble_values(const NodeLabels &labels, const double *beta, const double *beta3);
  void setup_solver();
  bool any_periodic() const;
  long node_key(int i, int j, int k) const;
  long seal_components(const NodeLabels &labels);
  long flood_from_surface(const NodeLabels &labels);
  void least_keys(const NodeLabels &labels);
  // solve's steps, in order (pressure_solver.cpp)
  const NodeLabels &wall_in_enclosed(const NodeLabels &labels_in, NodeLabels &walled, PressureResult &res) const;
  void update_active_box(const NodeLabels &labels);
  void prepare_operator(const NodeLabels &labels, const double *beta, const double *beta3, PressureResult &res);
  void load_vectors(const NodeLabels &labels, const double *beta, const double *beta3, const double *rhs,
                    const double *p, const double *p_empty, PressureResult &res);
  void run_pcg(PressureResult &res);
  void store_solution(const NodeLabels &labels, double *p, const double *p_empty);
  std::map<long, std::pair<double, long>> component_sums(const std::map<long, std::pair<double, long>> &mine) const;
  bool unknown(const NodeLabels &labels, int i, int j, int k, std::size_t n) const;

  LocalGrid &grid_;
  MPI_Comm comm_;
  PressureSettings settings_;
  ProjectionGeometry geo_;
  std::unique_ptr<Hypre> h_;
  // sealed components (seal_components, pressure_solver_sealed.cpp): per patch node the smallest
  // global key of the FLUID nodes its open faces connect it to, -1 where that set reaches an EMPTY
  // node; the node whose own key it is (one per sealed component) is held at p = 0. Empty: no
  // sealed component.
  std::vector<double> comp_;
};

}  // namespace mpm
