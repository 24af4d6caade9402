// The pressure model 'projection' of fix mpm/fluid (docs/theory/projection.md): the glue between the
// solver's grid update and the discrete operators (projection_ops.h) and the hypre solve
// (pressure_solver.h). Per fluid sub-step: labels from the node mass, the box walls, the gate and
// the mesh walls;
// u* -> solve div(beta grad p) = div(theta u*) / dt -> correction u = u* - (dt / rho) grad p ->
// wall conditions (Boundaries::apply). Keeps p between steps for the warm start.
#pragma once
#include <mpi.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "mpm/boundaries.h"
#include "mpm/grid.h"
#include "mpm/options.h"
#include "mpm/pressure_solver.h"
#include "mpm/projection_ops.h"
#include "mpm/projection_state.h"

namespace mpm {

class Projection {
 public:
  // grid: the solver's patch (set up); collective over comm.
  Projection(LocalGrid &grid, MPI_Comm comm, const Options &opt);

  // vel: the VelRec rows of the grid update, V_NEW = u* at the owned nodes (0 where the node
  // mass p2g M <= mmin: those become EMPTY nodes, p = 0). On return V_NEW holds the corrected,
  // wall-conditioned velocity at the owned nodes (not forwarded). theta: nodal fluid fraction
  // (null: 1), with the d(theta)/dt source from theta of the last solve (none at the first).
  // pvol: sum S V of the points per node (owned nodes, after the reverse sum), for the
  // volume correction (keyword volume_correction; null: none). Throws mpm::Error naming the
  // step if the solve does not converge.
  // work (sparse sweeps, docs/validation/performance.md "Sparse grid"): a box of the patch that holds every
  // node with fluid mass grown by kWorkMargin nodes; the sweeps then visit its nodes only and every
  // array keeps outside it the value the full sweep gives there (no fluid within reach: 0, EMPTY).
  // Not with theta (couple) or mesh walls. null: the whole patch.
  // vc_time: the time the volume correction of this step stands for (with pvol; see
  // volume_correction_every).
  void project(double *vel, const double *p2g, double mmin, const double *theta, double h,
               Boundaries &bc, long step, const double *pvol = nullptr, const IndexBox *work = nullptr,
               double vc_time = 0.0);
  // The volume correction at rate k runs on every M-th fluid step of length hf, M = max(1,
  // floor(kVolumeShare / (k hf))), and then removes the share min(k M hf, 1) of the error: the
  // same rate, with one solve every M steps instead of every step.
  static long volume_correction_every(double k, double hf);
  static constexpr double kVolumeShare = 0.05;
  // the nodes the work box must reach beyond the nodes with mass: the farthest any sweep reads or
  // writes from them (the surface's gradient and extrapolation 1, deep_inside 2) and one more
  static constexpr int kWorkMargin = 4;

  // Wall loads (Boundaries::recording; docs/theory/mesh_walls.md, "Force and torque on a mesh"):
  // the momentum the pressure correction of the last project() gave the fluid, sum over the owned
  // nodes n of J_n = m_n (u_n - u*_n), written as sum_n p_n c_n + r_n: load_coefficients() holds
  // c_n (3 per node, owned nodes: the weight of p_n in the J of all nodes, pressure_gradient's
  // face weights; sum over all nodes 0), load_rest() r_n (the whole J_n of a node whose gradient
  // is not of that form: filled next to a wall, extrapolated above the surface), load_pressure(n)
  // p_n (the solve's at FLUID nodes, 0 at the others). Sized only while loads are recorded.
  const std::vector<double> &load_coefficients() const { return lc_; }
  const std::vector<double> &load_rest() const { return lr_; }
  double load_pressure(std::size_t n) const { return lab_.kind[n] == kFluid ? p_[n] : 0.0; }
  // whether node (i, j, k) = n lies behind a mesh wall (its J in load_rest is the change to the
  // velocity of the fluid in front, set_velocities)
  bool load_behind(int i, int j, int k, std::size_t n) const { return behind_mesh(i, j, k, n); }

  // The state of the last solve on this rank's owned nodes (ProjectionState, projection_state.h).
  void save(ProjectionState &s) const;
  // Takes the state of an earlier solve (s.box must hold every owned node; collective: fills
  // the halos); false (nothing changed) if it does not.
  bool load(const ProjectionState &s);

  // nodal pressure of the last solve (owned nodes and halos), the padding nodes behind the box
  // walls with the pressure of the wall node in front (for interpolation to points); with
  // pressure_output acceleration the pressure of the fluid's acceleration (acceleration_pressure)
  const std::vector<double> &pressure() const { return opt_.pressure_acceleration ? p_acc_ext_ : p_ext_; }
  // the force of the grains' pressure force on the fluid (its reaction, 3 per node, owned nodes)
  // for the next project: with grains, the fluid receives it along the periodic directions
  // (exact_correction); null: none
  void set_grain_reaction(const double *r) { grain_reaction_ = r; }
  // nodal pressure gradient for the grains (owned nodes and halos; padding nodes with the wall
  // node's): of the last solve, the one the fluid felt; with grain_pressure acceleration that of
  // the pressure of the fluid's acceleration
  const std::vector<double> &gradient() const {
    return opt_.grain_pressure_acceleration ? grad_acc_ext_ : grad_ext_;
  }
  // The grains' immersion (FluidSolver::grain_drag_sums): per node (owned nodes and halos) the
  // signed distance to the free surface in cells that a grain reads, positive in the fluid, of
  // the last solve (grain_levels; NaN: a SOLID node, not read); null before the first solve with
  // grains
  const double *grain_level() const {
    return gl_.size() == grid_.size() && !gl_.empty() ? gl_.data() : nullptr;
  }
  // largest nodal pressure of the last solve on this rank's owned nodes, averaged in time
  // (keyword pressure_average tau: exponential average with time constant tau; 0: as solved)
  double largest_average_pressure() const { return p_avg_max_; }
  // volume correction (keyword volume_correction): the velocity, owned nodes and halos, that
  // moves the points this step on top of the fluid's and is not the fluid's (it enters the points'
  // positions only, never their velocity or momentum); empty when there is no correction
  const std::vector<double> &volume_drift() const { return drift_; }
  int iterations() const { return last_.iterations; }
  // FLUID nodes (all ranks) and sets of them that closed faces sealed off from the free surface
  // in the last solve (PressureResult::sealed, sealed_sets)
  long sealed_nodes() const { return last_.sealed; }
  long sealed_sets() const { return last_.sealed_sets; }
  double residual() const { return last_.relative_residual; }
  // since construction, this rank: wall time in the pressure solver (hypre assembly, setup and
  // PCG), number of solves (with the acceleration pressure two per fluid step), PCG iterations
  // summed over them
  double solver_seconds() const { return solver_seconds_; }
  long solves() const { return solves_; }
  long iterations_summed() const { return iterations_summed_; }

 private:
  // with: an array forwarded with the labels (NodeLabels::exchange)
  void make_labels(const double *p2g, double mmin, const double *theta, const WallGeometry *walls,
                   LocalGrid::Field with = {nullptr, 0}, LocalGrid::Field with2 = {nullptr, 0});
  // The film's front (node surface, Options::front_rate > 0): front_ set at the owned FLUID nodes
  // that hold less than half a cell (make_labels) and have an open face to a dry EMPTY node; true if
  // any. u_old_: the P2G velocity (owned nodes and halos, forwarded with the labels).
  bool mark_front();
  std::vector<std::uint8_t> front_;
  std::vector<double> u_old_;
  bool front_any_ = false;
  // project's steps. solve_pressure: u* from vel into u_, the solve into p_, its gradient grad_ and
  // the points' and grains' copies (p_ext_, grad_ext_); returns the step of the correction,
  // h / (1 + h damping). set_velocities: the projected velocity with the wall conditions into
  // vel's V_NEW at the owned nodes holding mass (behind mesh walls and in the padding too);
  // padding_velocity: that of one padding node behind the box walls (grains: theta given)
  double solve_pressure(const double *vel, const double *p2g, double mmin, const double *theta, double h, long step);
  void load_terms(const double *vel, const double *p2g, double mmin, const double *theta, double h, double s);
  std::vector<double> lc_, lr_;
  void set_velocities(double *vel, const double *p2g, double mmin, const double *theta, double h, double hs,
                      Boundaries &bc);
  void padding_velocity(double *v, int i, int j, int k, bool grains, double h, double hs, Boundaries &bc,
                        const double *p2g, double mmin) const;
  // the P2G velocity (V_OLD) of a padding node made from the nodes inside as its new velocity is,
  // so that FLIP's increment there is that of the node inside
  void padding_old_velocity(double *vel, int i, int j, int k, bool grains, const double *p2g, double mmin) const;
  // mesh walls: closes the faces the triangles cross (with the wall velocity), makes the nodes
  // within 2 cells behind a one-sided wall SOLID, and fills frac_ (fluid-side share of a node's
  // dual cell, for the surface threshold)
  void mesh_wall_labels(const WallGeometry &walls);
  // with grains: gl_ at the owned nodes from the labels (make_labels, after their exchange), forwarded
  void grain_levels();
  std::vector<double> gl_;
  bool behind_mesh(int i, int j, int k, std::size_t n) const;
  // a[stride n ...] at the nodes behind mesh walls := mean over their face neighbours that are
  // not SOLID and hold fluid (node mass above mmin; a massless node beyond the 2 cells behind a
  // wall is EMPTY but carries nothing), then over those already filled, 3 layers; owned nodes
  // and halos; collective
  // grad (stride 1 only): extrapolate linearly with this nodal gradient instead
  void extend_behind(std::vector<double> &a, int stride, const double *p2g, double mmin,
                     const std::vector<double> *grad = nullptr);
  void fill_wall_gradient(std::vector<double> &grad);
  // the nodal gradient of p (one-sided at the surface, halos forwarded), with the ghost surface
  // and above_surface extrapolated into the EMPTY layers above it (p as well if with_p), behind
  // mesh walls filled (fill_wall_gradient): the multiplier's for the fluid and the grains, the
  // acceleration pressure's for the grains and the mesh-wall extension of its points' values
  void form_gradient(std::vector<double> &p, std::vector<double> &grad, const double *p2g, double mmin,
                     bool above_surface, bool with_p);
  // one solve of the operator with rhs_ into p (warm start), timed into solver_seconds_; a solve
  // that does not converge is an error naming subject and the step
  PressureResult solve_rhs(double *p, long step, const char *subject, bool exact = false);
  // p and its nodal gradient for the points and grains: behind mesh walls extrapolated linearly
  // with the extended gradient (grad read only with mesh walls), then into the padding nodes
  void extend_for_points(const std::vector<double> &p, const std::vector<double> &grad, const double *p2g,
                         double mmin, std::vector<double> &p_out, std::vector<double> *grad_out);
  // The node of the box (indices clamped to 0..ncell in non-periodic dimensions) in front of a
  // padding node (itself if that node is outside the patch). Inline: extend_to_padding calls it
  // for every padding node.
  std::size_t wall_node(int i, int j, int k) const {
    const GridSpec &gs = opt_.grid;
    int q[3] = {i, j, k};
    for (int d = 0; d < 3; ++d)
      if (!gs.periodic[d]) q[d] = std::min(std::max(q[d], 0), gs.ncell[d]);
    return grid_.in_patch(q[0], q[1], q[2]) ? grid_.index(q[0], q[1], q[2]) : grid_.index(i, j, k);
  }
  void mirror_normal(double *v, int i, int j, int k, const double *p2g, double mmin) const;
  // node (i, j, k) lies on a grid face of that kind (keyword boundary ... inflow U | outflow)
  bool on_face(int i, int j, int k, BcKind kind) const {
    const int idx[3] = {i, j, k};
    for (int d = 0; d < 3; ++d)
      if (!opt_.grid.periodic[d] && ((idx[d] == 0 && opt_.face[2 * d].kind == kind) ||
                                     (idx[d] == opt_.grid.ncell[d] && opt_.face[2 * d + 1].kind == kind)))
        return true;
    return false;
  }
  double folded_mass(int i, int j, int k) const;
  double mirror_sum(const std::vector<double> &a, int i, int j, int k) const;
  void extrapolate_above_surface(const double *p2g, double mmin, std::vector<double> &p, std::vector<double> &grad,
                                 bool with_p);
  // its steps: the components along the surface of the first layer's gradient, one layer further
  void gradient_along_surface(std::vector<double> &grad);
  void extrapolation_pass(std::vector<double> &p, std::vector<double> &grad, bool with_p);
  void extend_to_padding(const std::vector<double> &a, std::vector<double> &out, int stride) const;
  // with grains: the padding nodes behind the box walls take the gradient of their mirror node
  // inside (the node their share of the grains' volume is folded to, FluidSolver::fluid_fraction),
  // so that a grain reads there the gradient of the node whose fluid fraction it changed
  void mirror_to_padding(const std::vector<double> &a, std::vector<double> &out) const;
  // sparse sweeps: the nodes of the last work box that are not in this one get the arrays' values
  // of a node without fluid within reach
  void retire(const IndexBox &work);
  void zero_for_sweep(std::vector<double> &a) const;
  IndexBox work_, work_prev_;       // this step's work box (the patch when not sparse), the last one
  bool have_prev_ = false;
  std::vector<double> gk_, pk_;     // extrapolate_above_surface: gradient / pressure known
  // extrapolate_above_surface: the owned EMPTY nodes holding fluid mass (the only ones a pass can
  // change), in the order of the owned nodes; each pass drops those it can no longer change
  struct SurfaceNode {
    std::size_t n;
    int i, j, k;
  };
  std::vector<SurfaceNode> surface_, ghost_, ghost_next_;
  std::vector<std::size_t> gnew_, pnew_;

  LocalGrid &grid_;
  const Options &opt_;
  ProjectionGeometry geo_;
  std::unique_ptr<PressureSolver> solver_;
  NodeLabels lab_;
  const double *theta_now_ = nullptr;  // the fluid fraction of this step (null: 1), for the gradient
  std::vector<double> u_, theta_, beta_, rhs_, p_, p_ext_, grad_, grad_ext_, inv_rho_;
  std::vector<double> fold_mass_;   // node mass, owned and halos (ghost surface's fill)
  // Exact exchange with grains along the periodic directions (exchange_weights, exact_correction):
  // per node and direction V_n / (folded mass) where the node takes the full-volume correction (0
  // elsewhere), the operator's coefficients, the plain nodal gradient; the grains' reaction
  bool exact_ = false;
  std::vector<double> wexact_, beta3_, gplain_, host_mass_;
  std::vector<std::size_t> host_;  // per EMPTY node holding fluid: its FLUID host (exchange_weights)
  std::vector<std::uint8_t> pass_of_;  // 0: the host is a face neighbour, 1: a neighbour's host
  const double *grain_reaction_ = nullptr;
  void exchange_weights(const double *theta, const double *p2g);
  void add_grain_reaction(const double *p2g, double hs);
  void exact_correction(const double *vel, const double *p2g, double hs);
  std::vector<double> frac_, u_ext_;  // mesh walls (make_labels, project)
  bool mesh_ = false;
  std::vector<double> theta_last_;  // theta of the last solve (the d(theta)/dt source)
  bool have_theta_last_ = false;
  std::vector<double> vol_;         // volume correction: sum S V with the padding folded back
  // volume correction with mesh walls: per node in front of walls its distances (cells) to the
  // walls off the box's faces, WallGeometry::kWallDirs per node (mesh_wall_labels,
  // WallGeometry::node_side), kWallFar beyond the shape's reach
  static constexpr double kWallFar = 2.0;
  std::vector<double> wall_dist_;
  // node (i, j, k) = n beside mesh walls: the fill it reads from an even fill of points (np per
  // cell) at rest, against which crowding (*crowd) and gaps (*gap) are read (left as they are,
  // 1, farther than kWallFar from every wall)
  void expected_fill(int i, int j, int k, std::size_t n, int np, double *crowd, double *gap) const;
  std::vector<double> q_, grad_q_, drift_;  // volume correction: its potential, gradient and drift
  void add_volume_correction(const double *pvol, const double *theta, double h, double share);
  void volume_drift(const double *pvol, const double *theta, double h, double share, long step);
  bool deep_inside(int i, int j, int k) const;
  bool near_flow_face(int i, int j, int k) const;  // within two nodes of an inflow or outflow face
  std::vector<double> p_avg_;       // pressure_average: the nodal pressure averaged in time (sized only then)
  bool have_avg_ = false;
  double p_avg_max_ = 0.0;
  void average_pressure(double h);
  // pressure_output acceleration: the pressure of the projected velocity's acceleration,
  // div(beta grad p) = div(theta (a_f - (u . grad) u)) (a_f: the grid forces per mass of this step,
  // vel's u* - u_old over h); u_ holds the projected velocity (owned and halos)
  // theta: the nodal fluid fraction of this solve
  void acceleration_pressure(const double *vel, const double *theta, double h, const double *p2g, double mmin,
                             long step);
  // the acceleration pressure is solved (pressure_output or grain_pressure acceleration)
  bool acceleration_on() const { return opt_.pressure_acceleration || opt_.grain_pressure_acceleration; }
  // sized only when acceleration_on() (grad_acc_ext_: grain_pressure acceleration)
  std::vector<double> acc_, p_acc_, p_acc_ext_, grad_acc_, grad_acc_ext_;
  void largest_pressure();  // p_avg_max_ from p_avg_ (averaging), else p_acc_ or p_ (the points' kind)
  PressureResult last_;
  double solver_seconds_ = 0.0;
  long solves_ = 0, iterations_summed_ = 0;
  MPI_Comm comm_;
};

}  // namespace mpm
