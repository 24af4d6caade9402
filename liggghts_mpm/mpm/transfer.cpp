// The transfer phases of the solver: P2G, G2P and the MUSL remap (solver.h, transfer.h).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "mpm/error.h"
#include "mpm/solver.h"
#include "mpm/transfer.h"

namespace mpm {

/* particles to grid: mass (8-19), momentum (8-10), internal force (8-24),
   external forces (gravity (8-18) and whatever the host's fixes add), wall traction (8-23); the
   pressure model's (EOS: the points' pressure in the internal force and the traction) */
void FluidSolver::particles_to_grid() { pressure_->particles_to_grid(*this); }

void FluidSolver::p2g(bool eos) {
  clear_nodes(g_.p2g, P2gRec::N);
  // the boundary term of each point right after its own share, so that every node sums its
  // contributions in point order
  // (projection: the walls' reaction is the solve's pressure, not a traction of the points)
  const bool traction = opt.shape == ShapeKind::QuadraticBSpline && eos;
  double *const g = g_.p2g.data();
  auto boundary_term = [&](int i, const Stencil &ps) {
    if (traction) bc.add_traction(ps, pts.x[i], pts.state[i][C_VOL], pts.state[i][C_P], g);
  };
  with_policy(opt, [&](auto pol) { p2g_kernel<decltype(pol)::NS, decltype(pol)>(boundary_term, eos); });
  grid_.reverse_sum(g_.p2g.data(), P2gRec::N);
}

template <int NS, class P, class Fn>
void FluidSolver::p2g_kernel(Fn &&after_point, bool eos) {
  double **x = pts.x, **v = pts.v, **f = pts.f;
  const double *rmass = pts.rmass;
  double *const g = g_.p2g.data();
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  const bool eos_p = eos;  // projection: no pressure in the internal force (u*)
  for (const int i : pw_.plist) {
    const Stencil &ps = pw_.shapes[i];
    const double *s = pts.state[i];
    const double m = rmass[i], V = s[C_VOL], p = eos_p ? s[C_P] : 0.0;
    const double *t = s + C_TAU;
    // -V sigma with sigma = -p I + tau (tau in Voigt order xx yy zz yz xz xy)
    const double sxx = -V * (t[0] - p), syy = -V * (t[1] - p), szz = -V * (t[2] - p);
    const double syz = -V * t[3], sxz = -V * t[4], sxy = -V * t[5];
    // each node update is two 4-wide rows of the record (mass and momentum; force)
    const Row4 mv = {m, m * v[i][0], m * v[i][1], m * v[i][2]};
    const Row4 fe = {f[i][0], f[i][1], f[i][2], 0.0};
    const Row4 sx = {sxx, sxy, sxz, 0.0}, sy_ = {sxy, syy, syz, 0.0}, sz_ = {sxz, syz, szz, 0.0};
    // APIC: the affine momentum in the momentum lanes 1..3 of the row
    Row4 col[3] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}};
    double o[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    if (P::apic) {
      double mC[9];
      for (int c = 0; c < 9; ++c) mC[c] = m * s[C_AFF + c];
      affine_columns(mC, 1, col);
      stencil_offsets(opt.grid, ps, x[i], o);
    }
    for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double gx, double gy, double gz) {
      Row4 u = mv;
      if (P::apic) u = mv + affine_row(col, o, a, b, c);
      double *gn = g + P2gRec::N * n;
      row4(gn + P2gRec::M) += w * u;
      row4(gn + P2gRec::F) += w * fe + gx * sx + gy * sy_ + gz * sz_;
    });
    after_point(i, ps);
  }
}

/* grid to particles: velocity (8-37)/(8-40), affine velocity, velocity gradient */
void FluidSolver::grid_to_particles() {
  with_policy(opt, [&](auto pol) { g2p_kernel<decltype(pol)::NS, decltype(pol)>(); });
}

template <int NS, class P>
void FluidSolver::g2p_kernel() {
  double **x = pts.x, **v = pts.v;
  const double *const gvel = g_.vel.data();
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  const double dinv = apic_dinv_bspline2() / (opt.grid.dx * opt.grid.dx);
  const bool flip = opt.transfer == Transfer::Flip;
  const double alpha = opt.flip_alpha;
  // the gradient of this transfer: in the affine record for FLIP and PIC, in pw_.velgrad for APIC
  if (P::need_L) pw_.grad_in_state = !P::apic;
  for (const int i : pw_.plist) {
    const Stencil &ps = pw_.shapes[i];
    double *s = pts.state[i];
    // 4-wide accumulators of the velocity record; L and B by columns: Lc[e][d] = sum v_d dS/dx_e
    Row4 vp = {0, 0, 0, 0}, dv = {0, 0, 0, 0};
    Row4 Lc[3] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}}, Bc[3] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}};
    double o[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    if (P::inertia) stencil_offsets(opt.grid, ps, x[i], o);
    for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double gx, double gy, double gz) {
      const Row4 un = row4(gvel + VelRec::N * n + VelRec::V_NEW), uo = row4(gvel + VelRec::N * n + VelRec::V_OLD);
      vp += w * un;
      dv += w * (un - uo);
      if (P::need_L) {
        Lc[0] += gx * un;
        Lc[1] += gy * un;
        Lc[2] += gz * un;
      }
      if (P::inertia) {
        const double ox = w * o[0][a], oy = w * o[1][b], oz = w * o[2][c];
        Bc[0] += ox * un;
        Bc[1] += oy * un;
        Bc[2] += oz * un;
      }
    });
    double L[9], B[9];
    for (int d = 0; d < 3; ++d)
      for (int e = 0; e < 3; ++e) {
        L[3 * d + e] = Lc[e][d];
        B[3 * d + e] = Bc[e][d];
      }
    for (int d = 0; d < 3; ++d) pw_.vpic[3 * i + d] = vp[d];
    if (flip) {
      for (int d = 0; d < 3; ++d) v[i][d] = alpha * (v[i][d] + dv[d]) + (1.0 - alpha) * vp[d];
    } else {
      for (int d = 0; d < 3; ++d) v[i][d] = vp[d];
    }
    // Affine field: B D^-1 for the quadratic B-spline (exact inertia), the velocity gradient for
    // linear shape functions and for FLIP/PIC without MUSL; with MUSL, FLIP/PIC store the
    // remapped gradient there.
    if (P::inertia)
      for (int c = 0; c < 9; ++c) s[C_AFF + c] = B[c] * dinv;
    else if (P::need_L)
      for (int c = 0; c < 9; ++c) s[C_AFF + c] = L[c];
    if (!(std::isfinite(v[i][0]) && std::isfinite(v[i][1]) && std::isfinite(v[i][2]))) {
      std::ostringstream os;
      os << "Fix mpm/fluid: velocity of material point " << pts.tag[i] << " is not finite at step " << clock.step
         << "; the fluid became unstable (reduce the timestep or the bulk modulus)";
      throw LocalError(os.str());
    }
    // velocity gradient for the stress update (USL; MUSL recomputes it)
    if (P::need_L && P::apic) std::copy(L, L + 9, &pw_.velgrad[9 * static_cast<std::size_t>(i)]);
  }
}

/* MUSL (Buzzi et al. 2008, text after (8-41)): the updated point momentum (with its new affine
   field for APIC), mapped back to the grid, gives the velocity gradient for the stress update,
   still at the positions of the start of the step. */
void FluidSolver::remap_velocity_musl(double h) {
  clear_nodes(g_.aux, AuxRec::N);
  with_policy(opt, [&](auto pol) { musl_scatter<decltype(pol)::NS, decltype(pol)>(); });
  grid_.reverse_sum(g_.aux.data(), AuxRec::N);
  const double mmin = mass_min();
  for_owned_nodes([&](int i, int j, int k, std::size_t n) {
    const double m = g_.p2g[P2gRec::N * n + P2gRec::M];
    double *g = &g_.aux[AuxRec::N * n + AuxRec::U];
    if (m <= mmin || m <= 0.0) {
      g[0] = g[1] = g[2] = 0.0;
      return;
    }
    const double inv = 1.0 / m;
    for (int d = 0; d < 3; ++d) g[d] *= inv;
    // the remapped velocity moves the points and gives their velocity gradient; the momentum of
    // the points is not changed here, so the wall conditions (a shear wall's stress over h too)
    // are those of the grid update
    bc.apply(g, i, j, k, h);
  });
  grid_.forward(g_.aux.data(), AuxRec::N);
  with_stencil(opt.shape, [&](auto ns) { musl_gradient<decltype(ns)::value>(); });
}

template <int NS, class P>
void FluidSolver::musl_scatter() {
  double **x = pts.x, **v = pts.v;
  const double *rmass = pts.rmass;
  double *const ga = g_.aux.data();
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  for (const int i : pw_.plist) {
    const Stencil &ps = pw_.shapes[i];
    const double *s = pts.state[i];
    const double m = rmass[i];
    const Row4 mv = {m * v[i][0], m * v[i][1], m * v[i][2], 0.0};
    Row4 col[3] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}};
    double o[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    if (P::apic) {
      double mC[9];
      for (int c = 0; c < 9; ++c) mC[c] = m * s[C_AFF + c];
      affine_columns(mC, 0, col);
      stencil_offsets(opt.grid, ps, x[i], o);
    }
    for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double, double, double) {
      Row4 u = mv;
      if (P::apic) u = mv + affine_row(col, o, a, b, c);
      row4(ga + AuxRec::N * n + AuxRec::U) += w * u;
    });
  }
}

template <int NS>
void FluidSolver::musl_gradient() {
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  const double *const ga = g_.aux.data();
  const bool store_affine = opt.transfer != Transfer::Apic;
  // anti-locking (eos): the cell sums of the stress update (update_stress) are taken here, in the
  // same point order, while the point's record is at hand (one pass over the points less)
  const bool cells = pressure_->pressure_is_stress();
  if (cells) {
    if (pw_.pcell.size() < static_cast<std::size_t>(pts.nlocal)) pw_.pcell.resize(pts.nlocal);
    clear_nodes(g_.cell, CellRec::N);
  }
  for (const int i : pw_.plist) {
    const Stencil &ps = pw_.shapes[i];
    Row4 Lc[3] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}};  // Lc[e][d] = sum v_d dS/dx_e
    for_stencil<NS>(ps, sy, sz, [&](std::size_t n, int, int, int, double, double gx, double gy, double gz) {
      const Row4 u = row4(ga + AuxRec::N * n + AuxRec::U);
      Lc[0] += gx * u;
      Lc[1] += gy * u;
      Lc[2] += gz * u;
    });
    double L[9];
    for (int d = 0; d < 3; ++d)
      for (int e = 0; e < 3; ++e) L[3 * d + e] = Lc[e][d];
    if (store_affine)
      std::copy(L, L + 9, pts.state[i] + C_AFF);
    else
      std::copy(L, L + 9, &pw_.velgrad[9 * static_cast<std::size_t>(i)]);
    if (cells) sum_cell(i, L);
  }
  pw_.cells_summed = cells;
  pw_.grad_in_state = store_affine;
}

}  // namespace mpm
