// What the fluid does to its mesh walls, and what pressure probes read (docs/fix_mpm_fluid.md,
// "Wall loads and probes"; docs/theory/mesh_walls.md, "Force and torque on a mesh").
//
// Walls: the momentum each wall gives the fluid, recorded where it is given (Boundaries::
// record_loads): the change of a node's momentum by each of the wall's velocity conditions, the
// (8-23) traction of pressure eos, the points the wall puts back, and with the projection the
// nodes behind the wall taking the velocity of the fluid in front and the pressure correction's
// momentum, written as nodal terms (wall_pressure_loads) that go to the wall that ends the node's
// grid line. The fluid's force on a wall is minus that momentum per time, its mean over a fluid step.
//
// Probes: the pressure field of the sub-step. pressure projection: the nodal pressure the points
// interpolate (the solve's, or the acceleration pressure with pressure_output acceleration),
// extended linearly behind the mesh walls, read with the points' shape functions, less the solve's
// pressure at the free surface (surface_pressure). pressure eos: the points' own pressures (those
// the internal force of this sub-step used), fitted linearly around the sample, p(y) = a + b . (y - x),
// by least squares with the weights m_p sum_i S_i(x) S_i(x_p) (the moments of the points gathered
// at the nodes, node_mass_pressure), p(x) = a: at a wall the fit is one-sided and extrapolates
// to the wall. Both read only where fluid is: sum_i S_i(x) M_i above the empty-node mass. A point
// probe belongs to the rank that owns its nearest grid node (clamped into the grid along
// non-periodic dimensions).
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "mpm/projection.h"
#include "mpm/solver.h"

namespace mpm {

namespace {
// columns of io_.wmp, per node i, sums over the points p with weights S_ip, d = x_p - x_i: mass m,
// m p, momentum m v (3), m d (3), m p d (3), m d d^T (xx yy zz yz xz xy)
enum { W_M = 0, W_MP = 1, W_MV = 2, W_MD = 5, W_MPD = 8, W_MDD = 11, kW = 17 };
double fill_depth(ShapeKind k, double f);
}  // namespace

// Depth t (cells) below a plane free surface of a node whose fill (nodal mass over a full cell's)
// is f: the inverse of Phi(t) = integral of the 1-D shape function from -infinity to t (Phi(0) = 1/2;
// quadratic B-spline: 1/2 + 3t/4 - t^3/3 for |t| <= 1/2, 1 - (3/2 - t)^3/6 for 1/2 <= t <= 3/2;
// tent: 1/2 + t - t|t|/2 for |t| <= 1), by bisection.
namespace {
double fill_depth(ShapeKind k, double f) {
  auto phi = [k](double t) {
    const double a = std::fabs(t);
    double c;  // Phi(|t|)
    if (k == ShapeKind::Linear)
      c = a >= 1.0 ? 1.0 : 0.5 + a - 0.5 * a * a;
    else
      c = a >= 1.5 ? 1.0 : a <= 0.5 ? 0.5 + 0.75 * a - a * a * a / 3.0 : 1.0 - (1.5 - a) * (1.5 - a) * (1.5 - a) / 6.0;
    return t >= 0.0 ? c : 1.0 - c;
  };
  double lo = -1.5, hi = 1.5;
  f = std::min(std::max(f, 0.0), 1.0);
  for (int it = 0; it < 50; ++it) {
    const double mid = 0.5 * (lo + hi);
    (phi(mid) < f ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}
}  // namespace

void FluidSolver::node_mass_pressure() {
  const std::size_t nodes = g_.p2g.size() / P2gRec::N;
  io_.wmp.assign(kW * nodes, 0.0);
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  const GridSpec &gs = opt.grid;
  const bool fit = !pressure_->solve();
  with_stencil(opt.shape, [&](auto ns) {
    for (const int i : pw_.plist) {
      const double m = pts.rmass[i], pp = pts.state[i][C_P], mp = m * pp;
      const double *v = pts.v[i], *x = pts.x[i];
      const Stencil &st = pw_.shapes[i];
      for_stencil<decltype(ns)::value>(st, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double, double,
                                                       double) {
        double *r = &io_.wmp[kW * n];
        r[W_M] += w * m;
        r[W_MP] += w * mp;
        for (int d = 0; d < 3; ++d) r[W_MV + d] += w * m * v[d];
        if (!fit) return;
        const int off[3] = {a, b, c};
        double dd[3];
        for (int d = 0; d < 3; ++d) dd[d] = x[d] - (gs.origin[d] + (st.base[d] + off[d]) * gs.dx);
        for (int d = 0; d < 3; ++d) {
          r[W_MD + d] += w * m * dd[d];
          r[W_MPD + d] += w * mp * dd[d];
        }
        r[W_MDD + 0] += w * m * dd[0] * dd[0];
        r[W_MDD + 1] += w * m * dd[1] * dd[1];
        r[W_MDD + 2] += w * m * dd[2] * dd[2];
        r[W_MDD + 3] += w * m * dd[1] * dd[2];
        r[W_MDD + 4] += w * m * dd[0] * dd[2];
        r[W_MDD + 5] += w * m * dd[0] * dd[1];
      });
    }
  });
  grid_.reverse_sum(io_.wmp.data(), kW);
  grid_.forward(io_.wmp.data(), kW);
}

// The pressure at x (false: no fluid there, or x outside the grid); mass: sum S M at x; vel
// (optional): the points' mass-weighted velocity there. x must lie within half a cell of an
// owned node.
bool FluidSolver::pressure_at(const double *x, double &p, double *vel) {
  const GridSpec &gs = opt.grid;
  for (int d = 0; d < 3; ++d) {
    const double xi = (x[d] - gs.origin[d]) / gs.dx;
    if (!gs.periodic[d] && (xi < 0.0 || xi > gs.ncell[d])) return false;
  }
  Stencil s;
  if (!shape_of(x, s)) return false;
  const std::vector<double> *pn = pressure_->solve() ? &pressure_->solve()->pressure() : nullptr;
  // moments about x: M0, sum m p, momentum; eos also M1 = sum m (y - x), Mp1, M2
  double m = 0.0, q = 0.0, pp = 0.0, mv[3] = {0.0, 0.0, 0.0};
  double M1[3] = {0.0, 0.0, 0.0}, P1[3] = {0.0, 0.0, 0.0}, M2[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  with_stencil(opt.shape, [&](auto ns) {
    for_stencil<decltype(ns)::value>(s, grid_.stride_y(), grid_.stride_z(), [&](std::size_t n, int a, int b, int c,
                                                                                double w, double, double, double) {
      const double *r = &io_.wmp[kW * n];
      m += w * r[W_M];
      q += w * r[W_MP];
      for (int d = 0; d < 3; ++d) mv[d] += w * r[W_MV + d];
      if (pn) {
        pp += w * (*pn)[n];
        return;
      }
      // y - x = d + e, e = x_i - x
      const int off[3] = {a, b, c};
      double e[3];
      for (int d = 0; d < 3; ++d) e[d] = gs.origin[d] + (s.base[d] + off[d]) * gs.dx - x[d];
      for (int d = 0; d < 3; ++d) {
        M1[d] += w * (r[W_MD + d] + r[W_M] * e[d]);
        P1[d] += w * (r[W_MPD + d] + r[W_MP] * e[d]);
      }
      static const int ia[6] = {0, 1, 2, 1, 0, 0}, ib[6] = {0, 1, 2, 2, 2, 1};
      for (int k = 0; k < 6; ++k)
        M2[k] += w * (r[W_MDD + k] + r[W_MD + ia[k]] * e[ib[k]] + e[ia[k]] * r[W_MD + ib[k]] + r[W_M] * e[ia[k]] * e[ib[k]]);
    });
  });
  if (!(m > mass_min()) || m <= 0.0) return false;
  if (vel)
    for (int d = 0; d < 3; ++d) vel[d] = mv[d] / m;
  if (pn) {
    p = pp - io_.p_surface;
    // projection: above the surface level the field less io_.p_surface turns negative (the solve's
    // zero lies higher); where the fluid is thinner than half a full cell that is no suction but air
    if (p < 0.0 && m < 0.5 * opt.rho0 * gs.dx * gs.dx * gs.dx) p = 0.0;
    return true;
  }
  // eos: [M0 M1^T; M1 M2] [a; b] = [q; P1]; a direction without spread (a slab one cell thick)
  // gets a small ridge (its slope ~0)
  Eigen::Matrix4d A;
  Eigen::Vector4d rhs;
  const double ridge = 1e-6 * m * gs.dx * gs.dx;
  A(0, 0) = m;
  for (int d = 0; d < 3; ++d) {
    A(0, 1 + d) = A(1 + d, 0) = M1[d];
    rhs(1 + d) = P1[d];
  }
  rhs(0) = q;
  A(1, 1) = M2[0] + ridge;
  A(2, 2) = M2[1] + ridge;
  A(3, 3) = M2[2] + ridge;
  A(2, 3) = A(3, 2) = M2[3];
  A(1, 3) = A(3, 1) = M2[4];
  A(1, 2) = A(2, 1) = M2[5];
  const Eigen::Vector4d sol = A.ldlt().solve(rhs);
  p = std::isfinite(sol(0)) ? sol(0) : q / m;
  return true;
}

// The rank that owns the nearest node of x counts a sample at x.
bool FluidSolver::owns_sample(const double *x) const {
  const GridSpec &gs = opt.grid;
  const IndexBox &ob = grid_.owned();
  for (int d = 0; d < 3; ++d) {
    int c = static_cast<int>(std::floor((x[d] - gs.origin[d]) / gs.dx + 0.5));
    if (gs.periodic[d]) {
      if (c < 0 || c >= gs.ncell[d]) return false;
    } else {
      c = std::min(std::max(c, 0), gs.ncell[d]);
    }
    if (c < ob.lo[d] || c > ob.hi[d]) return false;
  }
  return true;
}

/* The probes' sums of this sub-step with weight h: a point probe, the pressure at its point (on
   the rank that owns the point, where fluid is); a box probe, the nodal pressure of every owned
   node inside the box that holds fluid (each node counts once). io_.probe_sum[2 j] += h sum p,
   io_.probe_sum[2 j + 1] += h (number of values). */
void FluidSolver::probe_sums(double h) {
  const GridSpec &gs = opt.grid;
  const std::vector<double> *pn = pressure_->solve() ? &pressure_->solve()->pressure() : nullptr;
  const double mmin = mass_min();
  for (std::size_t j = 0; j < opt.probes.size(); ++j) {
    const Probe &pr = opt.probes[j];
    double sp = 0.0, cnt = 0.0;
    if (!pr.box) {
      double p = 0.0;
      if (owns_sample(pr.lo) && pressure_at(pr.lo, p, nullptr)) {
        sp = p;
        cnt = 1.0;
      }
    } else {
      int lo[3], hi[3];
      const IndexBox &ob = grid_.owned();
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::max(ob.lo[d], static_cast<int>(std::ceil((pr.lo[d] - gs.origin[d]) / gs.dx - 1e-9)));
        hi[d] = std::min(ob.hi[d], static_cast<int>(std::floor((pr.hi[d] - gs.origin[d]) / gs.dx + 1e-9)));
      }
      for (int k = lo[2]; k <= hi[2]; ++k)
        for (int jj = lo[1]; jj <= hi[1]; ++jj)
          for (int i = lo[0]; i <= hi[0]; ++i) {
            const std::size_t n = grid_.index(i, jj, k);
            const double m = io_.wmp[kW * n + W_M];
            if (!(m > mmin) || m <= 0.0) continue;
            sp += pn ? (*pn)[n] - io_.p_surface : io_.wmp[kW * n + W_MP] / m;
            cnt += 1.0;
          }
    }
    io_.probe_sum[2 * j] += h * sp;
    io_.probe_sum[2 * j + 1] += h * cnt;
  }
}

/* pressure projection: the pressure its solve has at the free surface. With mesh walls the solve
   puts p = 0 at the first EMPTY node above the fluid (docs/theory/projection.md, "Mesh walls": the node
   surface), so that its pressure at rest is rho g (h + delta) at depth h, delta about one cell
   (measured: 1.00 dx in a tank at rest). The fluid feels only the gradient; a wall feels the
   value. The surface of the fluid is where the nodal mass falls to half a full cell's, rho0 dx^3:
   at every owned node with at least half, whose neighbour in the direction the pressure falls
   fastest (largest component of -grad p, central differences) has less, the level follows from
   the fill of the one of the two nodes whose fill is nearer 1/2 (fill_depth: the fill of a node
   below a plane surface), and the pressure there linearly between the two nodes. The mean over these
   nodes (all ranks) is io_.p_surface, taken off every sample of the walls and probes. Nodes within
   two cells of a mesh wall, and pairs that reach the padding, take no part (there the nodal mass
   lacks what lies behind the wall). */
void FluidSolver::surface_pressure() {
  io_.p_surface = 0.0;
  if (!pressure_->solve()) return;
  const GridSpec &gs = opt.grid;
  const std::vector<double> &p = pressure_->solve()->pressure();
  const double full = opt.rho0 * gs.dx * gs.dx * gs.dx, half = 0.5 * full;
  const WallGeometry *wg = bc.walls();
  const std::size_t st[3] = {1, grid_.stride_y(), grid_.stride_z()};
  double loc[2] = {0.0, 0.0}, glob[2];
  grid_.for_owned_all([&](int i, int j, int k, std::size_t n) {
    const double ma = io_.wmp[kW * n + W_M];
    if (ma < half) return;
    const int c[3] = {i, j, k};
    double g[3];
    for (int d = 0; d < 3; ++d) {
      if (!gs.periodic[d] && (c[d] <= 0 || c[d] >= gs.ncell[d])) return;
      g[d] = p[n + st[d]] - p[n - st[d]];
    }
    int dd = 0;
    for (int d = 1; d < 3; ++d)
      if (std::fabs(g[d]) > std::fabs(g[dd])) dd = d;
    if (g[dd] == 0.0) return;
    const std::size_t nb = g[dd] < 0.0 ? n + st[dd] : n - st[dd];
    const double mb = io_.wmp[kW * nb + W_M];
    if (mb >= half) return;
    if (wg && wg->walls() > 0) {
      double x[3], dist;
      for (int d = 0; d < 3; ++d) x[d] = gs.origin[d] + c[d] * gs.dx;
      wg->node_side(x, 2.0 * gs.dx, &dist);
      if (dist < 2.0 * gs.dx) return;
    }
    // the level: the fill of a node at distance t (cells) below a plane surface is Phi(t), the
    // integral of the shape function up to t; read from the node whose fill is nearer 1/2
    const double fa = ma / full, fb = mb / full;
    const double t = std::fabs(fa - 0.5) <= std::fabs(fb - 0.5) ? fill_depth(opt.shape, fa) : 1.0 + fill_depth(opt.shape, fb);
    loc[0] += p[n] + t * (p[nb] - p[n]);
    loc[1] += 1.0;
  });
  MPI_Allreduce(loc, glob, 2, MPI_DOUBLE, MPI_SUM, comm_);
  io_.p_surface = glob[1] > 0.0 ? glob[0] / glob[1] : 0.0;
}

/* pressure projection: the pressure correction's momentum of this sub-step as nodal terms
   (Projection::load_coefficients), b_n = (p_n - io_.p_surface) c_n + r_n (the shift by a constant
   changes no sum: the c_n sum to 0), each direction d of each node's to the boundary that its grid
   line along d meets first (Boundaries::line_wall; a node behind a mesh casts from its mirror
   image in front): a mesh wall takes it, a grid face takes none. */
void FluidSolver::wall_pressure_loads() {
  const std::vector<double> &c = pressure_->solve()->load_coefficients(), &r = pressure_->solve()->load_rest();
  if (c.empty()) return;
  const double ps = opt.pressure_acceleration ? 0.0 : io_.p_surface;
  const GridSpec &gs = opt.grid;
  grid_.for_owned_all([&](int i, int j, int k, std::size_t n) {
    const double p = pressure_->solve()->load_pressure(n) - ps;
    double b[3];
    for (int d = 0; d < 3; ++d) b[d] = p * c[3 * n + d] + r[3 * n + d];
    if (b[0] == 0.0 && b[1] == 0.0 && b[2] == 0.0) return;
    const double x[3] = {gs.origin[0] + i * gs.dx, gs.origin[1] + j * gs.dx, gs.origin[2] + k * gs.dx};
    // a node behind a mesh: its lines are those of its mirror image in front of the wall
    double y[3] = {x[0], x[1], x[2]};
    if (pressure_->solve()->load_behind(i, j, k, n)) {
      double nrm[3], dist = 0.0;
      if (bc.node_normal(i, j, k, nrm) && bc.walls()->nearest_wall(x, 3.0 * gs.dx, &dist) >= 0)
        for (int e = 0; e < 3; ++e) y[e] = x[e] + 2.0 * dist * nrm[e];
    }
    for (int d = 0; d < 3; ++d) {
      if (b[d] == 0.0) continue;
      const int w = bc.line_wall(i, j, k, y, d, b[d]);
      if (w < 0) continue;
      double J[3] = {0.0, 0.0, 0.0};
      J[d] = b[d];
      bc.add_impulse(w, x, J);
    }
  });
}

void FluidSolver::sample_pressure(double h) {
  if (io_.probe_sum.size() != 2 * opt.probes.size()) {
    io_.probe_sum.assign(2 * opt.probes.size(), 0.0);
    io_.probe_mean.assign(opt.probes.size(), 0.0);
    io_.probe_time = 0.0;
  }
  const bool pressure_loads = bc.recording() && pressure_->solve();
  if (pressure_loads || !opt.probes.empty()) {
    node_mass_pressure();
    surface_pressure();
  }
  if (pressure_loads) wall_pressure_loads();
  if (!opt.probes.empty()) probe_sums(h);
  io_.wall_time += h;
  io_.probe_time += h;
}

// Start of a fluid step: the walls' sums restart (their output is the mean over this step).
void FluidSolver::begin_samples() {
  std::fill(io_.wall_sum.begin(), io_.wall_sum.end(), 0.0);
  io_.wall_time = 0.0;
  if (io_.probe_sum.size() != 2 * opt.probes.size()) {
    io_.probe_sum.assign(2 * opt.probes.size(), 0.0);
    io_.probe_mean.assign(opt.probes.size(), 0.0);
    io_.probe_time = 0.0;
  }
}

// End of a fluid step (collective): the walls' means over its sub-steps, summed over the ranks;
// the probes' means when their window is complete (every fluid step with probe_window 0).
void FluidSolver::end_samples() {
  const int nw = bc.walls() ? bc.walls()->walls() : 0;
  if (static_cast<int>(io_.wall_sum.size()) != 6 * nw) io_.wall_sum.assign(6 * static_cast<std::size_t>(nw), 0.0);
  // the walls' momentum given to the fluid over this step (Boundaries::record_loads): the fluid's
  // force on them is its opposite
  if (bc.recording()) {
    std::vector<double> J(io_.wall_sum.size(), 0.0);
    bc.take_loads(J);
    for (std::size_t c = 0; c < io_.wall_sum.size(); ++c) io_.wall_sum[c] -= J[c];
  }
  const bool window_done = !opt.probes.empty() && io_.probe_time >= opt.probe_window * (1.0 - 1e-9);
  std::vector<double> loc(io_.wall_sum);
  if (window_done) loc.insert(loc.end(), io_.probe_sum.begin(), io_.probe_sum.end());
  if (loc.empty()) return;
  std::vector<double> glob(loc.size());
  MPI_Allreduce(loc.data(), glob.data(), static_cast<int>(loc.size()), MPI_DOUBLE, MPI_SUM, comm_);
  io_.wall_mean.assign(6 * static_cast<std::size_t>(nw), 0.0);
  for (int c = 0; c < 6 * nw; ++c) io_.wall_mean[c] = io_.wall_time > 0.0 ? glob[c] / io_.wall_time : 0.0;
  if (window_done) {
    for (std::size_t j = 0; j < opt.probes.size(); ++j) {
      const double s = glob[6 * nw + 2 * j], w = glob[6 * nw + 2 * j + 1];
      io_.probe_mean[j] = w > 0.0 ? s / w : 0.0;
    }
    std::fill(io_.probe_sum.begin(), io_.probe_sum.end(), 0.0);
    io_.probe_time = 0.0;
  }
}

}  // namespace mpm
