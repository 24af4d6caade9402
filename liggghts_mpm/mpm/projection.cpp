#include "mpm/projection.h"

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
}

namespace {
// A node is EMPTY (p = 0) when it holds less than this fraction of the fluid mass of a full dual
// cell. The B-spline spreads a point's mass 1.5 cells: with the mass threshold alone the surface
// (p = 0) sits ~1.5 cells outside the fluid. Measured (docs/projection.md): F1 pressure error
// 0.43 / 0.22 (threshold only), 0.22 / 0.11 (0.25), 0.009 / 0.007 (0.5) at 8 / 16 cells, but 0.5
// leaves the column moving (0.07 m/s after 1 s) and the MPM16 dam-break front 0.39 a off; 0.25:
// at rest to 1e-12 m/s, front 0.037 a (apic).
constexpr double kSurfaceFill = 0.25;
}  // namespace

/* FLUID where the node holds fluid (mass above the threshold and kSurfaceFill of a full cell),
   EMPTY elsewhere (the free surface: p = 0), SOLID padding behind the box walls (NodeLabels::reset). The closed gate is a
   wall at rest: the face between the last node on the fluid side and the next one (a gate through
   a node plane leaves that node on the fluid side, like a box wall through its nodes). */
void Projection::make_labels(const double *p2g, double mmin, const double *theta, const WallGeometry *walls) {
  lab_.reset(grid_);
  mesh_ = walls != nullptr;
  if (mesh_) mesh_wall_labels(*walls);
  const double dx = opt_.grid.dx, full = opt_.rho0 * dx * dx * dx;
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] == kSolid) return;
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    const double th = theta ? theta[n] : 1.0;
    const double cut = mesh_ ? frac_[n] : 1.0;
    if (m <= mmin || m <= 0.0 || m < kSurfaceFill * th * full * geo_.volume(i, j, k) * cut) lab_.kind[n] = kEmpty;
  });
  const Gate &g = opt_.gate;
  if (g.active) {
    const GridSpec &gs = opt_.grid;
    const double xi = (g.pos - gs.origin[g.dim]) / gs.dx;
    const long r = std::lround(xi);
    const bool on_plane = std::fabs(xi - r) < 1e-9;
    // lower node of the closed face
    const int lo = on_plane ? static_cast<int>(g.fluid_below ? r : r - 1) : static_cast<int>(std::floor(xi));
    const IndexBox &pb = grid_.patch();
    for (int k = pb.lo[2]; k <= pb.hi[2]; ++k)
      for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
        for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) {
          const int idx[3] = {i, j, k};
          if (idx[g.dim] == lo) lab_.close_face(grid_, i, j, k, g.dim);
        }
  }
  lab_.exchange(grid_, comm_);
}

/* Mesh walls (docs/projection.md, "Mesh walls"). A grid face whose segment between its two nodes
   crosses a triangle is a wall moving with the triangle's velocity along the face normal (zero
   relative flux, like the gate; a wall through a node leaves that node on the fluid side). The
   nodes up to 2 cells behind a one-sided wall are SOLID: they take part in no solve (no spurious
   p = 0 or pocket of fluid behind the wall) and get the values of the fluid nodes in front
   (extend_behind). A node in front at distance s < dx/2 of the wall holds the fluid of only
   part of its dual cell: its surface threshold uses the share 1/2 + s/dx (as the half cells of
   the box walls). */
void Projection::mesh_wall_labels(const WallGeometry &walls) {
  const GridSpec &gs = opt_.grid;
  const double dx = gs.dx;
  frac_.assign(grid_.size(), 1.0);
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] == kSolid) return;
    const double x[3] = {gs.origin[0] + i * dx, gs.origin[1] + j * dx, gs.origin[2] + k * dx};
    // faces first: a face from a node behind the wall carries the wall's velocity too
    for (int d = 0; d < 3; ++d) {
      if (!gs.periodic[d] && (d == 0 ? i : d == 1 ? j : k) >= gs.ncell[d]) continue;
      double w = 0.0;
      if (walls.crosses(x, d, dx, &w)) lab_.close_face(grid_, i, j, k, d, w);
    }
    double dist;
    const int side = walls.node_side(x, 2.0 * dx, &dist);
    if (side < 0) lab_.kind[n] = kSolid;
    if (side > 0) frac_[n] = std::min(1.0, 0.5 + dist / dx);
  });
}

/* A node of the box (not a padding node) made SOLID by mesh_wall_labels. */
bool Projection::behind_mesh(int i, int j, int k, std::size_t n) const {
  if (!mesh_ || lab_.kind[n] != kSolid) return false;
  const GridSpec &gs = opt_.grid;
  const int idx[3] = {i, j, k};
  for (int d = 0; d < 3; ++d)
    if (!gs.periodic[d] && (idx[d] < 0 || idx[d] > gs.ncell[d])) return false;
  return true;
}

/* Next to mesh walls a node can have no pressure information along a direction: an EMPTY node of
   the surface layer whose neighbours along d are the wall and EMPTY nodes, or a FLUID node between
   two closed faces. pressure_gradient gives it 0 there, and the node would fall freely along the
   wall (measured: the surface corner on a wall inclined 30 degrees from the vertical slid down it
   at 0.15 m/s). Such a component (nodes touching a mesh wall only) takes the mean of that component
   at the face neighbours that have it. */
void Projection::fill_wall_gradient() {
  const std::size_t sz = grid_.size();
  std::vector<double> info(3 * sz, 0.0);
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] == kSolid) return;
    for (int d = 0; d < 3; ++d)
      for (int side = -1; side <= 1; side += 2) {
        std::size_t m;
        if (open_face(grid_, lab_, i, j, k, d, side, &m) && !(lab_.kind[n] == kEmpty && lab_.kind[m] == kEmpty))
          info[3 * n + d] = 1.0;
      }
  });
  grid_.forward(info.data(), 3);
  const IndexBox &pb = grid_.patch();
  std::vector<double> g = grad_;
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] == kSolid) return;
    if (info[3 * n] != 0.0 && info[3 * n + 1] != 0.0 && info[3 * n + 2] != 0.0) return;
    // touches a mesh wall: a closed face or a neighbour behind one
    bool touch = lab_.closed[n] != 0;
    std::size_t nb[6];
    bool in[6];
    for (int d = 0; d < 3; ++d)
      for (int s = 0; s < 2; ++s) {
        int q[3] = {i, j, k};
        q[d] += s ? 1 : -1;
        const int f = 2 * d + s;
        in[f] = q[d] >= pb.lo[d] && q[d] <= pb.hi[d];
        if (!in[f]) continue;
        nb[f] = grid_.index(q[0], q[1], q[2]);
        if (behind_mesh(q[0], q[1], q[2], nb[f]) || (!s && ((lab_.closed[nb[f]] >> d) & 1u))) touch = true;
      }
    if (!touch) return;
    for (int d = 0; d < 3; ++d) {
      if (info[3 * n + d] != 0.0) continue;
      double sum = 0.0;
      int cnt = 0;
      for (int f = 0; f < 6; ++f) {
        if (!in[f] || lab_.kind[nb[f]] == kSolid || info[3 * nb[f] + d] == 0.0) continue;
        sum += grad_[3 * nb[f] + d];
        ++cnt;
      }
      if (cnt) g[3 * n + d] = sum / cnt;
    }
  });
  grad_.swap(g);
  grid_.forward(grad_.data(), 3);
}

void Projection::extend_behind(std::vector<double> &a, int stride, const double *p2g, double mmin,
                               const std::vector<double> *grad) {
  // sources: decided on the owned nodes (their node mass is complete), then forwarded
  std::vector<double> have(grid_.size(), 0.0);
  grid_.for_owned([&](int, int, int, std::size_t n) {
    have[n] = lab_.kind[n] != kSolid ? 1.0 : 0.0;
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    if (!(m > mmin && m > 0.0)) have[n] = 0.0;
  });
  grid_.forward(have.data(), 1);
  const IndexBox &pb = grid_.patch();
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<double> next = have;
    grid_.for_owned([&](int i, int j, int k, std::size_t n) {
      if (have[n] != 0.0 || !behind_mesh(i, j, k, n)) return;
      double sum[3] = {0.0, 0.0, 0.0};
      int cnt = 0;
      for (int d = 0; d < 3; ++d)
        for (int side = -1; side <= 1; side += 2) {
          int q[3] = {i, j, k};
          q[d] += side;
          if (q[d] < pb.lo[d] || q[d] > pb.hi[d]) continue;
          const std::size_t m = grid_.index(q[0], q[1], q[2]);
          if (have[m] == 0.0) continue;
          // linear extrapolation with grad (x_n - x_m = -side dx e_d)
          const double lin = grad ? -side * opt_.grid.dx * (*grad)[3 * m + d] : 0.0;
          for (int e = 0; e < stride; ++e) sum[e] += a[stride * m + e] + lin;
          ++cnt;
        }
      if (cnt == 0) return;
      for (int e = 0; e < stride; ++e) a[stride * n + e] = sum[e] / cnt;
      next[n] = 1.0;
    });
    have.swap(next);
    grid_.forward(a.data(), stride);
    grid_.forward(have.data(), 1);
  }
}

/* The node of the box (indices clamped to 0..ncell in non-periodic dimensions) in front of a
   padding node (itself if that node is outside the patch). */
std::size_t Projection::wall_node(int i, int j, int k) const {
  const GridSpec &gs = opt_.grid;
  int q[3] = {i, j, k};
  for (int d = 0; d < 3; ++d)
    if (!gs.periodic[d]) q[d] = std::min(std::max(q[d], 0), gs.ncell[d]);
  return grid_.in_patch(q[0], q[1], q[2]) ? grid_.index(q[0], q[1], q[2]) : grid_.index(i, j, k);
}

void Projection::extend_to_padding(const std::vector<double> &a, std::vector<double> &out, int stride) const {
  out = a;
  const IndexBox &pb = grid_.patch();
  for (int k = pb.lo[2]; k <= pb.hi[2]; ++k)
    for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
      for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) {
        const std::size_t n = grid_.index(i, j, k);
        if (lab_.kind[n] != kSolid) continue;
        const std::size_t c = wall_node(i, j, k);
        for (int e = 0; e < stride; ++e) out[stride * n + e] = a[stride * c + e];
      }
}

void Projection::project(double *vel, const double *p2g, double mmin, const double *theta, bool dtheta, double h,
                         Boundaries &bc, long step) {
  make_labels(p2g, mmin, theta, bc.walls());
  const double *theta_prev = theta && dtheta && have_theta_last_ ? theta_last_.data() : nullptr;
  // u* as it is; every wall condition comes after the projection: the wall's reaction is the
  // pressure, and a wall node's velocity zeroed before it (normal or, no-slip, tangential) would
  // be moved again by the correction (measured: the F1 column at rest, docs/projection.md)
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    double *v = vel + VelRec::N * n + VelRec::V_NEW;
    for (int d = 0; d < 3; ++d) u_[3 * n + d] = v[d];
  });
  grid_.forward(u_.data(), 3);
  const double *th = theta ? theta : theta_.data();
  if (theta)
    for (std::size_t n = 0; n < beta_.size(); ++n) beta_[n] = theta[n] / opt_.rho0;
  pressure_rhs(grid_, lab_, geo_, u_.data(), th, theta_prev, h, rhs_.data());
  try {
    last_ = solver_->solve(lab_, beta_.data(), rhs_.data(), p_.data());
  } catch (const PressureSolveError &e) {
    std::ostringstream os;
    os << "Fix mpm/fluid: the pressure projection did not converge at step " << step << ": " << e.iterations
       << " PCG iterations (keyword 'max_iterations' " << opt_.pressure_max_iterations << "), relative residual "
       << e.residual << " (keyword 'tolerance' " << opt_.pressure_tolerance << ")";
    throw Error(os.str());
  }
  // for the points and grains: the padding nodes behind the box walls carry the pressure (and
  // gradient) of the wall node in front (the solve holds them at 0; interpolated as they are,
  // they would lower the pressure of the points next to a wall by half a cell's hydrostatic step)
  // (first the nodes behind mesh walls, which the padding nodes behind them then copy)
  pressure_gradient(grid_, lab_, p_.data(), grad_.data());
  grid_.forward(grad_.data(), 3);
  if (mesh_) {
    fill_wall_gradient();
    // the pressure extrapolated linearly with the (extended) gradient: a hydrostatic pressure
    // stays exact behind an inclined wall
    std::vector<double> pb = p_, gb = grad_;
    extend_behind(gb, 3, p2g, mmin);
    extend_behind(pb, 1, p2g, mmin, &gb);
    extend_to_padding(pb, p_ext_, 1);
    extend_to_padding(gb, grad_ext_, 3);
  } else {
    extend_to_padding(p_, p_ext_, 1);
    extend_to_padding(grad_, grad_ext_, 3);
  }
  if (theta) {
    theta_last_.assign(theta, theta + grid_.size());
    have_theta_last_ = true;
  }
  correct_velocity(grid_, lab_, grad_.data(), inv_rho_.data(), h, u_.data());
  grid_.forward(u_.data(), 3);
  if (mesh_) {
    // nodes behind mesh walls: the projected velocity of the fluid in front, then the wall
    // condition (the normal velocity relative to the wall removed), as the padding nodes
    u_ext_ = u_;
    extend_behind(u_ext_, 3, p2g, mmin);
  }
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    double *v = vel + VelRec::N * n + VelRec::V_NEW;
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    if (mesh_ && behind_mesh(i, j, k, n)) {
      if (!(m > mmin && m > 0.0)) return;
      for (int d = 0; d < 3; ++d) v[d] = u_ext_[3 * n + d];
      bc.apply(v, i, j, k, h);
      return;
    }
    if (lab_.kind[n] == kSolid) {
      // padding nodes behind the box walls (in the points' stencils): the projected velocity of
      // the wall node in front, with the wall condition. Their own u* is not projected; left as
      // it is, it would let the points next to a free-slip wall fall through the rest state.
      if (!(m > mmin && m > 0.0)) return;
      const std::size_t c = wall_node(i, j, k);
      for (int d = 0; d < 3; ++d) v[d] = lab_.kind[c] == kFluid ? u_[3 * c + d] : 0.0;
      bc.apply(v, i, j, k, h);
      return;
    }
    if (!(m > mmin && m > 0.0)) return;  // no fluid: velocity stays 0
    for (int d = 0; d < 3; ++d) v[d] = u_[3 * n + d];
    bc.apply(v, i, j, k, h);
  });
}

}  // namespace mpm
