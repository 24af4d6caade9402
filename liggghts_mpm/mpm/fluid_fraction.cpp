// The fluid-fraction phases of the solver (chapter 8.1): the fluid fraction at the nodes and the
// points from the grains' volumes, its smoothing (coupling.h) and the first-run mass reduction
// (solver.h; the drag and pressure exchange with the grains are in coupling.cpp).
#include <algorithm>
#include <climits>
#include <cmath>
#include <sstream>

#include "mpm/coupling.h"
#include "mpm/error.h"
#include "mpm/solver.h"

namespace mpm {
// One pass of smooth_node_volume along a row of len nodes from n0 whose neighbours along the
// pass's direction (n -+ sd) all exist: smoothing_step's arithmetic (the same operations in the
// same order), free of the per-node tests; the division is done before the test V > 0 and the
// function is compiled without trapping math (it changes no value: it lets the compiler treat the
// comparisons and the division as free of side effects), so that the loop is vectorized
#if defined(__GNUC__) && !defined(__clang__)
#define MPM_NO_TRAPPING_MATH __attribute__((optimize("no-trapping-math")))
#else
#define MPM_NO_TRAPPING_MATH
#endif
template <int ST>
MPM_NO_TRAPPING_MATH static void smooth_row(const double *p, double *q, const double *V, std::size_t n0, int len, std::size_t sd) {
  for (int t = 0; t < len; ++t) {
    const std::size_t n = n0 + static_cast<std::size_t>(t);
    const double v = V[n], v0 = V[n - sd], v1 = V[n + sd];
    for (int c = 0; c < ST; ++c) {
      const double ph = p[ST * n + c];
      double S = ph * v;
      S += 0.25 * (v < v0 ? v : v0) * (p[ST * (n - sd) + c] - ph);
      S += 0.25 * (v < v1 ? v : v1) * (p[ST * (n + sd) + c] - ph);
      const double r = S / v;
      q[ST * n + c] = v > 0.0 ? r : 0.0;
    }
  }
}

int smoothing_passes(double L, double dx) { return static_cast<int>(std::ceil(2.0 * L * L / (dx * dx) - 1e-9)); }

// fn(n, w) for the nodes a stencil reaches (the solver's shape functions)
template <class Fn>
void FluidSolver::for_nodes(const Stencil &ps, Fn &&fn) const {
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  auto body = [&](std::size_t n, int, int, int, double w, double, double, double) { fn(n, w); };
  if (opt.shape == ShapeKind::QuadraticBSpline)
    for_stencil<3>(ps, sy, sz, body);
  else
    for_stencil<2>(ps, sy, sz, body);
}

// Node volume for the grains' volume fraction (8-13) with shape functions reflected at the grid
// faces: half a cell on a wall, a full cell inside, none outside (the text's (8-13) integrates
// the unreflected shape function over the inside, which leaves the padding node 1/48 of a cell).
double FluidSolver::solid_node_volume(int i, int j, int k) const {
  const GridSpec &gs = opt.grid;
  const int idx[3] = {i, j, k};
  double v = gs.dx * gs.dx * gs.dx;
  for (int d = 0; d < 3; ++d) {
    if (gs.periodic[d]) continue;
    if (idx[d] < 0 || idx[d] > gs.ncell[d]) return 0.0;
    if (idx[d] == 0 || idx[d] == gs.ncell[d]) v *= 0.5;
  }
  return v;
}

void FluidSolver::setup_coupling() { coup_->setup(*this); }

// At the first run with grains: the fluid present in a point's volume is theta of it, so its
// mass is reduced once to theta rho0 V (8-3): otherwise the grains' volume would be counted as
// compressed fluid.
void FluidSolver::init_theta() {
  compute_shapes();
  fluid_fraction();
  for (int i = 0; i < pts.nlocal; ++i) {
    if (!is_point(i)) continue;
    double *s = pts.state[i];
    pts.rmass[i] *= s[C_THETA];
    s[C_RHO] = pts.rmass[i] / (s[C_THETA] * s[C_VOL]);
  }
  state.theta_initialized = true;
}

/* Fluid fraction (8-11)-(8-14) at the nodes from the grains' volumes (with the optional
   smoothing) and at the points (8-16). Done at the start of each sub-step, before the
   particles-to-grid map and the forces on the grains, so that the pressure with which the fluid
   and the grains push each other belongs to the grains' present positions (refresh_pressure):
   with the pressure of the previous sub-step the restoring force of the fluid on a grain lags
   one step behind its displacement, which feeds energy into the grain-fluid oscillation (stiff:
   K / theta per unit volume change) and made the moving dense bed of C3 blow up. */
/* What the coupling reads of grain k (position, velocity, radius, mass) is finite, the radius
   and mass positive: a grain whose mass underflowed (d = 1e-110) gets a non-finite position from
   its integrator, whose stencil would index far outside the grid. */
void FluidSolver::check_grain(int k) const {
  const double *x = pts.x[k], *v = pts.v[k];
  const char *what = first_bad(x, v, &pts.radius[k], pts.rmass[k]);
  if (!what) return;
  std::ostringstream os;
  os << "Fix mpm/fluid: the " << what << " of grain " << pts.tag[k] << " (group '" << opt.couple_group
     << "') is not finite" << (what[0] == 'r' || what[0] == 'm' ? " and positive" : "") << " at step " << clock.step << " (x = (" << x[0] << ", " << x[1] << ", " << x[2]
     << "), v = (" << v[0] << ", " << v[1] << ", " << v[2] << "), radius " << pts.radius[k] << ", mass " << pts.rmass[k]
     << "); a grain of underflowing mass or an unstable DEM step";
  throw LocalError(os.str());
}

bool FluidSolver::grains_need_nodes() const { return opt.grad_p != GradP::Weak && !pressure_->reaction_in_solve(); }

void FluidSolver::fluid_fraction() {
  const int nlocal = pts.nlocal;
  double **x = pts.x;
  const double *radius = pts.radius;
  if (static_cast<int>(coup_->grain_shapes.size()) < nlocal) coup_->grain_shapes.resize(nlocal);
  // the nodes some grain reads are needed only by the pressure moments of grad_p nodal and fit
  // (pressure_moments, grain_node_state); grad_p weak and the projection never read them
  double *const need = grains_need_nodes() ? g_.need.data() : nullptr;
  std::fill(g_.sol.begin(), g_.sol.end(), 0.0);
  if (need) std::fill(g_.need.begin(), g_.need.end(), 0.0);
  // (the box of the stencil bases in locals, written back after the loop: stores to the members
  // inside it could alias the sums and were made for every grain)
  int blo[3] = {INT_MAX, INT_MAX, INT_MAX}, bhi[3] = {INT_MIN, INT_MIN, INT_MIN};
  double *const sol = g_.sol.data();
  for (int k = 0; k < nlocal; ++k) {
    if (!is_grain(k)) continue;
    check_grain(k);
    Stencil &ps = coup_->grain_shapes[k];
    if (!shape_of(x[k], ps)) {
      ps.base[0] = INT_MIN;  // outside the grid: no fluid there
      continue;
    }
    for (int d = 0; d < 3; ++d) {
      blo[d] = std::min(blo[d], ps.base[d]);
      bhi[d] = std::max(bhi[d], ps.base[d]);
    }
    const double Vk = 4.0 / 3.0 * M_PI * radius[k] * radius[k] * radius[k];
    for_nodes(ps, [&](std::size_t n, double w) {
      sol[n] += w * Vk;
      if (need) need[n] = 1.0;
    });
  }
  for (int d = 0; d < 3; ++d) {
    coup_->base_lo[d] = blo[d];
    coup_->base_hi[d] = bhi[d];
  }
  // Walls: the solid volume mapped to a node outside a grid face is folded onto its mirror node
  // inside (reflected shape functions), so that no node has the sliver volume that (8-13) gives
  // the padding nodes (1/48 of a cell for the B-spline: one grain near the wall would swing its
  // theta by tens of per cent, and the pressure of the points next to the wall with it, by
  // K dtheta/theta). Node volumes: half a cell on the wall, full inside; a padding node takes the
  // fraction of its mirror.
  fold_to_mirror(g_.sol, 1);
  // the solid volume and the nodes some grain reads (fit of the pressure only there), summed in
  // one exchange; need goes back to the halo copies with theta below: a point of this rank must
  // add its pressure moments to a node that only another rank's grain reads (else np 2 differs
  // from np 1 with 'grad_p fit')
  grid_.reverse_sum({{need, 1}, {g_.sol.data(), 1}});
  if (opt.theta_smooth > 0.0) smooth_solid_volume();
  // the mirror node and its volume of every owned node depend on the patch only: found once
  if (g_.th_src.size() != grid_.size()) {
    g_.th_src.assign(grid_.size(), 0);
    g_.th_vol.assign(grid_.size(), 0.0);
    grid_.for_owned_all([&](int i, int j, int k, std::size_t n) {
      const int mi[3] = {opt.grid.mirror(i, 0), opt.grid.mirror(j, 1), opt.grid.mirror(k, 2)};
      g_.th_vol[n] = solid_node_volume(mi[0], mi[1], mi[2]);
      g_.th_src[n] = grid_.in_patch(mi[0], mi[1], mi[2]) ? grid_.index(mi[0], mi[1], mi[2]) : n;
    });
  }
  {
    const std::size_t *const src = g_.th_src.data();
    const double *const Vj = g_.th_vol.data(), *const sol = g_.sol.data();
    double *const th = g_.th.data();
    const double tmin = opt.theta_min;
    grid_.for_owned([&](int, int, int, std::size_t n) {
      th[n] = std::min(1.0, std::max(tmin, 1.0 - sol[src[n]] / Vj[n]));  // (8-11), (8-14)
    });
  }
  grid_.forward({{g_.th.data(), 1}, {need, 1}});
  const double *const gth = g_.th.data();
  for (const int i : pw_.plist) {
    double th = 0.0;
    for_nodes(pw_.shapes[i], [&](std::size_t n, double w) { th += w * gth[n]; });
    pts.state[i][C_THETA] = th;
  }
}

// The points' density and pressure for the new fluid fraction (their volume is unchanged).
void FluidSolver::refresh_pressure() { update_stress(0.0, true); }

/* Walls: what is mapped to a node outside a grid face (patch, partial sums before the reverse sum)
   is folded onto its mirror node inside (reflected shape functions), one direction after the
   other, so a corner's share ends on the inside too. */
void FluidSolver::fold_to_mirror(std::vector<double> &a, int stride) {
  const GridSpec &gs = opt.grid;
  const IndexBox &pb = grid_.patch();
  for (int d = 0; d < 3; ++d) {
    if (gs.periodic[d]) continue;
    // only the patch's padding layers outside the low and the high face
    for (const IndexBox &b : gs.padding_layers(pb, d)) {
      for (int k = b.lo[2]; k <= b.hi[2]; ++k)
        for (int j = b.lo[1]; j <= b.hi[1]; ++j)
          for (int i = b.lo[0]; i <= b.hi[0]; ++i) {
            int idx[3] = {i, j, k};
            idx[d] = gs.mirror(idx[d], d);
            if (!grid_.in_patch(idx[0], idx[1], idx[2])) continue;
            double *from = &a[stride * grid_.index(i, j, k)];
            double *to = &a[stride * grid_.index(idx[0], idx[1], idx[2])];
            for (int c = 0; c < stride; ++c)
              if (from[c] != 0.0) {
                to[c] += from[c];
                from[c] = 0.0;
              }
          }
    }
  }
}

/* Smoothing of the grains' volume at the owned nodes by a discrete diffusion of the solid
   fraction phi_j = S_j / V_j (smoothing_step along each direction, smoothing_passes passes). */
void FluidSolver::smooth_solid_volume() { smooth_node_volume(g_.sol); }

// The same filter for any volume-like quantity at the owned nodes: a holds `stride` values per
// node, each smoothed alone (one pass over the nodes and one exchange for all of them).
void FluidSolver::smooth_node_volume(std::vector<double> &a, int stride) {
  const GridSpec &gs = opt.grid;
  const int passes = smoothing_passes(opt.theta_smooth, gs.dx);
  if (passes <= 0) return;
  const std::size_t N = grid_.size();
  const std::vector<double> &vol = node_volumes();
  // phi and phi_new take turns (each pass writes the other and they swap): both are 0 outside the
  // box of the pass, which only grows, so the nodes a pass does not write hold the same in both
  std::vector<double> &phi = g_.phi, &phi_new = g_.phi_new;
  phi.assign(stride * N, 0.0);
  phi_new.assign(stride * N, 0.0);
  IndexBox nzb;  // the nodes with a nonzero fraction, grown by the passes
  smoothing_start(a, stride, nzb);
  int *const lo = nzb.lo, *const hi = nzb.hi;
  const bool any = !nzb.empty();
  grid_.forward(phi.data(), stride);
  const IndexBox &ob = grid_.owned();
  const double *const V = vol.data();
  IndexBox b = ob.cut(nzb);  // owned nodes inside the box
  for (int pass = 0; pass < passes && any; ++pass)
    for (int d = 0; d < 3; ++d) {
      if (!gs.periodic[d] && gs.ncell[d] < 2) continue;
      if (!gs.periodic[d]) {
        --lo[d];
        ++hi[d];
      }
      b = ob.cut(nzb);
      smoothing_sweep(d, stride, b, V);
      phi.swap(phi_new);
      grid_.forward(phi.data(), stride);
    }
  if (!any) return;  // a is +-0 at every owned node with a volume, 0 on the others: as phi V
  // outside the last box phi is 0 and a was +-0 (or set 0 above): only the box is written back
  grid_.for_box(b, [&](int, int, int, std::size_t n) {
    for (int c = 0; c < stride; ++c) a[stride * n + c] = phi[stride * n + c] * V[n];
  });
}

// smooth_node_volume: the node volumes of the patch (solid_node_volume), computed once.
const std::vector<double> &FluidSolver::node_volumes() {
  const std::size_t N = grid_.size();
  // the node volumes of the patch (owned, forwarded to the halo; 0 on padding nodes) do not change
  // with the grid's patch: computed once after setup_grid
  std::vector<double> &vol = g_.vnode;
  if (!g_.vnode_ready) {
    g_.vnode_ready = true;
    vol.assign(N, 0.0);
    grid_.for_owned([&](int i, int j, int k, std::size_t n) { vol[n] = solid_node_volume(i, j, k); });
    grid_.forward(vol.data(), 1);
  }
  return vol;
}

// smooth_node_volume's start: phi = a / V at the owned nodes (a set 0 on owned padding nodes) and
// nzb, the box of the nodes with a nonzero fraction.
void FluidSolver::smoothing_start(std::vector<double> &a, int stride, IndexBox &nzb) {
  const GridSpec &gs = opt.grid;
  const std::vector<double> &vol = g_.vnode;
  std::vector<double> &phi = g_.phi;
  // the box (global node indices, over all ranks) of the nodes with a nonzero fraction: a pass
  // along d changes no node farther than one node along d from it, so the passes sweep only that
  // box, grown by one node along d before each pass along d; everywhere else phi stays 0, as the
  // pass would give it. (The C3 tank at Grid40, theta_smooth 0.01: 8 passes x 3 directions over
  // the whole grid, twice per coupled step, took 40 % of the run.)
  int box[6] = {INT_MAX, INT_MAX, INT_MAX, INT_MAX, INT_MAX, INT_MAX};  // lo[3], -hi[3]
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    const double V = vol[n];
    bool nz = false;
    for (int c = 0; c < stride; ++c) {
      phi[stride * n + c] = V > 0.0 ? a[stride * n + c] / V : 0.0;
      if (phi[stride * n + c] != 0.0) nz = true;
      // an owned padding node (no volume) keeps phi = 0 in every pass and ends with a = 0 x 0
      if (!(V > 0.0)) a[stride * n + c] = 0.0;
    }
    if (nz) {
      const int idx[3] = {i, j, k};
      for (int d = 0; d < 3; ++d) {
        box[d] = std::min(box[d], idx[d]);
        box[3 + d] = std::min(box[3 + d], -idx[d]);
      }
    }
  });
  MPI_Allreduce(MPI_IN_PLACE, box, 6, MPI_INT, MPI_MIN, comm_);
  int *const lo = nzb.lo, *const hi = nzb.hi;
  for (int d = 0; d < 3; ++d) {
    lo[d] = box[d];
    hi[d] = box[3 + d] == INT_MAX ? INT_MIN : -box[3 + d];
    if (gs.periodic[d] && lo[d] <= hi[d]) {  // indices wrap: no restriction along d
      lo[d] = INT_MIN / 2;
      hi[d] = INT_MAX / 2;
    }
  }
}

// One pass of smooth_node_volume along d over the owned nodes of box b: phi_new from phi.
void FluidSolver::smoothing_sweep(int d, int stride, const IndexBox &b, const double *V) {
  const IndexBox &pb = grid_.patch();
  const std::size_t step[3] = {1, grid_.stride_y(), grid_.stride_z()};
  const double *const p = g_.phi.data();
  double *const q = g_.phi_new.data();
  const std::size_t sd = step[d];
  // row by row along x: along y and z a row's neighbours exist or not as a whole, along x
  // they do except at the patch's ends
  auto one = [&](std::size_t n, int id) {  // any node: the neighbours that exist
    const bool has[2] = {id - 1 >= pb.lo[d], id + 1 <= pb.hi[d]};
    const std::size_t m[2] = {has[0] ? n - sd : 0, has[1] ? n + sd : 0};
    const double Vn[2] = {has[0] ? V[m[0]] : 0.0, has[1] ? V[m[1]] : 0.0};
    for (int c = 0; c < stride; ++c) {
      const double phin[2] = {has[0] ? p[stride * m[0] + c] : 0.0, has[1] ? p[stride * m[1] + c] : 0.0};
      q[stride * n + c] = smoothing_step(V[n], p[stride * n + c], Vn, phin, has);
    }
  };
  auto row = [&](std::size_t n0, int len) {  // nodes n0 .. n0 + len - 1 with both neighbours
    if (len <= 0) return;
    if (stride == 1)
      smooth_row<1>(p, q, V, n0, len, sd);
    else if (stride == 3)
      smooth_row<3>(p, q, V, n0, len, sd);
    else
      for (int t = 0; t < len; ++t) one(n0 + static_cast<std::size_t>(t), pb.lo[d] + 1);
  };
  for (int k = b.lo[2]; k <= b.hi[2]; ++k)
    for (int j = b.lo[1]; j <= b.hi[1]; ++j) {
      const std::size_t n0 = grid_.index(b.lo[0], j, k);
      if (d != 0) {
        const int jk = d == 1 ? j : k;
        if (jk - 1 >= pb.lo[d] && jk + 1 <= pb.hi[d]) {
          row(n0, b.hi[0] - b.lo[0] + 1);
        } else {
          for (int i = b.lo[0]; i <= b.hi[0]; ++i) one(n0 + static_cast<std::size_t>(i - b.lo[0]), jk);
        }
        continue;
      }
      const int ilo = std::max(b.lo[0], pb.lo[0] + 1), ihi = std::min(b.hi[0], pb.hi[0] - 1);
      for (int i = b.lo[0]; i <= b.hi[0] && i < ilo; ++i) one(n0 + static_cast<std::size_t>(i - b.lo[0]), i);
      row(n0 + static_cast<std::size_t>(ilo - b.lo[0]), ihi - ilo + 1);
      for (int i = std::max(ihi + 1, b.lo[0]); i <= b.hi[0]; ++i) one(n0 + static_cast<std::size_t>(i - b.lo[0]), i);
    }
}

}  // namespace mpm
