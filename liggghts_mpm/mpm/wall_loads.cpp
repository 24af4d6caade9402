// What the fluid does to its mesh walls, and what pressure probes read (docs/fix_mpm_fluid.md,
// "Wall loads and probes"; docs/theory/mesh_walls.md, "Force and torque on a mesh"): the pressure field
// of the sub-step sampled on the triangles and at the probes, summed over the sub-steps of a fluid
// step (walls) or of a probe window.
//
// The pressure field. pressure projection: the nodal pressure the points interpolate (the
// solve's, or the acceleration pressure with pressure_output acceleration), extended linearly
// behind the mesh walls, read with the points' shape functions, less the solve's pressure at the
// free surface (surface_pressure). pressure eos: the points' own pressures (those the internal
// force of this sub-step used), fitted linearly around the sample, p(y) = a + b . (y - x), by
// least squares with the weights m_p sum_i S_i(x) S_i(x_p) (the moments of the points gathered
// at the nodes, node_mass_pressure), p(x) = a: at a wall the fit is one-sided and extrapolates
// to the wall (a mass-weighted mean would read the pressure about half a cell inside, measured
// -15 % of the weight on the floor of a closed box 3 cells deep). Both read only where fluid is:
// sum_i S_i(x) M_i above the empty-node mass.
//
// Each sample belongs to the rank that owns its nearest grid node (clamped into the grid along
// non-periodic dimensions, never wrapped along periodic ones, so that a triangle's periodic image
// counts once): summed over the ranks, every part of every triangle counts once.
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "mpm/projection.h"
#include "mpm/solver.h"

namespace mpm {

namespace {
// columns of wmp_, per node i, sums over the points p with weights S_ip, d = x_p - x_i: mass m,
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
  wmp_.assign(kW * nodes, 0.0);
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  const GridSpec &gs = opt.grid;
  const bool fit = !proj_;
  with_stencil(opt.shape, [&](auto ns) {
    for (const int i : plist_) {
      const double m = pts.rmass[i], pp = pts.state[i][C_P], mp = m * pp;
      const double *v = pts.v[i], *x = pts.x[i];
      const Stencil &st = shapes_[i];
      for_stencil<decltype(ns)::value>(st, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double, double,
                                                       double) {
        double *r = &wmp_[kW * n];
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
  grid_.reverse_sum(wmp_.data(), kW);
  grid_.forward(wmp_.data(), kW);
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
  const std::vector<double> *pn = proj_ ? &proj_->pressure() : nullptr;
  // moments about x: M0, sum m p, momentum; eos also M1 = sum m (y - x), Mp1, M2
  double m = 0.0, q = 0.0, pp = 0.0, mv[3] = {0.0, 0.0, 0.0};
  double M1[3] = {0.0, 0.0, 0.0}, P1[3] = {0.0, 0.0, 0.0}, M2[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  with_stencil(opt.shape, [&](auto ns) {
    for_stencil<decltype(ns)::value>(s, grid_.stride_y(), grid_.stride_z(), [&](std::size_t n, int a, int b, int c,
                                                                                double w, double, double, double) {
      const double *r = &wmp_[kW * n];
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
    p = pp - p_surface_;
    // projection: above the surface level the field less p_surface_ turns negative (the solve's
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

/* Force and torque of the fluid on each mesh wall in this sub-step, added to wall_sum_ with
   weight h. Each triangle is cut into n^2 equal triangles (n edges per side, none longer than
   half a cell), each sampled at its centroid. One-sided wall: the pressure presses along the
   normal away from the fluid, F = -p n_fluid dA. Two-sided wall (side both): the pressures one
   cell in front of and behind the triangle, F = (p_behind - p_front) n dA. Shear walls also carry
   the stress of their wall layer, mu (v_t - f w_t) / delta dA (the points' velocity at the sample
   relative to f times the wall's). Torque: (x - reference point) x F. */
void FluidSolver::wall_loads(double h) {
  const WallGeometry &wg = *bc.walls();
  const int nw = wg.walls();
  const double dx = opt.grid.dx;
  std::vector<double> loc(6 * static_cast<std::size_t>(nw), 0.0);
  for (const WallGeometry::Tri &t : wg.triangles()) {
    const WallSpec &ws = wg.wall(t.mesh);
    if (!ws.loads) continue;
    double e1[3], e2[3], e3[3];
    for (int d = 0; d < 3; ++d) {
      e1[d] = t.p[1][d] - t.p[0][d];
      e2[d] = t.p[2][d] - t.p[0][d];
      e3[d] = t.p[2][d] - t.p[1][d];
    }
    const double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double area = 0.5 * std::sqrt(geom::dot3(cr, cr));
    const double lmax = std::sqrt(std::max({geom::dot3(e1, e1), geom::dot3(e2, e2), geom::dot3(e3, e3)}));
    const int n = std::max(1, static_cast<int>(std::ceil(lmax / (0.5 * dx))));
    const double dA = area / (static_cast<double>(n) * n);
    const bool shear = ws.kind == WALL_SHEAR && opt.viscosity > 0.0;
    const double delta = shear ? wg.layer_thickness(t.mesh) : 0.0;
    double *out = &loc[6 * static_cast<std::size_t>(t.mesh)];
    auto sample = [&](double a, double b) {
      double x[3];
      for (int d = 0; d < 3; ++d) x[d] = t.p[0][d] + a * e1[d] + b * e2[d];
      if (!owns_sample(x)) return;
      double F[3] = {0.0, 0.0, 0.0};
      bool any = false;
      if (ws.side == SIDE_BOTH) {
        double xf[3], xb[3], pf = 0.0, pb = 0.0;
        for (int d = 0; d < 3; ++d) {
          xf[d] = x[d] + dx * t.n[d];
          xb[d] = x[d] - dx * t.n[d];
        }
        const bool hf = pressure_at(xf, pf, nullptr), hb = pressure_at(xb, pb, nullptr);
        any = hf || hb;
        for (int d = 0; d < 3; ++d) F[d] = ((hb ? pb : 0.0) - (hf ? pf : 0.0)) * t.n[d] * dA;
      } else {
        double p = 0.0, v[3];
        if (!pressure_at(x, p, shear ? v : nullptr)) return;
        any = true;
        const double s = ws.side == SIDE_OPPOSITE ? -1.0 : 1.0;  // n_fluid = s n
        for (int d = 0; d < 3; ++d) F[d] = -p * s * t.n[d] * dA;
        if (shear && std::isfinite(delta) && delta > 0.0) {
          const double b0 = 1.0 - a - b;
          double r[3];
          for (int d = 0; d < 3; ++d)
            r[d] = v[d] - ws.sticky * (b0 * t.w[0][d] + a * t.w[1][d] + b * t.w[2][d]);
          const double rn = geom::dot3(r, t.n);
          for (int d = 0; d < 3; ++d) F[d] += opt.viscosity * (r[d] - rn * t.n[d]) / delta * dA;
        }
      }
      if (!any) return;
      double r[3];
      for (int d = 0; d < 3; ++d) r[d] = x[d] - ws.ref[d];
      out[0] += F[0];
      out[1] += F[1];
      out[2] += F[2];
      out[3] += r[1] * F[2] - r[2] * F[1];
      out[4] += r[2] * F[0] - r[0] * F[2];
      out[5] += r[0] * F[1] - r[1] * F[0];
    };
    const double inv = 1.0 / (3.0 * n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j + i < n; ++j) {
        sample((3 * i + 1) * inv, (3 * j + 1) * inv);                        // upward
        if (i + j <= n - 2) sample((3 * i + 2) * inv, (3 * j + 2) * inv);    // downward
      }
  }
  if (wall_sum_.size() != loc.size()) wall_sum_.assign(loc.size(), 0.0);
  for (std::size_t c = 0; c < loc.size(); ++c) wall_sum_[c] += h * loc[c];
}

/* The probes' sums of this sub-step with weight h: a point probe, the pressure at its point (on
   the rank that owns the point, where fluid is); a box probe, the nodal pressure of every owned
   node inside the box that holds fluid (each node counts once). probe_sum_[2 j] += h sum p,
   probe_sum_[2 j + 1] += h (number of values). */
void FluidSolver::probe_sums(double h) {
  const GridSpec &gs = opt.grid;
  const std::vector<double> *pn = proj_ ? &proj_->pressure() : nullptr;
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
            const double m = wmp_[kW * n + W_M];
            if (!(m > mmin) || m <= 0.0) continue;
            sp += pn ? (*pn)[n] - p_surface_ : wmp_[kW * n + W_MP] / m;
            cnt += 1.0;
          }
    }
    probe_sum_[2 * j] += h * sp;
    probe_sum_[2 * j + 1] += h * cnt;
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
   nodes (all ranks) is p_surface_, taken off every sample of the walls and probes. Nodes within
   two cells of a mesh wall, and pairs that reach the padding, take no part (there the nodal mass
   lacks what lies behind the wall). */
void FluidSolver::surface_pressure() {
  p_surface_ = 0.0;
  if (!proj_) return;
  const GridSpec &gs = opt.grid;
  const std::vector<double> &p = proj_->pressure();
  const double full = opt.rho0 * gs.dx * gs.dx * gs.dx, half = 0.5 * full;
  const WallGeometry *wg = bc.walls();
  const std::size_t st[3] = {1, grid_.stride_y(), grid_.stride_z()};
  double loc[2] = {0.0, 0.0}, glob[2];
  grid_.for_owned_all([&](int i, int j, int k, std::size_t n) {
    const double ma = wmp_[kW * n + W_M];
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
    const double mb = wmp_[kW * nb + W_M];
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
  p_surface_ = glob[1] > 0.0 ? glob[0] / glob[1] : 0.0;
}

void FluidSolver::sample_pressure(double h) {
  if (probe_sum_.size() != 2 * opt.probes.size()) {
    probe_sum_.assign(2 * opt.probes.size(), 0.0);
    probe_mean_.assign(opt.probes.size(), 0.0);
    probe_time_ = 0.0;
  }
  node_mass_pressure();
  surface_pressure();
  if (walls_with_loads()) wall_loads(h);
  if (!opt.probes.empty()) probe_sums(h);
  wall_time_ += h;
  probe_time_ += h;
}

// Start of a fluid step: the walls' sums restart (their output is the mean over this step).
void FluidSolver::begin_samples() {
  std::fill(wall_sum_.begin(), wall_sum_.end(), 0.0);
  wall_time_ = 0.0;
  if (probe_sum_.size() != 2 * opt.probes.size()) {
    probe_sum_.assign(2 * opt.probes.size(), 0.0);
    probe_mean_.assign(opt.probes.size(), 0.0);
    probe_time_ = 0.0;
  }
}

// End of a fluid step (collective): the walls' means over its sub-steps, summed over the ranks;
// the probes' means when their window is complete (every fluid step with probe_window 0).
void FluidSolver::end_samples() {
  const int nw = bc.walls() ? bc.walls()->walls() : 0;
  if (static_cast<int>(wall_sum_.size()) != 6 * nw) wall_sum_.assign(6 * static_cast<std::size_t>(nw), 0.0);
  const bool window_done = !opt.probes.empty() && probe_time_ >= opt.probe_window * (1.0 - 1e-9);
  std::vector<double> loc(wall_sum_);
  if (window_done) loc.insert(loc.end(), probe_sum_.begin(), probe_sum_.end());
  if (loc.empty()) return;
  std::vector<double> glob(loc.size());
  MPI_Allreduce(loc.data(), glob.data(), static_cast<int>(loc.size()), MPI_DOUBLE, MPI_SUM, comm_);
  wall_mean_.assign(6 * static_cast<std::size_t>(nw), 0.0);
  for (int c = 0; c < 6 * nw; ++c) wall_mean_[c] = wall_time_ > 0.0 ? glob[c] / wall_time_ : 0.0;
  if (window_done) {
    for (std::size_t j = 0; j < opt.probes.size(); ++j) {
      const double s = glob[6 * nw + 2 * j], w = glob[6 * nw + 2 * j + 1];
      probe_mean_[j] = w > 0.0 ? s / w : 0.0;
    }
    std::fill(probe_sum_.begin(), probe_sum_.end(), 0.0);
    probe_time_ = 0.0;
  }
}

}  // namespace mpm
