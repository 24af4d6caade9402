// The coupling phases of the solver (chapter 7.2, 8.2): the pressure fit at the nodes, the drag
// and pressure exchange with the grains and its reaction on the fluid (solver.h, coupling.h); the
// fluid fraction and its smoothing are in fluid_fraction.cpp, grad_p weak's nodal gradient in
// coupling_weak.cpp.
#include <Eigen/Dense>
#if defined(__AVX__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <climits>
#include <cmath>
#include <sstream>

#include "mpm/coupling.h"
#include "mpm/error.h"
#include "mpm/projection.h"
#include "mpm/solver.h"

namespace mpm {

bool fit_linear_pressure(const double *c, double dx, double out[4]) {
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r)
    for (int q = 0; q < 4; ++q) M(r, q) = c[PfitRec::MAT + 4 * r + q];
  const Eigen::Vector4d r(c[0], c[1], c[2], c[3]);
  // scale the offsets by the cell so that the system is well conditioned
  const double s = 1.0 / dx;
  const Eigen::Vector4d D(1.0, s, s, s);
  const Eigen::Matrix4d Ms = D.asDiagonal() * M * D.asDiagonal();
  Eigen::LDLT<Eigen::Matrix4d> ldlt(Ms);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-6)) return false;
  const Eigen::Vector4d sol = D.asDiagonal() * ldlt.solve(D.asDiagonal() * r);
  if (!(std::isfinite(sol[0]) && std::isfinite(sol[1]) && std::isfinite(sol[2]) && std::isfinite(sol[3])))
    return false;
  for (int q = 0; q < 4; ++q) out[q] = sol[q];
  return true;
}

/* a + w v with the rounding of a loop that only sums w v into a: the build with FMA (MPM_SIMD)
   contracts that to one fused multiply-add (the product not rounded), whereas pressure_moments,
   which uses w V for its own sums too, rounds the product once for all of them */
static inline double add_product(double a, double w, double v) {
#if defined(__FMA__)
  return std::fma(w, v, a);
#else
  return a + w * v;
#endif
}

// The nodes of the stencils with bases lo..hi (per direction; none if hi = INT_MIN), in the patch.
static IndexBox stencil_box(const int lo[3], const int hi[3], int ns, const IndexBox &patch) {
  IndexBox b;
  for (int d = 0; d < 3; ++d) {
    b.lo[d] = lo[d];
    b.hi[d] = hi[d] == INT_MIN ? INT_MIN : hi[d] + ns - 1;
  }
  return b.cut(patch);
}

// The smallest box holding b and the boxes of more.
static IndexBox bounding_box(IndexBox b, const std::vector<IndexBox> &more) {
  for (const IndexBox &m : more) b = b.hull(m);
  return b;
}

/* Moments of the points' pressures for the linear least-squares fit at each node: with
   e = (1, x_s - x_j) for the point's sample position x_s, the node collects r = sum S V p e and
   the normal matrix M = sum S V e e^T (PfitRec). VOL (reaction points with the fit):
   the same pass also sums the points' volume sum S V at every node of their stencils into rq[3 n]
   (route_reaction), point by point in the order of pw_.plist as the pass of its own that it replaces
   (point_sums), with the same rounding (add_product): the same sums bit for bit. */
template <int NS, bool VOL>
void FluidSolver::pressure_moments() {
  const GridSpec &gs = opt.grid;
  double **x = pts.x;
  double *const g = g_.pfit.data();
  double *const rq = VOL ? g_.rq.data() : nullptr;
  const double *const need = g_.need.data();
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  for (const int i : pw_.plist) {
    const Stencil &ps = pw_.shapes[i];
    const double V = pts.state[i][C_VOL], p = pts.state[i][C_P];
    const double *xp = x[i];
    // With anti-locking the pressure is the cell's (its mean density): it belongs to the cell's
    // centre, not to the point (a fit to the points' own positions sees a staircase and, near a
    // wall, a flat one).
    double dn[3][3];  // x_s - x_j per direction, for the stencil's node planes
    for (int a = 0; a < 3; ++a) {
      int c = static_cast<int>(std::floor((xp[a] - gs.origin[a]) / gs.dx));
      if (!gs.periodic[a]) c = std::min(std::max(c, 0), gs.ncell[a] - 1);
      const double xs = gs.origin[a] + (c + 0.5) * gs.dx;
      for (int q = 0; q < 3; ++q) dn[a][q] = xs - (gs.origin[a] + (ps.base[a] + q) * gs.dx);
    }
    for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double, double, double) {
      if (VOL) rq[3 * n] = add_product(rq[3 * n], w, V);  // every node of the stencil, needed or not
      if (need[n] == 0.0) return;
      double *cn = g + PfitRec::N * n;
      const double wV = w * V;
      const Row4 e = {1.0, dn[0][a], dn[1][b], dn[2][c]};
      const Row4 we = wV * e;
      row4(cn + PfitRec::R) += p * we;
      row4(cn + PfitRec::MAT) += we;
      row4(cn + PfitRec::MAT + 4) += e[1] * we;
      row4(cn + PfitRec::MAT + 8) += e[2] * we;
      row4(cn + PfitRec::MAT + 12) += e[3] * we;
    });
  }
}

/* Two-way coupling with the DEM grains (chapter 7.2, 8.1-8.2): fluid velocity, fraction and
   pressure gradient at each grain; drag (7-7) exchanged over the sub-step for the two-body system
   grain + fluid seen by it (stable for any stiffness) and the pressure-gradient force -V grad p
   (7-15); the reaction of both goes to the nodes with the same shape functions (8-25), (8-26), so
   momentum is kept. */
void FluidSolver::couple_fluid_grains(double h) {
  with_stencil(opt.shape, [&](auto ns) { couple_kernel<decltype(ns)::value>(h); });
}

// couple_kernel's first step: the pressure the grains feel, at the nodes (projection: the last
// solve's gradient; grad_p weak: the fluid's own weak gradient; else the points' pressure moments
// for the nodal fit).
template <int NS>
void FluidSolver::grain_pressure_inputs(bool proj, bool weak) {
  if (!proj && weak) point_sums<NS>();
  if (proj) {
    // the last solve's gradient, read in place (grain_gradient)
  } else if (weak) {
    weak_pressure_gradient();
    smooth_weak_gradient<NS>();
  } else {
    // pressure at the nodes for the force on the grains (fit_linear_pressure); reaction points:
    // the points' volume at the nodes (rq[3 n], folded) in the same pass over the points. pfit is
    // 0 here (see the end of couple_kernel)
    if (opt.reaction_points) {
      std::fill(g_.rq.begin(), g_.rq.end(), 0.0);
      pressure_moments<NS, true>();
      fold_to_mirror(g_.rq, 3);
    } else {
      pressure_moments<NS, false>();
    }
    // (the points' volume with reaction points, summed in the same exchange)
    grid_.reverse_sum({{g_.pfit.data(), PfitRec::N}, {opt.reaction_points ? g_.rq.data() : nullptr, 3}});
  }
}

// couple_kernel: what the grains read at the owned nodes of sbox (StRec: fluid fraction,
// pressure, fitted gradient, mass, velocity); rbox: the nodes whose pfit record is summed.
void FluidSolver::grain_node_state(const IndexBox &sbox, const IndexBox &rbox, bool weak) {
  static const double kZeroPfit[PfitRec::N] = {};
  const double mmin = mass_min();
  grid_.for_box(sbox, [&](int i, int j, int k, std::size_t n) {
    const double *c = rbox.contains(i, j, k) ? &g_.pfit[PfitRec::N * n] : kZeroPfit;
    const double *g = &g_.p2g[P2gRec::N * n];
    double *st = &g_.st[StRec::N * n];
    for (int q = 0; q < StRec::N; ++q) st[q] = 0.0;
    st[StRec::TH] = g_.th[n];
    st[StRec::P] = !weak && c[PfitRec::MAT] > 0.0 ? c[PfitRec::R] / c[PfitRec::MAT] : 0.0;
    double fit[4];
    if (opt.grad_p == GradP::Fit && c[PfitRec::MAT] > 0.0 && g_.need[n] > 0.0 && fit_linear_pressure(c, opt.grid.dx, fit)) {
      st[StRec::P] = fit[0];
      for (int a = 0; a < 3; ++a) st[StRec::FIT + a] = fit[1 + a];
      st[StRec::FIT + 3] = 1.0;  // the fit (value and gradient) is determined
    }
    st[StRec::M] = g[P2gRec::M];
    if (g[P2gRec::M] > mmin) {  // only nodes that hold fluid carry its velocity
      for (int d = 0; d < 3; ++d) st[StRec::U + d] = g[P2gRec::MV + d] / g[P2gRec::M];
      st[StRec::U + 3] = 1.0;
    }
  });
}

// The share of a grain (stencil ps, radius r) below the free surface (docs/theory/drag.md, "Grains
// at the free surface"): the depth of its centre, its nodes' levels (Projection::grain_level, in
// cells; NaN at SOLID nodes: left out) interpolated with its weights, and the cap of its sphere
// below it; 1 without levels (pressure eos). The grain's drag and pressure force take this share.
template <int NS>
static double immersion(const Stencil &ps, std::size_t sy, std::size_t sz, const double *lev, double dx, double r) {
  if (!lev) return 1.0;
  double wl = 0.0, ws = 0.0;
  for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double, double, double) {
    if (!std::isnan(lev[n])) {
      wl += w * lev[n];
      ws += w;
    }
  });
  return ws > 0.0 ? immersed_fraction(wl / ws * dx, r) : 1.0;
}

  // Drag, exchanged node by node. Each grain k has the coefficient K_k (frozen over the sub-step)
  // and touches node j with weight S_jk. At every node the fluid (mass M_j, velocity u_j) and the
  // grains' share of it (coefficient K_j = sum_k S_jk K_k, mass sum_k S_jk m_k, K-weighted mean
  // velocity) exchange the backward-Euler two-body impulse J_j over h: the slip decays without
  // overshoot however many grains share the node (a dense bed) and however stiff the drag, the
  // fluid loses exactly what the grains gain, and a grain advanced by LIGGGHTS' velocity Verlet
  // keeps the right terminal slip (see mpm::drag_implicit_impulse). Grain k receives the share
  // S_jk K_k / K_j of J_j. The pressure-gradient force (7-15) is explicit (not stiff); its
  // reaction goes to the nodes too.
// couple_kernel, per grain: Kgrain[k], the pressure force (coup_->grain_force) and the grain's shares
// of K, K v, mass, pressure reaction and K a at the nodes of its stencil (dr).
// (inlined into couple_kernel: as a call of its own, GCC emitted for it a register-to-register
// vmovq encoding that valgrind 3.19 cannot decode, which stopped callgrind on coupled runs)
template <int NS>
[[gnu::always_inline]] inline void FluidSolver::grain_drag_sums(std::vector<double> &Kgrain, bool proj, bool weak) {
  const int nlocal = pts.nlocal;
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  const double *const gst = g_.st.data();
  double *const gdr = g_.dr.data();
  double **v = pts.v;
  const double *radius = pts.radius, *rmass = pts.rmass;
  const int nsub = state.nsub;
  const double mu = opt.viscosity, rho_f = opt.eos.rho0;
  const double *lev = pressure_->solve() ? pressure_->solve()->grain_level() : nullptr;  // (immersion)
  for (int k = 0; k < nlocal; ++k) {
    if (!is_grain(k) || coup_->grain_shapes[k].base[0] == INT_MIN) continue;
    const Stencil &ps = coup_->grain_shapes[k];
    // one pass over the stencil: velocity of the wet nodes (and their total weight, the record's
    // 4th entry), fitted gradients of the determined nodes (and their weight), fluid fraction,
    // gradient of the nodal pressures
    Row4 uw = {0, 0, 0, 0}, fw = {0, 0, 0, 0};
    double th = 0.0, gradp[3] = {0, 0, 0};
    if (weak) {
      // the gradient the fluid itself feels at the nodes (weak_pressure_gradient), interpolated, in
      // the same pass (the fitted and the nodal gradients below are not read then)
      const double *const gw = grain_gradient();
      for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double, double, double) {
        const double *st = gst + StRec::N * n;
        uw += w * row4(st + StRec::U);
        th += w * st[StRec::TH];
        for (int d = 0; d < 3; ++d) gradp[d] += w * gw[3 * n + d];
      });
    } else {
      for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double gx, double gy, double gz) {
        const double *st = gst + StRec::N * n;
        uw += w * row4(st + StRec::U);
        fw += w * row4(st + StRec::FIT);
        th += w * st[StRec::TH];
        gradp[0] += st[StRec::P] * gx;
        gradp[1] += st[StRec::P] * gy;
        gradp[2] += st[StRec::P] * gz;
      });
    }
    const double wet = uw[3], wfit = fw[3];
    double u[3] = {uw[0], uw[1], uw[2]};
    // Pressure gradient at the grain: the fitted nodal gradients interpolated (exact for a linear
    // pressure field, also next to walls where a node's own fit is undetermined: all its points
    // in one layer); the gradient of the interpolated nodal pressures where no fit is determined.
    if (!weak && wfit > 0.5)
      for (int d = 0; d < 3; ++d) gradp[d] = fw[d] / wfit;
    const double d_k = 2.0 * radius[k];
    const double Vk = M_PI / 6.0 * d_k * d_k * d_k;
    const double immersed = immersion<NS>(ps, sy, sz, lev, opt.grid.dx, radius[k]);
    double K = 0.0;
    if (wet > 0.0) {
      for (int d = 0; d < 3; ++d) u[d] /= wet;
      const double urel = std::sqrt((u[0] - v[k][0]) * (u[0] - v[k][0]) + (u[1] - v[k][1]) * (u[1] - v[k][1]) +
                                    (u[2] - v[k][2]) * (u[2] - v[k][2]));
      K = immersed * drag_coefficient(opt.drag_law, opt.drag_form, rho_f, mu, d_k, Vk, th, urel, opt.theta_min);
    }
    Kgrain[k] = K;
    double Fp[3];
    pressure_gradient_force(immersed * Vk, gradp, Fp);
    if (wet <= 0.0) Fp[0] = Fp[1] = Fp[2] = 0.0;
    for (int d = 0; d < 3; ++d) coup_->grain_force[3 * static_cast<std::size_t>(k) + d] += Fp[d] / nsub;
    // the grain's other accelerations (contacts, gravity: its force so far, and the pressure
    // force), held over the step in the exchange
    double ak[3];
    for (int d = 0; d < 3; ++d) ak[d] = (pts.f[k][d] + Fp[d]) / rmass[k];
    // a grain no integrator moves (a fixed bed) has, for the exchange, infinite mass
    const bool mobile = (pts.mask[k] & pts.integrated_bits) != 0;
    if (!mobile) ak[0] = ak[1] = ak[2] = 0.0;
    const Row4 r0 = {K, K * v[k][0], K * v[k][1], K * v[k][2]};
    const Row4 r1 = {rmass[k], -Fp[0], -Fp[1], -Fp[2]};
    const Row4 r2 = {K * ak[0], K * ak[1], K * ak[2], mobile ? 0.0 : K};
    for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double, double, double) {
      double *q = gdr + DrRec::N * n;
      row4(q + DrRec::K) += w * r0;
      row4(q + DrRec::M) += w * r1;
      row4(q + DrRec::KA) += w * r2;
    });
  }
}

// couple_kernel: the drag impulse of each owned node inside dbox over h (drag_implicit_impulse),
// the force on the fluid (rx) and the impulse per unit K for the grains (dr).
void FluidSolver::drag_exchange(const IndexBox &dbox, double h) {
  const double mmin = mass_min();
  // The fluid's acceleration held over the step besides the drag: its forces so far (p2g F: body
  // forces, and with pressure eos its stress) and, with the projection, whose pressure acts only
  // after the exchange, the pressure gradient of the last solve (the one the grains feel, gw). Left
  // out, a fluid at rest in hydrostatic balance looked to the exchange as if it fell freely over
  // the step: the drag then pulled a held bed down by about K g h / 2 per grain (Archimedes on a
  // held random bed 0.92 with h = 8.6 ms; proportional to h and to the viscosity).
  const double *pgrad = pressure_->reaction_in_solve() ? grain_gradient() : nullptr;
  const double inv_rho = 1.0 / opt.eos.rho0;
  const bool proj = pressure_->reaction_in_solve();
  // node-wise exchange; the fluid's share of it stays on the owner (rx is read only there, by
  // update_grid; the other nodes keep the 0 of the allocation). At the owned nodes outside dbox
  // (no grain: K = 0, J = 0, the record keeps its zeros) rx is 0 - 0 / h = 0: only the nodes the
  // last call may have left nonzero (g_.xbox) are cleared, and only dbox's are visited, not the
  // whole patch (projection: rp, the grains' pressure reaction, written at the same nodes, alike)
  const IndexBox vis = grid_.restricted() ? grid_.owned().cut(grid_.work()) : grid_.owned();
  const IndexBox wbox = vis.cut(dbox);
  const std::vector<IndexBox> gone = vis.cut(g_.xbox).minus(wbox);
  grid_.zero_boxes(g_.rx, 3, gone);
  if (proj) grid_.zero_boxes(g_.rp, 3, gone);
  // (with a work box the nodes outside it keep what they had, as before: the box only grows)
  g_.xbox = grid_.restricted() ? g_.xbox.hull(wbox) : wbox;
  if (wbox.empty()) return;
  grid_.for_box(wbox, [&](int, int, int, std::size_t n) {
    double *rx = &g_.rx[3 * n];
    double *q = &g_.dr[DrRec::N * n];
    const double *st = &g_.st[StRec::N * n];
    double J[3] = {0, 0, 0};
    if (q[DrRec::K] > 0.0 && st[StRec::M] > mmin) {
      const double K = q[DrRec::K];
      const double vg[3] = {q[DrRec::KV] / K, q[DrRec::KV + 1] / K, q[DrRec::KV + 2] / K};
      const double ag[3] = {q[DrRec::KA] / K, q[DrRec::KA + 1] / K, q[DrRec::KA + 2] / K};
      const double *f = &g_.p2g[P2gRec::N * n + P2gRec::F];
      const double mf = st[StRec::M];
      // (projection: the pressure reaction is not a force of u*; Projection::exact_correction)
      const double fp[3] = {proj ? 0.0 : q[DrRec::FP], proj ? 0.0 : q[DrRec::FP + 1], proj ? 0.0 : q[DrRec::FP + 2]};
      double af[3] = {(f[0] + fp[0]) / mf, (f[1] + fp[1]) / mf, (f[2] + fp[2]) / mf};
      if (pgrad)
        for (int d = 0; d < 3; ++d) af[d] -= pgrad[3 * n + d] * inv_rho;
      const double mg = q[DrRec::KFIX] > 0.0 ? HUGE_VAL : q[DrRec::M];
      drag_implicit_impulse(vg, st + StRec::U, mg, mf, K, h, J, ag, af);
    }
    for (int d = 0; d < 3; ++d) {
      rx[d] = (opt.reaction_points || proj ? 0.0 : q[DrRec::FP + d]) - J[d] / h;  // force on the fluid
      q[DrRec::J + d] = q[DrRec::K] > 0.0 ? J[d] / q[DrRec::K] : 0.0;  // impulse per unit K, to the grains
    }
    // projection: the reaction of the grains' pressure force at the owned nodes, for the
    // projection's exact exchange along the periodic directions (Projection::exact_correction)
    if (proj)
      for (int d = 0; d < 3; ++d) g_.rp[3 * n + d] = q[DrRec::FP + d];
  });
}

// couple_kernel's last step: each grain's share of its nodes' drag impulses, as a force averaged
// over the sub-steps (coup_->grain_force).
template <int NS>
void FluidSolver::grain_drag_forces(const std::vector<double> &Kgrain, double h) {
  const int nlocal = pts.nlocal;
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  const double *const gdr = g_.dr.data();
  const int nsub = state.nsub;
  for (int k = 0; k < nlocal; ++k) {
    if (!is_grain(k) || coup_->grain_shapes[k].base[0] == INT_MIN || Kgrain[k] <= 0.0) continue;
    const Stencil &ps = coup_->grain_shapes[k];
    Row4 J = {0, 0, 0, 0};  // J[1..3]: the impulse per unit K of the nodes, weighted
    for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double, double, double) {
      J += w * row4(gdr + DrRec::N * n);
    });
    for (int d = 0; d < 3; ++d)
      coup_->grain_force[3 * static_cast<std::size_t>(k) + d] += Kgrain[k] * J[1 + d] / h / nsub;
  }
}

template <int NS>
void FluidSolver::couple_kernel(double h) {
  const int nlocal = pts.nlocal;
  double *const gdr = g_.dr.data();
  if (static_cast<int>(coup_->grain_shapes.size()) < nlocal) coup_->grain_shapes.resize(nlocal);

  // projection: the grains feel the nodal gradient of the last solve (grain_pressure); the fluid
  // gets no pressure reaction as a force: the projection takes it along the periodic directions
  // (the exact exchange, set_grain_reaction) and elsewhere its share -theta grad p is its correction
  const bool proj = pressure_->reaction_in_solve();
  const bool weak = opt.grad_p == GradP::Weak || proj;
  const bool moments = grains_need_nodes();  // grad_p nodal / fit: the points' pressure moments (pfit)
  grain_pressure_inputs<NS>(proj, weak);

  // the box of the grains' stencils (fluid_fraction found them for this sub-step)
  const IndexBox gbox = stencil_box(coup_->base_lo, coup_->base_hi, NS, grid_.patch());
  const std::vector<IndexBox> xboxes = grid_.exchanged_boxes();
  // What the grains read (st) is read only at their stencils, here and, through the forward, at
  // the owned nodes of the exchanged boxes, and by the drag exchange below in the same box: st is
  // set only at the owned nodes of the bounding box of those (the rest keeps stale values nobody
  // reads). dr is 0 outside that box after the reverse sum.
  const IndexBox dbox = bounding_box(gbox, xboxes);
  IndexBox sbox = grid_.owned().cut(dbox);
  if (grid_.restricted()) sbox = sbox.cut(grid_.work());
  // pfit is 0 outside the points' stencils and the exchanged boxes (with grad_p weak and the
  // projection everywhere): there the node reads a record of zeros, not the array
  const IndexBox pbox = stencil_box(pw_.base_lo, pw_.base_hi, NS, grid_.patch());
  const IndexBox rbox = moments ? bounding_box(pbox, xboxes) : IndexBox();
  if (!sbox.empty()) grain_node_state(sbox, rbox, weak);
  grid_.forward(g_.st.data(), StRec::N);

  // the drag coefficients, pressure forces and the grains' shares at the nodes (dr is 0 here: see
  // the end of this function)
  std::vector<double> Kgrain(static_cast<std::size_t>(nlocal), 0.0);
  grain_drag_sums<NS>(Kgrain, proj, weak);
  if (opt.every_auto) {
    // every auto: the mobile grains' shortest drag response time m / K (choose_every)
    double tau = HUGE_VAL;
    for (int k = 0; k < nlocal; ++k)
      if (Kgrain[k] > 0.0 && (pts.mask[k] & pts.integrated_bits)) tau = std::min(tau, pts.rmass[k] / Kgrain[k]);
    state.grain_tau = std::min(state.grain_tau, tau);
  }
  // the grains wrote dr in gbox only (0 elsewhere until the reverse sum)
  if (opt.reaction_points && !proj) {
    // the grains' pressure reaction, folded at the faces like their volume (route_reaction)
    std::fill(g_.rp.begin(), g_.rp.end(), 0.0);
    if (!gbox.empty())
      grid_.for_box(gbox, [&](int, int, int, std::size_t n) {
        for (int d = 0; d < 3; ++d) g_.rp[3 * n + d] = gdr[DrRec::N * n + DrRec::FP + d];
      });
    fold_to_mirror(g_.rp, 3);
  }
  // (the grains' pressure reaction with reaction points, summed in the same exchange)
  grid_.reverse_sum({{g_.dr.data(), DrRec::N}, {opt.reaction_points && !proj ? g_.rp.data() : nullptr, 3}});

  drag_exchange(dbox, h);
  if (opt.reaction_points && !proj) {
    route_reaction<NS>();
    g_.xbox = grid_.owned();  // route_reaction adds to rx at any owned node
  }
  // projection: the grains' pressure reaction for the solve (rp, written by drag_exchange)
  if (proj) pressure_->solve()->set_grain_reaction(g_.rp.data());
  grid_.forward(g_.dr.data(), DrRec::N);
  grain_drag_forces<NS>(Kgrain, h);
  // pfit and dr are 0 at the next call (they are allocated 0 and no other code writes them): only
  // the nodes written are cleared, the stencils of the points (pfit) and of the grains (dr) and
  // the halo and owner boxes of the exchanges; the drag exchange above wrote +0 to dr at the
  // other owned nodes (K = 0 there). This replaces clearing the whole arrays before their use
  // (pfit 20 doubles a node, dr 12; the points and grains of C3 fill a small part of the grid).
  std::vector<IndexBox> boxes = xboxes;
  boxes.push_back(gbox);
  grid_.zero_boxes(g_.dr, DrRec::N, boxes);
  if (moments) {
    boxes.back() = pbox;
    grid_.zero_boxes(g_.pfit, PfitRec::N, boxes);
  }
}

/* grad_p weak: the points' volume and external force at the nodes (WkRec, reverse-summed), and
   with reaction points the volume again folded at the faces (rq[3 n], for route_reaction; with
   grad_p nodal or fit pressure_moments sums it in its pass over the points). */
template <int NS>
void FluidSolver::point_sums() {
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  double *const wk = g_.wk.data();
  std::fill(g_.wk.begin(), g_.wk.end(), 0.0);
  for (const int i : pw_.plist) {
    const double *f = pts.f[i];
    const Row4 r = {pts.state[i][C_VOL], f[0], f[1], f[2]};
    for_stencil<NS>(pw_.shapes[i], sy, sz, [&](std::size_t n, int, int, int, double w, double, double, double) {
      row4(wk + WkRec::N * n) += w * r;
    });
  }
  if (opt.reaction_points) {
    std::fill(g_.rq.begin(), g_.rq.end(), 0.0);
    for (std::size_t n = 0; n < grid_.size(); ++n) g_.rq[3 * n] = wk[WkRec::N * n + WkRec::V];
    fold_to_mirror(g_.rq, 3);
  }
  // (the volume folded at the faces with reaction points, summed in the same exchange)
  grid_.reverse_sum({{g_.wk.data(), WkRec::N}, {opt.reaction_points ? g_.rq.data() : nullptr, 3}});
}

/* grad_p weak, the points' view of the nodal gradient: g_p = sum_i S_ip g_i at the points, then
   g_j = sum_p S_jp V_p g_p / sum_p S_jp V_p. A uniform field stays uniform; what goes is the part
   of the nodal residual that no point sees (the MPM null space of quadratic B-splines with 2
   points per cell: forces alternating in sign from node layer to node layer move no point and so
   stay at rest). At rest under a free surface 3 cells above the floor that part was +5 % / -14 %
   of rho g on alternate layers, and a bed between them read 1.020 of Archimedes. rp is scratch. */
template <int NS>
void FluidSolver::smooth_weak_gradient() {
  const double vmin = 1e-12 * opt.grid.dx * opt.grid.dx * opt.grid.dx;
  through_points<NS>(g_.gw.data(), g_.rp);
  const double *const acc = g_.rp.data();
  grid_.for_owned([&](int, int, int, std::size_t n) {
    const double V = g_.wk[WkRec::N * n + WkRec::V];
    for (int d = 0; d < 3; ++d) g_.gw[3 * n + d] = V > vmin ? acc[3 * n + d] / V : 0.0;
  });
  grid_.forward(g_.gw.data(), 3);
  weak_face_copy();
}

/* reaction points: the grains' pressure reaction r_i (rp, owned, folded) goes to the fluid
   through its points, the way the fluid's displaced mass went (theta_p interpolated from the
   nodes, then mapped back with the mass): q_i = r_i / V_i (V_i = sum_p S_ip V_p folded, smoothed
   like the grains' volume with theta_smooth), q_p = sum_i S_ip q_i, R_j = sum_p S_jp V_p q_p.
   For a uniform gradient this is exactly the complement of the fluid's weight, and
   sum_j R_j = sum_i r_i (momentum kept). A node with a reaction but no fluid point keeps it. */
template <int NS>
void FluidSolver::route_reaction() {
  const double vmin = 1e-12 * opt.grid.dx * opt.grid.dx * opt.grid.dx;
  if (opt.theta_smooth > 0.0) smooth_node_volume(g_.rp, 3);
  grid_.for_owned([&](int, int, int, std::size_t n) {
    const double V = g_.rq[3 * n];
    for (int d = 0; d < 3; ++d) {
      const double r = g_.rp[3 * n + d];
      g_.rq[3 * n + d] = V > vmin ? r / V : 0.0;
      if (!(V > vmin)) g_.rx[3 * n + d] += r;
    }
  });
  grid_.forward(g_.rq.data(), 3);
  // padding nodes take their mirror's value, as the fluid fraction does
  const IndexBox &pb = grid_.patch();
  auto copy = [&](int i, int j, int k) {
    const int mi[3] = {opt.grid.mirror(i, 0), opt.grid.mirror(j, 1), opt.grid.mirror(k, 2)};
    if ((mi[0] == i && mi[1] == j && mi[2] == k) || !grid_.in_patch(mi[0], mi[1], mi[2])) return;
    const std::size_t n = grid_.index(i, j, k), m = grid_.index(mi[0], mi[1], mi[2]);
    for (int d = 0; d < 3; ++d) g_.rq[3 * n + d] = g_.rq[3 * m + d];
  };
  // only a padding node has a mirror other than itself; when the padding is no deeper than the
  // grid every mirror lies inside, where no copy writes, and the padding layers along each
  // direction are visited alone (a corner node more than once, with the same copy)
  bool shallow = true;
  for (int e = 0; e < 3; ++e)
    if (!opt.grid.periodic[e]) shallow = shallow && pb.lo[e] >= -opt.grid.ncell[e] && pb.hi[e] <= 2 * opt.grid.ncell[e];
  if (shallow) {
    for (int e = 0; e < 3; ++e) {
      if (opt.grid.periodic[e]) continue;
      for (const IndexBox &b : opt.grid.padding_layers(pb, e))
        if (!b.empty()) grid_.for_box(b, [&](int i, int j, int k, std::size_t) { copy(i, j, k); });
    }
  } else {
    grid_.for_box(pb, [&](int i, int j, int k, std::size_t) { copy(i, j, k); });
  }
  through_points<NS>(g_.rq.data(), g_.rp);
  const double *const rr = g_.rp.data();
  grid_.for_owned([&](int, int, int, std::size_t n) {
    for (int d = 0; d < 3; ++d) g_.rx[3 * n + d] += rr[3 * n + d];
  });
}

/* A node's 3 values as a Row4 (the 4th 0): with AVX one masked load (the 4th lane not read), else
   element by element; and a Row4's first 3 added back element by element (an AVX masked store
   there took fewer instructions but the coupling ran slower, docs/validation/performance.md "The
   coupling's sweeps"). The sums are the same operations in the same order either way. */
#if defined(__AVX__)
static inline Row4 load3(const double *p) {
  return (Row4)_mm256_maskload_pd(p, _mm256_set_epi64x(0, -1, -1, -1));
}
#else
static inline Row4 load3(const double *p) { return Row4{p[0], p[1], p[2], 0.0}; }
#endif
static inline void add3(double *p, double w, const Row4 &v) {
  for (int d = 0; d < 3; ++d) p[d] += w * v[d];
}

template <int NS>
void FluidSolver::through_points(const double *q, std::vector<double> &out) {
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  std::fill(out.begin(), out.end(), 0.0);
  double *const o = out.data();
  for (const int i : pw_.plist) {
    const Stencil &ps = pw_.shapes[i];
    Row4 qp = {0, 0, 0, 0};
    for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double, double, double) {
      qp += w * load3(q + 3 * n);
    });
    const Row4 vq = pts.state[i][C_VOL] * qp;
    for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double w, double, double, double) {
      add3(o + 3 * n, w, vq);
    });
  }
  grid_.reverse_sum(out.data(), 3);
}

}  // namespace mpm
