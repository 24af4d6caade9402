#include "mpm/projection.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "mpm/error.h"
#include "mpm/grid_fields.h"

namespace mpm {

Projection::Projection(LocalGrid &grid, MPI_Comm comm, const Options &opt)
    : grid_(grid), opt_(opt), geo_{opt.grid, true}, comm_(comm) {
  PressureSettings ps;
  ps.tolerance = opt.pressure_tolerance;
  ps.max_iterations = opt.pressure_max_iterations;
  solver_.reset(new PressureSolver(grid_, comm_, ps, geo_));
  const std::size_t n = grid_.size();
  u_.assign(3 * n, 0.0);
  grad_.assign(3 * n, 0.0);
  theta_.assign(n, 1.0);
  beta_.assign(n, 1.0 / opt.rho0);
  inv_rho_.assign(n, 1.0 / opt.rho0);
  rhs_.assign(n, 0.0);
  p_.assign(n, 0.0);
  p_ext_.assign(n, 0.0);
  grad_ext_.assign(3 * n, 0.0);
  if (opt.pressure_average > 0.0) p_avg_.assign(n, 0.0);
  if (acceleration_on()) {
    acc_.assign(3 * n, 0.0);
    p_acc_.assign(n, 0.0);
    p_acc_ext_.assign(n, 0.0);
    grad_acc_.assign(3 * n, 0.0);
  }
  if (opt.grain_pressure_acceleration) grad_acc_ext_.assign(3 * n, 0.0);
}

void Projection::retire(const IndexBox &work) {
  if (!have_prev_) return;
  const std::pair<std::vector<double> *, int> arrays[] = {
      {&u_, 3}, {&grad_, 3}, {&grad_ext_, 3}, {&rhs_, 1}, {&p_, 1}, {&p_ext_, 1},
      {&acc_, 3}, {&p_acc_, 1}, {&p_acc_ext_, 1}, {&grad_acc_, 3}, {&grad_acc_ext_, 3},
      {&fold_mass_, 1}, {&gk_, 1}, {&pk_, 1}};
  const std::vector<IndexBox> gone = work_prev_.cut(grid_.patch()).minus(work);
  for (const auto &a : arrays) grid_.zero_boxes(*a.first, a.second, gone);  // (unused arrays are empty)
}

// a (one value per node) as a sweep starts it, 0 at every node it visits: the whole array, or with
// a work box the box (sized on first use; outside the box it holds what retire left, 0, or is not read)
void Projection::zero_for_sweep(std::vector<double> &a) const {
  if (!grid_.restricted()) {
    a.assign(grid_.size(), 0.0);
    return;
  }
  a.resize(grid_.size(), 0.0);
  grid_.zero_boxes(a, 1, {work_});
}

void Projection::form_gradient(std::vector<double> &p, std::vector<double> &grad, const double *p2g, double mmin,
                               bool above_surface, bool with_p) {
  pressure_gradient(grid_, lab_, p.data(), grad.data(), theta_now_);
  grid_.forward(grad.data(), 3);
  if (above_surface && opt_.surface_ghost) extrapolate_above_surface(p2g, mmin, p, grad, with_p);
  if (mesh_) fill_wall_gradient(grad);
}

PressureResult Projection::solve_rhs(double *p, long step, const char *subject, bool exact) {
  try {
    const double t0 = MPI_Wtime();
    const PressureResult r =
        solver_->solve(lab_, beta_.data(), rhs_.data(), p, nullptr, exact && exact_ ? beta3_.data() : nullptr);
    solver_seconds_ += MPI_Wtime() - t0;
    ++solves_;  // every solve (the acceleration pressure's too), as the time
    iterations_summed_ += r.iterations;
    return r;
  } catch (const PressureSolveError &e) {
    std::ostringstream os;
    os << "Fix mpm/fluid: " << subject << " did not converge at step " << step << ": " << e.iterations
       << " PCG iterations (keyword 'max_iterations' " << opt_.pressure_max_iterations << "), relative residual "
       << e.residual << " (keyword 'tolerance' " << opt_.pressure_tolerance << ")";
    if (std::isnan(e.residual)) {
      os << "; " << e.what();  // hypre failed (INF or NaN), not a slow convergence
    } else if (e.iterations < opt_.pressure_max_iterations) {
      // PCG stopped before max_iterations without converging: a breakdown (a step length <= 0),
      // which more iterations or a looser tolerance do not cure
      os << "; PCG broke down before 'max_iterations' (the preconditioned operator was not positive definite "
            "for this state), so neither more iterations nor another tolerance helps: please report the input";
    }
    throw Error(os.str());
  }
}

void Projection::extend_for_points(const std::vector<double> &p, const std::vector<double> &grad, const double *p2g,
                                   double mmin, std::vector<double> &p_out, std::vector<double> *grad_out) {
  if (!mesh_) {
    extend_to_padding(p, p_out, 1);
    if (grad_out) extend_to_padding(grad, *grad_out, 3);
    return;
  }
  // the pressure extrapolated linearly with the (extended) gradient: a hydrostatic pressure
  // stays exact behind an inclined wall
  std::vector<double> pb = p, gb = grad;
  extend_behind(gb, 3, p2g, mmin);
  extend_behind(pb, 1, p2g, mmin, &gb);
  extend_to_padding(pb, p_out, 1);
  if (grad_out) extend_to_padding(gb, *grad_out, 3);
}

long Projection::volume_correction_every(double k, double hf) {
  const double m = std::floor(kVolumeShare / (k * hf));
  return m >= 1.0 ? (m < 1e9 ? static_cast<long>(m) : 1000000000L) : 1L;
}

void Projection::project(double *vel, const double *p2g, double mmin, const double *theta, double h,
                         Boundaries &bc, long step, const double *pvol, const IndexBox *work, double vc_time) {
  // sparse sweeps: every for_owned of this step visits the work box only
  work_ = work ? work->cut(grid_.patch()) : grid_.patch();
  if (work) retire(work_);
  work_prev_ = work_;
  have_prev_ = true;
  LocalGrid::WorkScope scope(grid_, work ? &work_ : nullptr);
  // u* as it is; every wall condition comes after the projection: the wall's reaction is the
  // pressure, and a wall node's velocity zeroed before it (normal or, no-slip, tangential) would
  // be moved again by the correction (measured: the F1 column at rest, docs/theory/projection.md).
  // Forwarded with the labels (one exchange), for solve_pressure.
  const bool film = opt_.front_rate > 0.0;
  if (film) u_old_.resize(3 * grid_.size(), 0.0);  // (outside a work box never read: EMPTY nodes)
  grid_.for_owned([&](int, int, int, std::size_t n) {
    const double *v = vel + VelRec::N * n;
    for (int d = 0; d < 3; ++d) u_[3 * n + d] = v[VelRec::V_NEW + d];
    if (film)
      for (int d = 0; d < 3; ++d) u_old_[3 * n + d] = v[VelRec::V_OLD + d];
  });
  make_labels(p2g, mmin, theta, bc.walls(), {u_.data(), 3}, {film ? u_old_.data() : nullptr, 3});
  front_any_ = film && mark_front();
  const double hs = solve_pressure(vel, p2g, mmin, theta, h, step);
  correct_velocity(grid_, lab_, grad_.data(), inv_rho_.data(), hs, u_.data());
  if (exact_) exact_correction(vel, p2g, hs);
  grid_.forward(u_.data(), 3);
  if (pvol && opt_.volume_correction > 0.0 && vc_time > 0.0)
    volume_drift(pvol, theta, h, std::min(opt_.volume_correction * vc_time, 1.0), step);
  else
    drift_.clear();
  if (acceleration_on()) acceleration_pressure(vel, theta ? theta : theta_.data(), h, p2g, mmin, step);
  average_pressure(h);
  if (bc.recording()) load_terms(vel, p2g, mmin, theta, h, h / hs);
  set_velocities(vel, p2g, mmin, theta, h, hs, bc);
}

/* The pressure correction's momentum as nodal terms (load_coefficients): J_n = -m_n h / rho_n g_n
   (s = 1 + h damping times the velocity change m_n (u_n - u*_n), u* and the correction both
   divided by s; Boundaries::record_loads) with g_n,d = sum_side c_side side (p_m - p_n) / dx
   (gradient_weights): p_n gets +m_n h / rho_n c side / dx, p_m the opposite, so that the coefficients sum to 0 over all nodes (halo parts
   summed to their owners). A node whose gradient is not of that form keeps its J in load_rest. */
void Projection::load_terms(const double *vel, const double *p2g, double mmin, const double *theta, double h, double s) {
  lc_.assign(3 * grid_.size(), 0.0);
  lr_.assign(3 * grid_.size(), 0.0);
  const double inv_dx = 1.0 / opt_.grid.dx;
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    if (!(m > mmin && m > 0.0) || lab_.kind[n] == kSolid) return;
    const double *us = vel + VelRec::N * n + VelRec::V_NEW;  // u*
    const double mu = m * h * inv_rho_[n];
    for (int d = 0; d < 3; ++d) {
      double c[2];
      std::size_t nb[2];
      gradient_weights(grid_, lab_, theta, i, j, k, n, d, c, nb);
      double g = 0.0;
      for (int q = 0; q < 2; ++q) g += c[q] * (q ? 1.0 : -1.0) * (load_pressure(nb[q]) - load_pressure(n)) * inv_dx;
      const double J = s * m * (u_[3 * n + d] - us[d]);
      // (the exact exchange's components are not of that form)
      const bool exact = exact_ && wexact_[3 * n + d] > 0.0;
      if (exact || std::fabs(g - grad_[3 * n + d]) > 1e-9 * (std::fabs(g) + std::fabs(grad_[3 * n + d])) + 1e-300) {
        lr_[3 * n + d] += J;
        continue;
      }
      for (int q = 0; q < 2; ++q) {
        const double a = mu * c[q] * (q ? 1.0 : -1.0) * inv_dx;
        lc_[3 * n + d] += a;
        lc_[3 * nb[q] + d] -= a;
      }
    }
  });
  grid_.reverse_sum(lc_.data(), 3);
}

double Projection::solve_pressure(const double *vel, const double *p2g, double mmin, const double *theta, double h,
                                  long step) {
  const double *theta_prev = theta && have_theta_last_ ? theta_last_.data() : nullptr;
  // u_: u* on the owned nodes and halos (project, with the labels)
  const double *th = theta ? theta : theta_.data();
  theta_now_ = theta;
  if (theta)
    for (std::size_t n = 0; n < beta_.size(); ++n) beta_[n] = theta[n] / opt_.rho0;
  // the exact exchange's nodes (with grains) and the reaction of the grains' pressure force in u*:
  // the solve makes the velocity with it divergence-free (exact_correction)
  const double s = 1.0 + h * opt_.damping, hs = h / s;
  exchange_weights(theta, p2g);
  if (exact_) add_grain_reaction(p2g, hs);
  pressure_rhs(grid_, lab_, geo_, u_.data(), th, theta_prev, h, rhs_.data());
  // the film's front: the P2G velocity's divergence removed at the rate front_rate, not within the
  // step (docs/theory/projection.md, "The step size"); u_old over s as u* has it
  if (front_any_) {
    const double f = std::min(h * opt_.front_rate, 1.0);
    relax_front_source(grid_, lab_, geo_, front_.data(), u_old_.data(), th, (1.0 - f) / (s * h), rhs_.data());
  }
  // grid damping c (update_grid): u* = (u_old + h f / m) / s, s = 1 + h c, and the step is
  // s u = u_old + h f / m - h grad p / rho, i.e. u = u* - (h / s) grad p / rho. The solve gives
  // that p (the source times s, the correction with h / s): the pressure of a damped fluid at
  // rest is rho g depth. Solving with h instead gave p / s, the multiplier of the damped u*:
  // 1 / (1 + 1e-3 s x 20 1/s) = 0.980 of rho g depth in the closed mesh box at rest
  // (docs/theory/projection.md, "Mesh walls: the pressure beside a mesh floor").
  if (s != 1.0) grid_.for_owned([&](int, int, int, std::size_t n) { rhs_[n] *= s; });
  last_ = solve_rhs(p_.data(), step, "the pressure projection", true);
  // for the points and grains: the padding nodes behind the box walls carry the pressure (and
  // gradient) of the wall node in front (the solve holds them at 0; interpolated as they are,
  // they would lower the pressure of the points next to a wall by half a cell's hydrostatic step)
  // (first the nodes behind mesh walls, which the padding nodes behind them then copy)
  form_gradient(p_, grad_, p2g, mmin, true, true);
  if (exact_) {
    // the plain mean of the two face gradients (exact_correction reads it where both neighbours
    // along the direction are FLUID, where the EMPTY nodes' extrapolated pressure is not read)
    gplain_.assign(3 * grid_.size(), 0.0);
    pressure_gradient(grid_, lab_, p_.data(), gplain_.data(), nullptr);
    grid_.forward(gplain_.data(), 3);
  }
  extend_for_points(p_, grad_, p2g, mmin, p_ext_, &grad_ext_);
  if (theta && !mesh_) mirror_to_padding(grad_, grad_ext_);
  if (theta) {
    theta_last_.assign(theta, theta + grid_.size());
    have_theta_last_ = true;
  }
  return hs;
}

void Projection::set_velocities(double *vel, const double *p2g, double mmin, const double *theta, double h,
                                double hs, Boundaries &bc) {
  if (mesh_) {
    // nodes behind mesh walls: the projected velocity of the fluid in front, then the wall
    // condition (the normal velocity relative to the wall removed), as the padding nodes
    u_ext_ = u_;
    extend_behind(u_ext_, 3, p2g, mmin);
  }
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    double *v = vel + VelRec::N * n + VelRec::V_NEW;
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    if (!(m > mmin && m > 0.0)) return;  // no fluid: velocity stays 0
    if (mesh_ && behind_mesh(i, j, k, n)) {
      // the node takes the velocity of the fluid in front: its change of momentum, a wall's (load_rest)
      if (!lr_.empty())
        for (int d = 0; d < 3; ++d) lr_[3 * n + d] += bc.load_scale() * m * (u_ext_[3 * n + d] - v[d]);
      for (int d = 0; d < 3; ++d) v[d] = u_ext_[3 * n + d];
      bc.apply(v, i, j, k, h, m);
      return;
    }
    if (lab_.kind[n] == kSolid) {
      padding_velocity(v, i, j, k, theta != nullptr, h, hs, bc, p2g, mmin);
      padding_old_velocity(vel, i, j, k, theta != nullptr, p2g, mmin);
      return;
    }
    for (int d = 0; d < 3; ++d) v[d] = u_[3 * n + d];
    bc.apply(v, i, j, k, h, m);
  });
}

/* Padding node (i, j, k) behind the box walls (in the points' stencils), holding mass: the
   projected velocity of the wall node in front, with the wall condition. Its own u* is not
   projected; left as it is, it would let the points next to a free-slip wall fall through the rest
   state. An EMPTY wall node's velocity (extrapolated from the fluid) counts too: with 0 there the
   points along the back wall of the dam break hung back (wall height 0.15 a off at MPM24). */
void Projection::padding_velocity(double *v, int i, int j, int k, bool grains, double h, double hs, Boundaries &bc,
                                  const double *p2g, double mmin) const {
  const std::size_t c = wall_node(i, j, k);
  const bool wall_fluid = lab_.kind[c] != kSolid;
  // with grains (box walls only): the components along the walls (periodic or tangential)
  // keep the node's own u* corrected by the pressure gradient of its mirror node inside (the
  // node its share of the grains' volume is folded to, and whose gradient the grains read
  // here: mirror_to_padding), a pressure force on its mass and no other change of momentum.
  // Copying the wall node's velocity changed the momentum of this mass by m (u_wall - u*),
  // among others the drag the grains near the wall gave it: with a constant force on the
  // grains of a box periodic in x and y, cells of 3 grain diameters, 0.03 s, the x momentum of
  // fluid and grains 3.1 % above the impulse, 0.19 % without the copy (docs/theory/projection.md,
  // "Momentum of grains and fluid")
  const int q[3] = {opt_.grid.mirror(i, 0), opt_.grid.mirror(j, 1), opt_.grid.mirror(k, 2)};
  const int idx[3] = {i, j, k};
  double ut[3];
  std::size_t mq = c;
  if (grid_.in_patch(q[0], q[1], q[2])) mq = grid_.index(q[0], q[1], q[2]);
  const bool mq_fluid = lab_.kind[mq] != kSolid;
  for (int d = 0; d < 3; ++d) ut[d] = mq_fluid ? v[d] - hs * inv_rho_[mq] * grad_[3 * mq + d] : 0.0;
  if (exact_ && grains && mq_fluid) {
    // the exact exchange at the mirror node: this node's mass shares its full-volume correction
    // (the folded mass) and receives the reaction of the grains' pressure force here
    const std::size_t n = grid_.index(i, j, k);
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    for (int d = 0; d < 3; ++d)
      if (wexact_[3 * mq + d] > 0.0)
        ut[d] = v[d] - hs * wexact_[3 * mq + d] * gplain_[3 * mq + d] +
                (grain_reaction_ ? hs * grain_reaction_[3 * n + d] / m : 0.0);
  }
  for (int d = 0; d < 3; ++d) v[d] = wall_fluid ? u_[3 * c + d] : 0.0;
  if (grains && !mesh_)
    for (int d = 0; d < 3; ++d)
      if (q[d] == idx[d]) v[d] = ut[d];
  bc.apply(v, i, j, k, h);
  mirror_normal(v, i, j, k, p2g, mmin);
}

/* Padding node (i, j, k) behind the box walls: its P2G velocity (V_OLD) made as padding_velocity
   makes its new one from the nodes inside where that is a copy: the wall node's P2G velocity (the
   new one is the wall node's with the wall condition), the normal components the mirror node's
   reflected; the components that keep their own u* (with grains) keep their own. FLIP then gives
   the points near the wall the increment of the node inside. With the padding node's own P2G
   velocity, the difference between the copied velocity and it, of the same size at every step,
   reached the points at every step: kinetic energy in proportion to the number of steps
   (docs/theory/projection.md, "The step size"). */
void Projection::padding_old_velocity(double *vel, int i, int j, int k, bool grains, const double *p2g,
                                      double mmin) const {
  const std::size_t n = grid_.index(i, j, k), c = wall_node(i, j, k);
  const GridSpec &gs = opt_.grid;
  const int q[3] = {gs.mirror(i, 0), gs.mirror(j, 1), gs.mirror(k, 2)};
  const int idx[3] = {i, j, k};
  // behind an inflow or outflow face the node keeps its own P2G velocity (its new one is the
  // stream's: reflected about U, or the outflow's zero normal gradient). Measured in a column fed
  // from below and drained at the top (test mpm_case.flow_faces_balance), largest |vz - U| / U:
  // 1.9e-2 with the normal component reflected about 0 as at a wall, 1.2e-4 reflected about U,
  // 1.7e-11 with the node's own
  for (int d = 0; d < 3; ++d)
    if (q[d] != idx[d] && opt_.face[2 * d + (idx[d] < 0 ? 0 : 1)].flow()) return;
  // (it reads the P2G velocities of nodes that are not SOLID, which this loop leaves as they came)
  double *vo = vel + VelRec::N * n + VelRec::V_OLD;
  const double *old_c = vel + VelRec::N * c + VelRec::V_OLD;
  const bool wall_fluid = lab_.kind[c] != kSolid;
  for (int d = 0; d < 3; ++d)
    if (!(grains && !mesh_ && q[d] == idx[d])) vo[d] = wall_fluid ? old_c[d] : 0.0;
  if (!grid_.in_patch(q[0], q[1], q[2])) return;
  const std::size_t mn = grid_.index(q[0], q[1], q[2]);
  const double mm = p2g[P2gRec::N * mn + P2gRec::M];
  const bool fluid = lab_.kind[mn] != kSolid && mm > mmin && mm > 0.0;
  const double *old_m = vel + VelRec::N * mn + VelRec::V_OLD;
  for (int d = 0; d < 3; ++d)
    if (q[d] != idx[d]) vo[d] = fluid ? -old_m[d] : 0.0;
}

/* Padding node (i, j, k) behind the box walls: along each direction d in which it lies behind a
   wall, its velocity component d becomes minus that of its mirror node inside (the node reflected at
   the wall: index -i, or 2 ncell - i; all out-of-range indices reflected), 0 if the mirror node
   holds no fluid. The wall condition (bc.apply) had set it to 0: a point next to the wall then read
   the quadratic B-spline's share of the node above it (1/8 of its velocity on the wall itself) and
   crossed the wall, to be put back there (C3 with projection: f_fluid[8] 79,040 at Grid20 and
   6.4e5 at Grid48 by 0.2 s). With the odd reflection the interpolated normal velocity is 0 on the
   wall and linear near it: Grid20 0 put back, fronts within 3 mm (docs/validation/tank.md). */
void Projection::mirror_normal(double *v, int i, int j, int k, const double *p2g, double mmin) const {
  const GridSpec &gs = opt_.grid;
  const int q[3] = {gs.mirror(i, 0), gs.mirror(j, 1), gs.mirror(k, 2)};
  const bool out[3] = {q[0] != i, q[1] != j, q[2] != k};
  if (!grid_.in_patch(q[0], q[1], q[2])) return;
  const std::size_t mn = grid_.index(q[0], q[1], q[2]);
  const double mm = p2g[P2gRec::N * mn + P2gRec::M];
  const bool fluid = lab_.kind[mn] != kSolid && mm > mmin && mm > 0.0;
  const int idx[3] = {i, j, k};
  for (int d = 0; d < 3; ++d) {
    if (!out[d]) continue;
    // an outflow face: the wall node's velocity (copied by padding_velocity) stays, zero normal
    // gradient; an inflow face: reflected about its velocity U, so that U is interpolated on it
    const int f = 2 * d + (idx[d] < 0 ? 0 : 1);
    if (opt_.face[f].kind == BcKind::Outflow) continue;
    const double uf = opt_.face_velocity(f);
    v[d] = fluid ? 2.0 * uf - u_[3 * mn + d] : uf;
  }
}

/* Exact exchange of momentum with the grains (docs/theory/projection.md, "Momentum of grains and
   fluid"), along the periodic directions d of a run with grains and box walls only: at a FLUID
   node whose two neighbours along d are FLUID the fluid's momentum changes by
   -h V_n Gp_n,d + h r_n,d, Gp the plain mean of the two face gradients (sum_n V_n Gp_n,d telescopes
   to 0 along a periodic row), r the reaction of the pressure force the grains received at the
   node: the pressure creates no momentum along d whatever gradient the grains read. The velocity
   change is that over the folded mass (the node's and its mirror images' in the padding, which
   share it: padding_velocity); the operator's coefficient of those faces is theta_n V_n / m_n in
   place of theta_n / rho0, so that the corrected fluxes keep the divergence constraint. Along the
   walls' normals and elsewhere (the surface, EMPTY nodes, runs without grains) as before, 1 / rho0:
   a fluid at rest keeps the hydrostatic pressure exactly. */
void Projection::exchange_weights(const double *theta, const double *p2g) {
  const GridSpec &gs = opt_.grid;
  exact_ = theta && !mesh_ && opt_.surface_ghost && (gs.periodic[0] || gs.periodic[1] || gs.periodic[2]);
  if (!exact_) return;
  const double dx = gs.dx, dx3 = dx * dx * dx;
  wexact_.assign(3 * grid_.size(), 0.0);
  beta3_.assign(3 * grid_.size(), 0.0);
  // the EMPTY nodes holding fluid (the mass the B-spline spreads beyond the surface) share the
  // correction of a FLUID node, their host, as the padding nodes share their mirror node's: the
  // host's mass in the correction includes theirs. The host of one next to FLUID nodes is the
  // deepest of them (largest level); of one next to such EMPTY nodes only, the host of the one of
  // them with the largest level. Found on the whole patch (halos too), so that an owned node's
  // second layer is the same on every rank; one without either keeps the 1 / rho0 form
  constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  host_.assign(grid_.size(), kNone);
  pass_of_.assign(grid_.size(), 0);
  host_mass_.assign(grid_.size(), 0.0);
  auto wet_empty = [&](std::size_t n) { return lab_.kind[n] == kEmpty && lab_.wet[n]; };
  for (int pass = 0; pass < 2; ++pass)
    grid_.for_box(grid_.patch(), [&](int i, int j, int k, std::size_t n) {
      if (!wet_empty(n) || host_[n] != kNone) return;
      double best = -1e300;
      std::size_t h = kNone;
      for (int d = 0; d < 3; ++d)
        for (int side = -1; side <= 1; side += 2) {
          std::size_t m = n;
          if (!open_face(grid_, lab_, i, j, k, d, side, &m)) continue;
          const bool cand =
              pass == 0 ? lab_.kind[m] == kFluid : (wet_empty(m) && host_[m] != kNone && pass_of_[m] == 0);
          if (!cand || !(lab_.level[m] > best)) continue;
          best = lab_.level[m];
          h = pass == 0 ? m : host_[m];
        }
      if (h != kNone) {
        host_[n] = h;
        pass_of_[n] = static_cast<std::uint8_t>(pass);
      }
    });
  grid_.for_owned([&](int, int, int, std::size_t n) {
    if (host_[n] != kNone) host_mass_[host_[n]] += p2g[P2gRec::N * n + P2gRec::M];
  });
  grid_.reverse_sum(host_mass_.data(), 1);
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    for (int d = 0; d < 3; ++d) beta3_[3 * n + d] = beta_[n];
    if (lab_.kind[n] != kFluid) return;
    const double mf = folded_mass(i, j, k) + host_mass_[n];
    if (!(mf > 0.0)) return;
    for (int d = 0; d < 3; ++d) {
      if (!gs.periodic[d]) continue;
      bool inner = true;
      for (int side = -1; side <= 1 && inner; side += 2) {
        std::size_t m = n;
        inner = open_face(grid_, lab_, i, j, k, d, side, &m) && lab_.kind[m] == kFluid;
      }
      if (!inner) continue;
      const double w = geo_.volume(i, j, k) * dx3 / mf;
      wexact_[3 * n + d] = w;
      beta3_[3 * n + d] = theta[n] * w;
    }
  });
  grid_.forward(wexact_.data(), 3);
  grid_.forward(beta3_.data(), 3);
}

// u_ (u*) plus h r / m along the directions where the node (or its host) takes the exact exchange
// (exchange_weights), owned nodes, halos forwarded: the velocity the solve projects
void Projection::add_grain_reaction(const double *p2g, double hs) {
  if (!grain_reaction_) return;
  grid_.for_owned([&](int, int, int, std::size_t n) {
    const std::size_t c = lab_.kind[n] == kFluid ? n : host_[n];
    if (c == static_cast<std::size_t>(-1)) return;
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    for (int d = 0; d < 3; ++d)
      if (wexact_[3 * c + d] > 0.0) u_[3 * n + d] += hs * grain_reaction_[3 * n + d] / m;
  });
  grid_.forward(u_.data(), 3);
}

// the correction of the exact exchange (exchange_weights) at the owned FLUID nodes that take it:
// u = u* - h V Gp / m_fold + h r / m along those directions (u_ holds the 1 / rho0 form there)
void Projection::exact_correction(const double *vel, const double *p2g, double hs) {
  grid_.for_owned([&](int, int, int, std::size_t n) {
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    for (int d = 0; d < 3; ++d) {
      const double w = wexact_[3 * n + d];
      if (!(w > 0.0)) continue;
      const double us = vel[VelRec::N * n + VelRec::V_NEW + d];
      u_[3 * n + d] = us - hs * w * gplain_[3 * n + d] + (grain_reaction_ ? hs * grain_reaction_[3 * n + d] / m : 0.0);
    }
    // an EMPTY node holding fluid: its host's correction
    const std::size_t c = host_[n];
    if (c == static_cast<std::size_t>(-1)) return;
    for (int d = 0; d < 3; ++d) {
      const double w = wexact_[3 * c + d];
      if (!(w > 0.0)) continue;
      const double us = vel[VelRec::N * n + VelRec::V_NEW + d];
      u_[3 * n + d] = us - hs * w * gplain_[3 * c + d] + (grain_reaction_ ? hs * grain_reaction_[3 * n + d] / m : 0.0);
    }
  });
}

}  // namespace mpm
