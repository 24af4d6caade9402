#include "mpm/projection.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "mpm/error.h"
#include "mpm/grid_fields.h"
#include "mpm/solver.h"

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

namespace {
// A node is EMPTY (p = 0) when it holds less than this fraction of the fluid mass of a full dual
// cell. The B-spline spreads a point's mass 1.5 cells: with the mass threshold alone the surface
// (p = 0) sits ~1.5 cells outside the fluid. Measured (docs/projection.md): F1 pressure error
// 0.43 / 0.22 (threshold only), 0.22 / 0.11 (0.25), 0.009 / 0.007 (0.5) at 8 / 16 cells, but 0.5
// leaves the column moving (0.07 m/s after 1 s) and the MPM16 dam-break front 0.39 a off; 0.25:
// at rest to 1e-12 m/s, front 0.037 a (apic).
constexpr double kSurfaceFill = 0.25;
// volume correction: the error |phi - 1| it leaves alone. A point lattice moving with a fluid
// samples phi = sum S V / volume with an error of a few per cent that comes and goes with the
// flow; corrected, it moved the surface of a standing wave of 2 % of the depth: amplitude over
// three periods 0.84 of its start with no band, 1.003 with 0.02, 0.953 with 0.05 (0.953 without
// any correction); the sloshing tank's volume after 10 s 1.007 / 1.009 / 1.018 of the start
// (docs/projection.md, "Volume drift and `volume_correction`")
constexpr double kVolumeBand = 0.02;
// Ghost surface: a node is FLUID when level_is_fluid(level) (projection_ops.h, kLevelTie). A fluid
// filled up to a node plane gives its nodes a level of exactly 0 up to round-off; with 0 as the
// bound they flipped between EMPTY and FLUID from step to step (F1 at rest: 2.6e-4 m/s after 1 s).

// The signed distance (units of dx, positive inside) from a node to a plane free surface whose
// fluid gives the node the fill f: the inverse of the fill F(s) = int_{-inf}^{s} N(x) dx of the
// shape function N across the surface (uniform fluid up to the plane at s cells above the node;
// docs/projection.md, "Free surface: energy and stiffness"). With fill - 1/2 as the level instead,
// the ghost surface moved 1 / N(0) = 4/3 (quadratic B-spline) times as far as the water near a
// node and the surface was too stiff: the standing wave ran fast.
double surface_distance(double f, ShapeKind shape) {
  if (shape == ShapeKind::Linear) {  // hat: F = (1 + s)^2 / 2 (s < 0), 1 - (1 - s)^2 / 2
    if (f <= 0.0) return -1.0;
    if (f >= 1.0) return 1.0;
    return f < 0.5 ? std::sqrt(2.0 * f) - 1.0 : 1.0 - std::sqrt(2.0 * (1.0 - f));
  }
  // quadratic B-spline: F = (s + 3/2)^3 / 6 on [-3/2, -1/2], 1 - (3/2 - s)^3 / 6 on [1/2, 3/2],
  // 1/2 + 3 s / 4 - s^3 / 3 between
  if (f <= 0.0) return -1.5;
  if (f >= 1.0) return 1.5;
  if (f <= 1.0 / 6.0) return std::cbrt(6.0 * f) - 1.5;
  if (f >= 5.0 / 6.0) return 1.5 - std::cbrt(6.0 * (1.0 - f));
  double x = (f - 0.5) / 0.75;  // Newton on the middle branch (F' = 3/4 - s^2 >= 1/2 there)
  for (int it = 0; it < 30; ++it) {
    const double r = 0.5 + 0.75 * x - x * x * x / 3.0 - f;
    x -= r / (0.75 - x * x);
    if (std::fabs(r) < 1e-15) break;
  }
  return x;
}
}  // namespace

/* FLUID where the node holds fluid (mass above the threshold and kSurfaceFill of a full cell),
   EMPTY elsewhere (the free surface: p = 0), SOLID padding behind the box walls (NodeLabels::reset). The closed gate is a
   wall at rest: the face between the last node on the fluid side and the next one (a gate through
   a node plane leaves that node on the fluid side, like a box wall through its nodes). */
void Projection::make_labels(const double *p2g, double mmin, const double *theta, const WallGeometry *walls) {
  const bool sparse = grid_.restricted();
  lab_.reset(grid_, sparse ? &work_ : nullptr);
  mesh_ = walls != nullptr;
  if (mesh_) mesh_wall_labels(*walls);
  const double dx = opt_.grid.dx, full = opt_.rho0 * dx * dx * dx;
  if (opt_.surface_ghost) {
    // with a work box: outside it the level is never read (it enters only the faces of FLUID
    // nodes) and fold_mass_ is 0 (retire)
    zero_for_sweep(lab_.level);
    zero_for_sweep(fold_mass_);
    grid_.for_owned([&](int, int, int, std::size_t n) { fold_mass_[n] = p2g[P2gRec::N * n + P2gRec::M]; });
    grid_.forward(fold_mass_.data(), 1);
  }
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] == kSolid) return;
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    const double th = theta ? theta[n] : 1.0;
    const double cut = mesh_ ? frac_[n] : 1.0;
    const double fill = (opt_.surface_ghost ? folded_mass(i, j, k) : m) / (th * full * geo_.volume(i, j, k) * cut);
    if (opt_.surface_ghost) {
      // level set: the fill of a node whose dual cell the surface halves is 1/2 (a symmetric
      // kernel), so fill - 1/2 changes sign at the surface; FLUID where it is positive
      lab_.level[n] = surface_distance(fill, opt_.shape);
      if (m <= mmin || m <= 0.0 || !level_is_fluid(lab_.level[n])) lab_.kind[n] = kEmpty;
    } else if (m <= mmin || m <= 0.0 || fill < kSurfaceFill) {
      lab_.kind[n] = kEmpty;
    }
  });
  if (opt_.surface_ghost) {
    // the EMPTY nodes holding fluid: their velocity enters the surface faces' flux (surface_weight)
    lab_.wet.assign(grid_.size(), 0);
    grid_.for_owned([&](int, int, int, std::size_t n) {
      const double m = p2g[P2gRec::N * n + P2gRec::M];
      if (lab_.kind[n] == kEmpty && m > mmin && m > 0.0) lab_.wet[n] = 1;
    });
  }
  const Gate &g = opt_.gate;
  if (g.active) {
    const GridSpec &gs = opt_.grid;
    const double xi = (g.pos - gs.origin[g.dim]) / gs.dx;
    const long r = std::lround(xi);
    const bool on_plane = std::fabs(xi - r) < 1e-9;
    // lower node of the closed face
    const int lo = on_plane ? static_cast<int>(g.fluid_below ? r : r - 1) : static_cast<int>(std::floor(xi));
    // the plane of those nodes in the patch
    IndexBox plane = grid_.patch();
    plane.lo[g.dim] = std::max(plane.lo[g.dim], lo);
    plane.hi[g.dim] = std::min(plane.hi[g.dim], lo);
    grid_.for_box(plane, [&](int i, int j, int k, std::size_t) { lab_.close_face(grid_, i, j, k, g.dim); });
  }
  lab_.exchange(grid_, comm_);
}

/* The node mass with the mass of its mirror images behind the box walls added (the padding nodes
   the B-spline gives part of the wall-side points' mass): the mass a fluid continued by
   reflection at the walls would give. Without it the nodes next to a wall read a fill 1-3 % low,
   the ghost surface sits lower there and a column at rest starts to circulate (F1: 0.02 m/s after
   1 s, docs/projection.md). Reads fold_mass_ on the owned nodes and halos. */
double Projection::folded_mass(int i, int j, int k) const { return mirror_sum(fold_mass_, i, j, k); }

/* a at node (i, j, k) plus a at its mirror images behind the box walls (reflected at each
   non-periodic grid face, corners too), those of them that lie in the patch: the share a
   B-spline gave to the padding nodes, counted at the node inside. a: owned values and halos. */
double Projection::mirror_sum(const std::vector<double> &a, int i, int j, int k) const {
  const GridSpec &gs = opt_.grid;
  const int idx[3] = {i, j, k};
  int img[3][3], cnt[3];  // per direction: the node's index and its mirror images in the padding
  for (int d = 0; d < 3; ++d) {
    img[d][0] = idx[d];
    cnt[d] = 1;
    if (gs.periodic[d]) continue;
    if (idx[d] > 0 && -idx[d] >= gs.node_lo(d)) img[d][cnt[d]++] = -idx[d];
    if (idx[d] < gs.ncell[d] && 2 * gs.ncell[d] - idx[d] <= gs.node_hi(d)) img[d][cnt[d]++] = 2 * gs.ncell[d] - idx[d];
  }
  double sum = 0.0;
  for (int c = 0; c < cnt[2]; ++c)
    for (int b = 0; b < cnt[1]; ++b)
      for (int q = 0; q < cnt[0]; ++q)
        if (grid_.in_patch(img[0][q], img[1][b], img[2][c])) sum += a[grid_.index(img[0][q], img[1][b], img[2][c])];
  return sum;
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
void Projection::fill_wall_gradient(std::vector<double> &grad) {
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
  std::vector<double> g = grad;
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
        sum += grad[3 * nb[f] + d];
        ++cnt;
      }
      if (cnt) g[3 * n + d] = sum / cnt;
    }
  });
  grad.swap(g);
  grid_.forward(grad.data(), 3);
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

void Projection::mirror_to_padding(const std::vector<double> &a, std::vector<double> &out) const {
  const GridSpec &gs = opt_.grid;
  const IndexBox &pb = grid_.restricted() ? work_ : grid_.patch();
  for (int k = pb.lo[2]; k <= pb.hi[2]; ++k)
    for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
      for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) {
        const std::size_t n = grid_.index(i, j, k);
        if (lab_.kind[n] != kSolid) continue;
        const int q[3] = {gs.mirror(i, 0), gs.mirror(j, 1), gs.mirror(k, 2)};
        if (!grid_.in_patch(q[0], q[1], q[2])) continue;
        const std::size_t m = grid_.index(q[0], q[1], q[2]);
        if (lab_.kind[m] == kSolid) continue;
        for (int e = 0; e < 3; ++e) out[3 * n + e] = a[3 * m + e];
      }
}

void Projection::extend_to_padding(const std::vector<double> &a, std::vector<double> &out, int stride) const {
  // sparse sweeps: the work box only (outside it both hold 0, retire)
  const bool sparse = grid_.restricted();
  const IndexBox &pb = sparse ? work_ : grid_.patch();
  if (sparse)
    grid_.for_box(pb, [&](int, int, int, std::size_t n) {
      for (int e = 0; e < stride; ++e) out[stride * n + e] = a[stride * n + e];
    });
  else
    out = a;
  for (int k = pb.lo[2]; k <= pb.hi[2]; ++k)
    for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
      for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) {
        const std::size_t n = grid_.index(i, j, k);
        if (lab_.kind[n] != kSolid) continue;
        const std::size_t c = wall_node(i, j, k);
        for (int e = 0; e < stride; ++e) out[stride * n + e] = a[stride * c + e];
      }
}

// The nodes of box a that are not in box b, as up to 6 boxes (slabs along z, then y, then x).
static std::vector<IndexBox> box_minus(const IndexBox &a, const IndexBox &b) {
  std::vector<IndexBox> out;
  if (a.empty()) return out;
  const IndexBox c = a.cut(b);
  if (c.empty()) return {a};
  IndexBox rest = a;
  for (int d = 2; d >= 0; --d) {
    IndexBox lo = rest, hi = rest;
    lo.hi[d] = c.lo[d] - 1;
    hi.lo[d] = c.hi[d] + 1;
    if (!lo.empty()) out.push_back(lo);
    if (!hi.empty()) out.push_back(hi);
    rest.lo[d] = c.lo[d];
    rest.hi[d] = c.hi[d];
  }
  return out;
}

void Projection::retire(const IndexBox &work) {
  if (!have_prev_) return;
  const std::pair<std::vector<double> *, int> arrays[] = {
      {&u_, 3}, {&grad_, 3}, {&grad_ext_, 3}, {&rhs_, 1}, {&p_, 1}, {&p_ext_, 1},
      {&acc_, 3}, {&p_acc_, 1}, {&p_acc_ext_, 1}, {&grad_acc_, 3}, {&grad_acc_ext_, 3},
      {&fold_mass_, 1}, {&gk_, 1}, {&pk_, 1}};
  const std::vector<IndexBox> gone = box_minus(work_prev_.cut(grid_.patch()), work);
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

/* Ghost-fluid surface: the EMPTY nodes that hold fluid mass (the B-spline spreads the points'
   mass up to 1.5 cells beyond the surface) need a pressure gradient for their velocity and a
   pressure for the points' interpolation. A node next to a FLUID one has the one-sided gradient of
   the surface face (pressure_gradient); the next layer takes the mean gradient of its neighbours
   that have one, layer by layer (two layers reach 1.5 cells). The pressure of such a node is the
   linear continuation p_k + (x_n - x_k) . grad_n from those neighbours k (for the first layer the
   ghost value p_k (1 - 1 / s_f)): a hydrostatic column then stays at rest and its points read the
   hydrostatic pressure at their height, also in the top layer. The solve's EMPTY values (0) are
   not changed: p holds the extrapolated values only after the solve. with_p false: the gradient
   alone (the grains' gradient of the acceleration pressure, whose p the points read unextended). */
void Projection::extrapolate_above_surface(const double *p2g, double mmin, std::vector<double> &p,
                                           std::vector<double> &grad, bool with_p) {
  const double dx = opt_.grid.dx;
  // per node: 1 if its gradient (gk) / pressure (pk) is known: FLUID nodes, and EMPTY nodes next
  // to a FLUID one for the gradient (pressure_gradient's one-sided surface face)
  std::vector<double> &gk = gk_, &pk = pk_;
  zero_for_sweep(gk);
  zero_for_sweep(pk);
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] == kFluid) {
      gk[n] = pk[n] = 1.0;
      return;
    }
    if (lab_.kind[n] != kEmpty) return;
    for (int d = 0; d < 3; ++d)
      for (int side = -1; side <= 1; side += 2) {
        std::size_t m;
        if (open_face(grid_, lab_, i, j, k, d, side, &m) && lab_.kind[m] == kFluid) gk[n] = 1.0;
      }
  });
  // An EMPTY node next to the fluid has from pressure_gradient only the components along its faces
  // to FLUID nodes: above a level surface the vertical one, and 0 along the surface, so the points
  // near the surface read an unaccelerated velocity along it from the nodes above them and the
  // standing wave ran slow (20 cells across: 0.962 of its frequency). The other components are
  // the mean of the FLUID neighbours' (docs/theory/projection.md, "Free surface: the gradient
  // along the surface").
  {
  std::vector<std::pair<std::size_t, int>> fill;
  std::vector<double> val;
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] != kEmpty || gk[n] == 0.0) return;
    for (int d = 0; d < 3; ++d) {
      bool along = false;
      for (int side = -1; side <= 1; side += 2) {
        std::size_t m;
        if (open_face(grid_, lab_, i, j, k, d, side, &m) && lab_.kind[m] == kFluid) along = true;
      }
      if (along) continue;
      double sum = 0.0;
      int cnt = 0;
      for (int e = 0; e < 3; ++e)
        for (int side = -1; side <= 1; side += 2) {
          std::size_t m;
          if (open_face(grid_, lab_, i, j, k, e, side, &m) && lab_.kind[m] == kFluid) {
            sum += grad[3 * m + d];
            ++cnt;
          }
        }
      if (cnt > 0) {
        fill.emplace_back(n, d);
        val.push_back(sum / cnt);
      }
    }
  });
  for (std::size_t q = 0; q < fill.size(); ++q) grad[3 * fill[q].first + fill[q].second] = val[q];
  }
  grid_.forward(gk.data(), 1);
  grid_.forward(pk.data(), 1);
  grid_.forward(grad.data(), 3);
  // the nodes that become known in a pass are marked after it (the pass reads the flags before it)
  std::vector<std::size_t> gnew, pnew;
  for (int pass = 0; pass < 3; ++pass) {
    gnew.clear();
    pnew.clear();
    grid_.for_owned([&](int i, int j, int k, std::size_t n) {
      if (lab_.kind[n] != kEmpty) return;
      const double m = p2g[P2gRec::N * n + P2gRec::M];
      if (!(m > mmin && m > 0.0)) return;
      double g[3] = {0, 0, 0}, psum = 0.0;
      int ng = 0, np = 0;
      for (int d = 0; d < 3; ++d)
        for (int side = -1; side <= 1; side += 2) {
          std::size_t q;
          if (!open_face(grid_, lab_, i, j, k, d, side, &q)) continue;
          if (gk[q] != 0.0) {
            for (int e = 0; e < 3; ++e) g[e] += grad[3 * q + e];
            ++ng;
          }
          // x_n - x_q = -side dx e_d
          if (with_p && gk[n] != 0.0 && pk[q] != 0.0) {
            psum += p[q] - side * dx * grad[3 * n + d];
            ++np;
          }
        }
      if (gk[n] == 0.0 && ng > 0) {
        for (int e = 0; e < 3; ++e) grad[3 * n + e] = g[e] / ng;
        gnew.push_back(n);
      }
      if (pk[n] == 0.0 && np > 0) {
        p[n] = psum / np;
        pnew.push_back(n);
      }
    });
    for (const std::size_t n : gnew) gk[n] = 1.0;
    for (const std::size_t n : pnew) pk[n] = 1.0;
    grid_.forward(gk.data(), 1);
    grid_.forward(pk.data(), 1);
    grid_.forward(grad.data(), 3);
    if (with_p) grid_.forward(p.data(), 1);
  }
}

void Projection::form_gradient(std::vector<double> &p, std::vector<double> &grad, const double *p2g, double mmin,
                               bool above_surface, bool with_p) {
  pressure_gradient(grid_, lab_, p.data(), grad.data(), theta_now_);
  grid_.forward(grad.data(), 3);
  if (above_surface && opt_.surface_ghost) extrapolate_above_surface(p2g, mmin, p, grad, with_p);
  if (mesh_) fill_wall_gradient(grad);
}

PressureResult Projection::solve_rhs(double *p, long step, const char *subject) {
  try {
    const double t0 = MPI_Wtime();
    const PressureResult r = solver_->solve(lab_, beta_.data(), rhs_.data(), p);
    solver_seconds_ += MPI_Wtime() - t0;
    ++solves_;  // every solve (the acceleration pressure's too), as the time
    iterations_summed_ += r.iterations;
    return r;
  } catch (const PressureSolveError &e) {
    std::ostringstream os;
    os << "Fix mpm/fluid: " << subject << " did not converge at step " << step << ": " << e.iterations
       << " PCG iterations (keyword 'max_iterations' " << opt_.pressure_max_iterations << "), relative residual "
       << e.residual << " (keyword 'tolerance' " << opt_.pressure_tolerance << ")";
    if (std::isnan(e.residual)) os << "; " << e.what();  // hypre failed (INF or NaN), not a slow convergence
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
  make_labels(p2g, mmin, theta, bc.walls());
  const double *theta_prev = theta && have_theta_last_ ? theta_last_.data() : nullptr;
  // u* as it is; every wall condition comes after the projection: the wall's reaction is the
  // pressure, and a wall node's velocity zeroed before it (normal or, no-slip, tangential) would
  // be moved again by the correction (measured: the F1 column at rest, docs/projection.md)
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    double *v = vel + VelRec::N * n + VelRec::V_NEW;
    for (int d = 0; d < 3; ++d) u_[3 * n + d] = v[d];
  });
  grid_.forward(u_.data(), 3);
  const double *th = theta ? theta : theta_.data();
  theta_now_ = theta;
  if (theta)
    for (std::size_t n = 0; n < beta_.size(); ++n) beta_[n] = theta[n] / opt_.rho0;
  pressure_rhs(grid_, lab_, geo_, u_.data(), th, theta_prev, h, rhs_.data());
  last_ = solve_rhs(p_.data(), step, "the pressure projection");
  // for the points and grains: the padding nodes behind the box walls carry the pressure (and
  // gradient) of the wall node in front (the solve holds them at 0; interpolated as they are,
  // they would lower the pressure of the points next to a wall by half a cell's hydrostatic step)
  // (first the nodes behind mesh walls, which the padding nodes behind them then copy)
  form_gradient(p_, grad_, p2g, mmin, true, true);
  extend_for_points(p_, grad_, p2g, mmin, p_ext_, &grad_ext_);
  if (theta && !mesh_) mirror_to_padding(grad_, grad_ext_);
  if (theta) {
    theta_last_.assign(theta, theta + grid_.size());
    have_theta_last_ = true;
  }
  correct_velocity(grid_, lab_, grad_.data(), inv_rho_.data(), h, u_.data());
  grid_.forward(u_.data(), 3);
  if (pvol && opt_.volume_correction > 0.0 && vc_time > 0.0)
    volume_drift(pvol, theta, h, std::min(opt_.volume_correction * vc_time, 1.0), step);
  else
    drift_.clear();
  if (acceleration_on()) acceleration_pressure(vel, th, h, p2g, mmin, step);
  average_pressure(h);
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
      // it is, it would let the points next to a free-slip wall fall through the rest state. An
      // EMPTY wall node's velocity (extrapolated from the fluid) counts too: with 0 there the
      // points along the back wall of the dam break hung back (wall height 0.15 a off at MPM24).
      if (!(m > mmin && m > 0.0)) return;
      const std::size_t c = wall_node(i, j, k);
      const bool wall_fluid = lab_.kind[c] != kSolid;
      // with grains (box walls only): the components along the walls (periodic or tangential)
      // keep the node's own u* corrected by the pressure gradient of its mirror node inside (the
      // node its share of the grains' volume is folded to, and whose gradient the grains read
      // here: mirror_to_padding), a pressure force on its mass and no other change of momentum.
      // Copying the wall node's velocity changed the momentum of this mass by m (u_wall - u*),
      // among others the drag the grains near the wall gave it: with a constant force on the
      // grains of a box periodic in x and y, cells of 3 grain diameters, 0.03 s, the x momentum of
      // fluid and grains 3.1 % above the impulse, 0.19 % without the copy (docs/projection.md,
      // "Momentum of grains and fluid")
      const int q[3] = {opt_.grid.mirror(i, 0), opt_.grid.mirror(j, 1), opt_.grid.mirror(k, 2)};
      const int idx[3] = {i, j, k};
      double ut[3];
      std::size_t mq = c;
      if (grid_.in_patch(q[0], q[1], q[2])) mq = grid_.index(q[0], q[1], q[2]);
      const bool mq_fluid = lab_.kind[mq] != kSolid;
      for (int d = 0; d < 3; ++d) ut[d] = mq_fluid ? v[d] - h * inv_rho_[mq] * grad_[3 * mq + d] : 0.0;
      for (int d = 0; d < 3; ++d) v[d] = wall_fluid ? u_[3 * c + d] : 0.0;
      if (theta && !mesh_)
        for (int d = 0; d < 3; ++d)
          if (q[d] == idx[d]) v[d] = ut[d];
      bc.apply(v, i, j, k, h);
      mirror_normal(v, i, j, k, p2g, mmin);
      return;
    }
    if (!(m > mmin && m > 0.0)) return;  // no fluid: velocity stays 0
    for (int d = 0; d < 3; ++d) v[d] = u_[3 * n + d];
    bc.apply(v, i, j, k, h);
  });
}

/* Padding node (i, j, k) behind the box walls: along each direction d in which it lies behind a
   wall, its velocity component d becomes minus that of its mirror node inside (the node reflected at
   the wall: index -i, or 2 ncell - i; all out-of-range indices reflected), 0 if the mirror node
   holds no fluid. The wall condition (bc.apply) had set it to 0: a point next to the wall then read
   the quadratic B-spline's share of the node above it (1/8 of its velocity on the wall itself) and
   crossed the wall, to be put back there (C3 with projection: f_fluid[8] 79,040 at Grid20 and
   6.4e5 at Grid48 by 0.2 s). With the odd reflection the interpolated normal velocity is 0 on the
   wall and linear near it: Grid20 0 put back, fronts within 3 mm (docs/tank.md). */
void Projection::mirror_normal(double *v, int i, int j, int k, const double *p2g, double mmin) const {
  const GridSpec &gs = opt_.grid;
  const int q[3] = {gs.mirror(i, 0), gs.mirror(j, 1), gs.mirror(k, 2)};
  const bool out[3] = {q[0] != i, q[1] != j, q[2] != k};
  if (!grid_.in_patch(q[0], q[1], q[2])) return;
  const std::size_t mn = grid_.index(q[0], q[1], q[2]);
  const double mm = p2g[P2gRec::N * mn + P2gRec::M];
  const bool fluid = lab_.kind[mn] != kSolid && mm > mmin && mm > 0.0;
  for (int d = 0; d < 3; ++d)
    if (out[d]) v[d] = fluid ? -u_[3 * mn + d] : 0.0;
}

/* Volume correction (keyword volume_correction k, docs/projection.md "Volume drift"). The
   points hold their volume V = m / (theta rho0), but the approximate projection makes the nodal
   velocities divergence-free only up to its approximation error, so the point cloud drifts: where
   the flow converges the points crowd, elsewhere they open gaps (F2 dam break, MPM16 apic, 2 s:
   3 to 5 % of the held volume overlapping, the fluid's volume on the grid 3.4 % below the held
   one). The points' volume on the grid, phi_n = sum_p S_np V_p / (dx^3 volume(n)), is 1 where
   they fill the space evenly (exactly, at rest, for a regular fill); the shares the B-spline gives
   to the padding nodes behind a box wall count at their mirror node inside (as the coupling folds
   the grains' volume). The source of the correction's own solve (volume_drift) removes the
   share a = min(k M h, 1) of the error e = phi - 1 (beyond kVolumeBand) on every M-th step
   (volume_correction_every): the drift w it gives has
       D(w) = volume(n) theta_n a e_n / h,
   i.e. rhs_n -= volume(n) theta_n a e_n / h^2: crowded points (e > 0) are pushed apart, and gaps
   (e < 0) drawn together, but the latter only where no EMPTY node lies within two nodes
   (deep_inside): under the free surface phi falls from 1 to 0 over 1.5 cells and is no error.
   Measured: correcting compression alone removed it better but opened gaps, the fluid's volume
   on the grid growing by 2-8 % (docs/projection.md). The density-error source of the pressure
   equation of Kugelstadt, Longva, Thuerey & Bender (2021), "Implicit density projection for
   volume conserving liquids", IEEE TVCG 27(4), applied as they do to the positions, with the
   projection's operator. */
void Projection::add_volume_correction(const double *pvol, const double *theta, double h, double a) {
  const GridSpec &gs = opt_.grid;
  vol_.assign(pvol, pvol + grid_.size());
  grid_.forward(vol_.data(), 1);  // the padding nodes' shares, wherever they are owned
  const double dx = gs.dx, dx3 = dx * dx * dx;
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] != kFluid) return;
    const double sum = mirror_sum(vol_, i, j, k);
    const double cv = geo_.volume(i, j, k);
    // the part of the error beyond the band kVolumeBand: what the points' own sampling of a
    // moving fluid gives is left alone
    double e = sum / (dx3 * cv) - 1.0;
    e = e > kVolumeBand ? e - kVolumeBand : (e < -kVolumeBand ? e + kVolumeBand : 0.0);
    if (e < 0.0 && !deep_inside(i, j, k)) return;  // a partly filled node under the surface
    const double th = theta ? theta[n] : 1.0;
    rhs_[n] -= cv * th * a * e / (h * h);
  });
}

/* The volume correction as a drift of the points' positions (Kugelstadt et al. 2021 correct
   the positions too): the solve of the projection's operator with the volume error alone as its
   source gives the potential q, and w = -(dt / rho) grad q is the velocity whose divergence
   removes the fraction a of the error this step. The points move by dt w on top of the fluid's
   velocity; w never enters their velocity, so the correction neither adds momentum nor energy
   (as a source in the velocity's own solve it entered the points' velocity, which FLIP keeps;
   docs/projection.md "Volume drift and `volume_correction`"). Zero first guess:
   the drift of a step is a function of that step's state only (restart, np 2 = np 1). */
void Projection::volume_drift(const double *pvol, const double *theta, double h, double share, long step) {
  const std::size_t n = grid_.size();
  rhs_.assign(n, 0.0);
  add_volume_correction(pvol, theta, h, share);
  q_.assign(n, 0.0);
  grad_q_.assign(3 * n, 0.0);
  drift_.assign(3 * n, 0.0);
  solve_rhs(q_.data(), step, "the volume correction's solve");
  grid_.forward(q_.data(), 1);
  pressure_gradient(grid_, lab_, q_.data(), grad_q_.data(), theta_now_);
  grid_.for_owned([&](int, int, int, std::size_t m) {
    if (lab_.kind[m] == kSolid) return;
    for (int d = 0; d < 3; ++d) drift_[3 * m + d] = -h * inv_rho_[m] * grad_q_[3 * m + d];
  });
  grid_.forward(drift_.data(), 3);
}

// no EMPTY node and no node behind a mesh wall within two nodes along each direction: phi = 1
// there for a regular fill (the surface, where phi falls from 1 to 0 over 1.5 cells, is at least
// 1.5 cells away; beside a mesh wall the B-spline's share behind the triangles holds no points and
// has no mirror image, so phi < 1 at rest there: counted as a gap, it moved columns at rest beside
// vertical / 30 / 60 degree walls at 8.4e-3 / 1.0e-2 / 6.0e-2 m/s after 1 s with k = 10; with
// these nodes left out 1.9e-12 / 3.5e-12 / 7.0e-12 m/s, test mpm_case.projection_mesh_rest)
bool Projection::deep_inside(int i, int j, int k) const {
  for (int c = -2; c <= 2; ++c)
    for (int b = -2; b <= 2; ++b)
      for (int a = -2; a <= 2; ++a)
        if (grid_.in_patch(i + a, j + b, k + c)) {
          const std::size_t q = grid_.index(i + a, j + b, k + c);
          if (lab_.kind[q] == kEmpty || behind_mesh(i + a, j + b, k + c, q)) return false;
        }
  return true;
}

/* ---------------------------------------------------------------------- state of the last solve */

/* pressure_output acceleration (docs/projection.md, "The pressure the points carry"). The
   projection's p is the Lagrange multiplier that makes this step's velocity divergence-free: it
   removes whatever divergence the step's u* holds, the transfer's as well (FLIP and APIC do not
   give back on the grid the divergence-free velocity they took from it), in one step h, so that
   part of it is of order rho |du| dx / h and grows without bound as h shrinks (C3, F2 dam break,
   docs/tank.md). The pressure of the incompressible Navier-Stokes equations is instead fixed by
   the velocity field and the forces alone: with Du/Dt = a_f - grad p / rho and div u = 0,
       div(beta grad p) = div(theta (a_f - (u . grad) u)),   no normal acceleration at walls,
   p = 0 at the free surface. Here u is the projected velocity, a_f the grid forces per mass of the
   step (gravity, viscosity, drag, damping: (u* - u_old) / h), (u . grad) u by central differences
   between FLUID nodes (one-sided next to a non-FLUID node). The same operator and labels as the
   projection: at rest it is the projection's hydrostatic pressure. Not in it: d(theta)/dt of moving
   grains, the acceleration of walls. */
void Projection::acceleration_pressure(const double *vel, const double *theta, double h, const double *p2g,
                                      double mmin, long step) {
  const double inv2dx = 0.5 / opt_.grid.dx, invdx = 1.0 / opt_.grid.dx;
  const long s[3] = {1, static_cast<long>(grid_.stride_y()), static_cast<long>(grid_.stride_z())};
  grid_.for_owned([&](int, int, int, std::size_t n) {
    double *a = &acc_[3 * n];
    if (lab_.kind[n] != kFluid) {
      a[0] = a[1] = a[2] = 0.0;
      return;
    }
    const double *rec = vel + VelRec::N * n;
    // V_NEW still holds u*: the forces of the step per mass
    for (int d = 0; d < 3; ++d) a[d] = (rec[VelRec::V_NEW + d] - rec[VelRec::V_OLD + d]) / h;
    const double *u = &u_[3 * n];
    for (int e = 0; e < 3; ++e) {  // - u_e d/dx_e u
      const std::size_t lo = n - s[e], hi = n + s[e];
      const bool fl = lab_.kind[lo] == kFluid, fh = lab_.kind[hi] == kFluid;
      if (!fl && !fh) continue;
      for (int d = 0; d < 3; ++d) {
        const double du = fl && fh ? (u_[3 * hi + d] - u_[3 * lo + d]) * inv2dx
                                   : fh ? (u_[3 * hi + d] - u[d]) * invdx : (u[d] - u_[3 * lo + d]) * invdx;
        a[d] -= u[e] * du;
      }
    }
  });
  grid_.forward(acc_.data(), 3);
  acceleration_rhs(grid_, lab_, geo_, acc_.data(), theta, rhs_.data());
  solve_rhs(p_acc_.data(), step, "the solve for the pressure of the acceleration (keyword 'pressure_output' or 'grain_pressure' acceleration)");
  // behind mesh walls extrapolated linearly with its own gradient, as the multiplier (at rest
  // beside a 30 degree wall one pressure per row of points to 2e-11 rho g dx; with the mean of the
  // neighbours behind the wall instead, 0.27 rho g dx)
  // grain_pressure acceleration: the grains feel its gradient, formed as the multiplier's (the
  // surface layers of the ghost-fluid surface included)
  const bool grains = opt_.grain_pressure_acceleration;
  if (mesh_ || grains) form_gradient(p_acc_, grad_acc_, p2g, mmin, grains, false);
  extend_for_points(p_acc_, grad_acc_, p2g, mmin, p_acc_ext_, grains ? &grad_acc_ext_ : nullptr);
  if (grains && theta && !mesh_) mirror_to_padding(grad_acc_, grad_acc_ext_);
}

/* The pressure a sensor of finite response time reads (keyword pressure_average tau). Under the
   projection an impact or a transfer event that must change the velocity within one fluid step h
   gives a pressure of order rho |du| dx / h for that step: the pressure impulse (its integral over
   time) converges as h shrinks, the single-step peak does not (docs/tank.md). The exponential
   average pa += (1 - exp(-h / tau)) (p - pa) responds to an impulse I with I / tau, independent of
   h, and to a steady pressure with that pressure. Nodes hold a fixed place, as a wall sensor. */
void Projection::average_pressure(double h) {
  const double tau = opt_.pressure_average;
  if (tau > 0.0) {
    const double a = have_avg_ ? -std::expm1(-h / tau) : 1.0;  // the first solve starts the average
    const std::vector<double> &p = opt_.pressure_acceleration ? p_acc_ : p_;
    // every owned node, work box or not: the average decays where the fluid has gone
    grid_.for_owned_all([&](int, int, int, std::size_t n) { p_avg_[n] += a * (p[n] - p_avg_[n]); });
    have_avg_ = true;
  }
  largest_pressure();
}

void Projection::largest_pressure() {
  const std::vector<double> &a = have_avg_ ? p_avg_ : opt_.pressure_acceleration ? p_acc_ : p_;
  double mx = -HUGE_VAL;
  grid_.for_owned_all([&](int, int, int, std::size_t n) { mx = std::max(mx, a[n]); });
  p_avg_max_ = mx;
}

void Projection::save(ProjectionState &s) const {
  s.valid = true;
  s.box = grid_.owned();
  s.have_theta_last = have_theta_last_;
  s.iterations = last_.iterations;
  s.residual = last_.relative_residual;
  const std::size_t nb = static_cast<std::size_t>(s.box.count());
  s.p.resize(nb);
  s.grad.resize(3 * nb);
  s.theta_last.resize(have_theta_last_ ? nb : 0);
  s.have_avg = have_avg_;
  s.p_avg.resize(have_avg_ ? nb : 0);
  const bool acc = acceleration_on();
  s.have_acc = acc;
  s.p_acc.resize(acc ? nb : 0);
  // the gradient the grains feel at the next step (grain_pressure: of the multiplier or of the
  // acceleration pressure)
  const std::vector<double> &grad = opt_.grain_pressure_acceleration ? grad_acc_ : grad_;
  std::size_t q = 0;
  grid_.for_owned([&](int, int, int, std::size_t n) {  // k, j, i with i fastest: the box's order
    s.p[q] = p_[n];
    for (int d = 0; d < 3; ++d) s.grad[3 * q + d] = grad[3 * n + d];
    if (have_theta_last_) s.theta_last[q] = theta_last_[n];
    if (have_avg_) s.p_avg[q] = p_avg_[n];
    if (acc) s.p_acc[q] = p_acc_[n];
    ++q;
  });
}

bool Projection::load(const ProjectionState &s) {
  const IndexBox &b = s.box;
  int ok = s.valid ? 1 : 0, all = 0;
  const IndexBox &ob = grid_.owned();
  if (!ob.empty())
    for (int d = 0; d < 3; ++d)
      if (ob.lo[d] < b.lo[d] || ob.hi[d] > b.hi[d]) ok = 0;
  MPI_Allreduce(&ok, &all, 1, MPI_INT, MPI_MIN, comm_);
  if (!all) return false;
  const long ex = b.hi[0] - b.lo[0] + 1, ey = b.hi[1] - b.lo[1] + 1;
  // the place of node (i, j, k) in the state's box
  auto at = [&](int i, int j, int k) {
    return static_cast<std::size_t>(((k - b.lo[2]) * ey + (j - b.lo[1])) * ex + (i - b.lo[0]));
  };
  const bool grains_acc = opt_.grain_pressure_acceleration;
  std::vector<double> &grad = grains_acc ? grad_acc_ : grad_;  // the grains' (save)
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    const std::size_t q = at(i, j, k);
    p_[n] = s.p[q];
    for (int d = 0; d < 3; ++d) grad[3 * n + d] = s.grad[3 * q + d];
  });
  grid_.forward(p_.data(), 1);
  grid_.forward(grad.data(), 3);
  have_theta_last_ = s.have_theta_last;
  if (have_theta_last_) {
    theta_last_.assign(grid_.size(), 1.0);
    grid_.for_owned([&](int i, int j, int k, std::size_t n) {
      theta_last_[n] = s.theta_last[at(i, j, k)];
    });
    grid_.forward(theta_last_.data(), 1);
  }
  // the averaged pressure goes on only if this run averages too (else it starts at the next solve)
  have_avg_ = s.have_avg && opt_.pressure_average > 0.0;
  if (have_avg_) grid_.for_owned([&](int i, int j, int k, std::size_t n) { p_avg_[n] = s.p_avg[at(i, j, k)]; });
  const bool acc = acceleration_on();
  if (s.have_acc && acc) {
    grid_.for_owned([&](int i, int j, int k, std::size_t n) { p_acc_[n] = s.p_acc[at(i, j, k)]; });
    grid_.forward(p_acc_.data(), 1);
  }
  largest_pressure();
  last_.iterations = s.iterations;
  last_.relative_residual = s.residual;
  // the padding nodes' copies, as after a solve (their labels are SOLID from the grid alone)
  lab_.reset(grid_);
  extend_to_padding(p_, p_ext_, 1);
  extend_to_padding(grad_, grad_ext_, 3);
  if (acc) extend_to_padding(p_acc_, p_acc_ext_, 1);
  if (grains_acc) extend_to_padding(grad_acc_, grad_acc_ext_, 3);
  if (have_theta_last_ && !mesh_) {  // with grains: as after a solve (project, acceleration_pressure)
    mirror_to_padding(grad_, grad_ext_);
    if (grains_acc) mirror_to_padding(grad_acc_, grad_acc_ext_);
  }
  work_prev_ = grid_.patch();  // values anywhere: a sparse step retires all outside its work box
  have_prev_ = true;
  return true;
}

namespace {
constexpr double kStateVersion = 2.0;  // layout of ProjectionState::pack (1: without p_avg)
}

void ProjectionState::pack(std::vector<double> &out) const {
  out.push_back(valid ? kStateVersion : 0.0);
  if (!valid) return;
  for (int d = 0; d < 3; ++d) out.push_back(box.lo[d]);
  for (int d = 0; d < 3; ++d) out.push_back(box.hi[d]);
  out.push_back(have_theta_last ? 1.0 : 0.0);
  out.push_back(iterations);
  out.push_back(residual);
  out.insert(out.end(), p.begin(), p.end());
  out.insert(out.end(), grad.begin(), grad.end());
  out.insert(out.end(), theta_last.begin(), theta_last.end());
  out.push_back(have_avg ? 1.0 : 0.0);
  out.insert(out.end(), p_avg.begin(), p_avg.end());
  out.push_back(have_acc ? 1.0 : 0.0);
  out.insert(out.end(), p_acc.begin(), p_acc.end());
}

std::size_t ProjectionState::unpack(const double *in) {
  *this = ProjectionState();
  if (in[0] == 0.0) return 1;
  if (in[0] != kStateVersion && in[0] != 1.0) {
    std::ostringstream os;
    os << "Fix mpm/fluid: the restart file holds a pressure-projection state of layout " << in[0]
       << "; this build reads layout " << kStateVersion;
    throw Error(os.str());
  }
  std::size_t m = 1;
  for (int d = 0; d < 3; ++d) box.lo[d] = static_cast<int>(in[m++]);
  for (int d = 0; d < 3; ++d) box.hi[d] = static_cast<int>(in[m++]);
  have_theta_last = in[m++] != 0.0;
  iterations = static_cast<int>(in[m++]);
  residual = in[m++];
  const std::size_t nb = static_cast<std::size_t>(box.count());
  p.assign(in + m, in + m + nb);
  m += nb;
  grad.assign(in + m, in + m + 3 * nb);
  m += 3 * nb;
  if (have_theta_last) {
    theta_last.assign(in + m, in + m + nb);
    m += nb;
  }
  if (in[0] >= 2.0) {
    have_avg = in[m++] != 0.0;
    if (have_avg) {
      p_avg.assign(in + m, in + m + nb);
      m += nb;
    }
    have_acc = in[m++] != 0.0;
    if (have_acc) {
      p_acc.assign(in + m, in + m + nb);
      m += nb;
    }
  }
  valid = true;
  return m;
}

ProjectionState gather_global(const ProjectionState &local, const GridSpec &spec, MPI_Comm comm) {
  int nprocs = 1;
  MPI_Comm_size(comm, &nprocs);
  int v = local.valid ? 1 : 0, allv = 0;
  MPI_Allreduce(&v, &allv, 1, MPI_INT, MPI_MIN, comm);
  ProjectionState g;
  if (!allv) return g;
  g.valid = true;
  for (int d = 0; d < 3; ++d) {
    g.box.lo[d] = spec.node_lo(d);
    g.box.hi[d] = spec.node_hi(d);
  }
  // the optional fields every rank holds
  const int mine_has[3] = {local.have_theta_last, local.have_avg, local.have_acc};
  int all_have[3];
  MPI_Allreduce(mine_has, all_have, 3, MPI_INT, MPI_MIN, comm);
  g.have_theta_last = all_have[0] != 0;
  g.have_avg = all_have[1] != 0;
  g.have_acc = all_have[2] != 0;
  g.iterations = local.iterations;
  g.residual = local.residual;
  // every rank's box and values (p, grad, theta, p_avg, p_acc per node), copied into place on every rank
  const int per = 4 + (g.have_theta_last ? 1 : 0) + (g.have_avg ? 1 : 0) + (g.have_acc ? 1 : 0);
  std::vector<double> mine;
  const std::size_t nb = static_cast<std::size_t>(local.box.count());
  mine.reserve(per * nb);
  for (std::size_t q = 0; q < nb; ++q) {
    mine.push_back(local.p[q]);
    for (int d = 0; d < 3; ++d) mine.push_back(local.grad[3 * q + d]);
    if (g.have_theta_last) mine.push_back(local.theta_last[q]);
    if (g.have_avg) mine.push_back(local.p_avg[q]);
    if (g.have_acc) mine.push_back(local.p_acc[q]);
  }
  std::vector<int> boxes(6 * nprocs), counts(nprocs), displs(nprocs);
  const int mybox[6] = {local.box.lo[0], local.box.lo[1], local.box.lo[2], local.box.hi[0], local.box.hi[1], local.box.hi[2]};
  MPI_Allgather(mybox, 6, MPI_INT, boxes.data(), 6, MPI_INT, comm);
  int mycount = static_cast<int>(mine.size());
  MPI_Allgather(&mycount, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  long total = 0;
  for (int r = 0; r < nprocs; ++r) {
    displs[r] = static_cast<int>(total);
    total += counts[r];
  }
  std::vector<double> all(static_cast<std::size_t>(total));
  MPI_Allgatherv(mine.data(), mycount, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, comm);
  const std::size_t ng = static_cast<std::size_t>(g.box.count());
  g.p.assign(ng, 0.0);
  g.grad.assign(3 * ng, 0.0);
  g.theta_last.assign(g.have_theta_last ? ng : 0, 1.0);
  g.p_avg.assign(g.have_avg ? ng : 0, 0.0);
  g.p_acc.assign(g.have_acc ? ng : 0, 0.0);
  const long gx = g.box.hi[0] - g.box.lo[0] + 1, gy = g.box.hi[1] - g.box.lo[1] + 1;
  for (int r = 0; r < nprocs; ++r) {
    const int *b = &boxes[6 * r];
    std::size_t q = static_cast<std::size_t>(displs[r]);
    for (int k = b[2]; k <= b[5]; ++k)
      for (int j = b[1]; j <= b[4]; ++j)
        for (int i = b[0]; i <= b[3]; ++i) {
          const std::size_t n = static_cast<std::size_t>(((k - g.box.lo[2]) * gy + (j - g.box.lo[1])) * gx + (i - g.box.lo[0]));
          g.p[n] = all[q++];
          for (int d = 0; d < 3; ++d) g.grad[3 * n + d] = all[q++];
          if (g.have_theta_last) g.theta_last[n] = all[q++];
          if (g.have_avg) g.p_avg[n] = all[q++];
          if (g.have_acc) g.p_acc[n] = all[q++];
        }
  }
  return g;
}

}  // namespace mpm
