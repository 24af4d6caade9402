// The pressure projection's free surface and walls (docs/theory/projection.md): the node labels
// from the node mass (the ghost surface's level), the mesh walls' closed faces and the nodes
// behind them, the padding nodes behind the box walls, and the pressure and its gradient continued
// above the surface for the points.
#include "mpm/projection.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "mpm/error.h"
#include "mpm/grid_fields.h"

namespace mpm {

namespace {
// A node is EMPTY (p = 0) when it holds less than this fraction of the fluid mass of a full dual
// cell. The B-spline spreads a point's mass 1.5 cells: with the mass threshold alone the surface
// (p = 0) sits ~1.5 cells outside the fluid. Measured (docs/theory/projection.md): F1 pressure error
// 0.43 / 0.22 (threshold only), 0.22 / 0.11 (0.25), 0.009 / 0.007 (0.5) at 8 / 16 cells, but 0.5
// leaves the column moving (0.07 m/s after 1 s) and the MPM16 dam-break front 0.39 a off; 0.25:
// at rest to 1e-12 m/s, front 0.037 a (apic).
constexpr double kSurfaceFill = 0.25;
// The film's front (Projection::mark_front): a FLUID node holding less than this fraction of a full
// cell next to a dry EMPTY node (docs/theory/projection.md, "The step size").
constexpr double kFrontFill = 0.5;
// Ghost surface: a node is FLUID when level_is_fluid(level) (projection_ops.h, kLevelTie). A fluid
// filled up to a node plane gives its nodes a level of exactly 0 up to round-off; with 0 as the
// bound they flipped between EMPTY and FLUID from step to step (F1 at rest: 2.6e-4 m/s after 1 s).

}  // namespace

// (projection_ops.h)
double lattice_fill(double s, ShapeKind shape, int np, double *slope) {
  const double r = shape == ShapeKind::Linear ? 1.0 : 1.5, h = 1.0 / np;
  double g = 0.0, dg = 0.0;
  for (int j = 0;; ++j) {
    const double x = s - (j + 0.5) * h, a = std::fabs(x);  // the point's offset from the node
    if (x <= -r) break;
    if (a >= r) continue;
    const double sg = x < 0.0 ? -1.0 : 1.0;
    if (shape == ShapeKind::Linear) {
      g += 1.0 - a;
      dg -= sg;
    } else if (a < 0.5) {
      g += 0.75 - a * a;
      dg -= 2.0 * x;
    } else {
      g += 0.5 * (1.5 - a) * (1.5 - a);
      dg -= sg * (1.5 - a);
    }
  }
  if (slope) *slope = dg * h;
  return g * h;
}

double continuum_fill(double s, ShapeKind shape) {
  if (s < 0.0) return 1.0 - continuum_fill(-s, shape);
  if (shape == ShapeKind::Linear) return s >= 1.0 ? 1.0 : 1.0 - 0.5 * (1.0 - s) * (1.0 - s);
  if (s >= 1.5) return 1.0;
  if (s >= 0.5) return 1.0 - (1.5 - s) * (1.5 - s) * (1.5 - s) / 6.0;
  return 0.5 + 0.75 * s - s * s * s / 3.0;
}

double surface_distance(double f, ShapeKind shape, int np) {
  const double lo = (shape == ShapeKind::Linear ? -1.0 : -1.5) + 0.5 / np, hi = -lo;
  if (f <= 0.0) return lo;
  if (f >= 1.0) return hi;
  // safeguarded Newton on the increasing G between the bracket's ends
  double a = lo, b = hi, x = 0.5 * (lo + hi);
  for (int it = 0; it < 100; ++it) {
    double dg;
    const double res = lattice_fill(x, shape, np, &dg) - f;
    if (std::fabs(res) < 1e-14) break;
    (res < 0.0 ? a : b) = x;
    double nx = dg > 0.0 ? x - res / dg : 0.5 * (a + b);
    if (!(nx > a && nx < b)) nx = 0.5 * (a + b);
    if (b - a < 1e-14) break;
    x = nx;
  }
  return x;
}

/* FLUID where the node holds fluid (mass above the threshold and kSurfaceFill of a full cell),
   EMPTY elsewhere (the free surface: p = 0), SOLID padding behind the box walls (NodeLabels::reset). The closed gate is a
   wall at rest: the face between the last node on the fluid side and the next one (a gate through
   a node plane leaves that node on the fluid side, like a box wall through its nodes). */
void Projection::make_labels(const double *p2g, double mmin, const double *theta, const WallGeometry *walls,
                             LocalGrid::Field with, LocalGrid::Field with2) {
  const bool sparse = grid_.restricted();
  lab_.reset(grid_, sparse ? &work_ : nullptr);
  for (int f = 0; f < 6; ++f) lab_.grid_face_u[f] = opt_.face_velocity(f);
  mesh_ = walls != nullptr;
  if (mesh_) mesh_wall_labels(*walls);
  const double dx = opt_.grid.dx, full = opt_.rho0 * dx * dx * dx;
  // the points per cell along the surface's normal: the fill's largest count (a slab one cell
  // thick, filled with one point across, has no surface across it)
  const int np = std::max({opt_.fill_ppc[0], opt_.fill_ppc[1], opt_.fill_ppc[2]});
  if (opt_.surface_ghost) {
    // with a work box: outside it the level is never read (it enters only the faces of FLUID
    // nodes) and fold_mass_ is 0 (retire)
    zero_for_sweep(lab_.level);
    zero_for_sweep(fold_mass_);
    grid_.for_owned([&](int, int, int, std::size_t n) { fold_mass_[n] = p2g[P2gRec::N * n + P2gRec::M]; });
    grid_.forward(fold_mass_.data(), 1);
  }
  // the film's front: the candidates (under kFrontFill) and the dry nodes (outside a work box: dry)
  const bool film = opt_.front_rate > 0.0;
  if (film) {
    front_.assign(grid_.size(), 0);
    lab_.dry.assign(grid_.size(), 1);
  }
  gl_.assign(theta ? grid_.size() : 0, 0.0);  // with grains: their levels (grain_levels)
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] == kSolid) return;
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    const double th = theta ? theta[n] : 1.0;
    const double cut = mesh_ ? frac_[n] : 1.0;
    const double fill = (opt_.surface_ghost ? folded_mass(i, j, k) : m) / (th * full * geo_.volume(i, j, k) * cut);
    if (opt_.surface_ghost) {
      // level set: the signed distance to the surface read from the fill (surface_distance);
      // FLUID where it exceeds kLevelTie
      lab_.level[n] = surface_distance(fill, opt_.shape, np);
      if (m <= mmin || m <= 0.0 || !level_is_fluid(lab_.level[n])) lab_.kind[n] = kEmpty;
    } else if (m <= mmin || m <= 0.0 || fill < kSurfaceFill) {
      lab_.kind[n] = kEmpty;
    }
    // (without a level set, mesh walls: the level of the same fill, for the grains only)
    if (!gl_.empty() && !opt_.surface_ghost) gl_[n] = surface_distance(fill, opt_.shape, np);
    if (film) {
      lab_.dry[n] = m <= mmin || m <= 0.0;
      front_[n] = fill < kFrontFill;
    }
    // the nodes on an outflow face hold p = 0 (a Dirichlet face: EMPTY, wet when they hold fluid);
    // those on an inflow face holding fluid are FLUID: the inflow's stream goes on behind the face,
    // where there are no points yet, so their fill falls as the lattice moves off the face (by a
    // whole layer before the next is made), and read as a free surface it held p = 0 under the
    // column (a column fed from below lost its pressure and velocity within 0.02 s)
    if (on_face(i, j, k, BcKind::Outflow)) lab_.kind[n] = kEmpty;
    if (on_face(i, j, k, BcKind::Inflow) && m > mmin && m > 0.0) lab_.kind[n] = kFluid;
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
  lab_.exchange(grid_, comm_, with, with2);
  if (theta) grain_levels();
}

/* The grains' immersion (FluidSolver::grain_drag_sums; docs/theory/drag.md, "Grains at the free
   surface"): per node the signed distance to the free surface in cells that a grain reads, at the
   owned nodes then forwarded. A node counts with its own level (the level set, or with mesh walls
   the level of its fill, in gl_ from make_labels) only in the surface's band, where it or one of
   its six face neighbours is EMPTY; elsewhere with the bulk's kLevelMin (beside a wall the fill is
   cut by the wall, not by the water: a wall below the water is no surface); at SOLID nodes
   (padding, behind mesh walls) NaN: not read. Labels of the owned nodes' neighbours: after the
   labels' exchange. */
void Projection::grain_levels() {
  const bool own = lab_.level.empty();  // mesh walls: gl_ holds the fill's level
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] == kSolid) {
      gl_[n] = std::numeric_limits<double>::quiet_NaN();
      return;
    }
    const bool band = lab_.kind[n] == kEmpty || neighbour_of_kind(grid_, lab_, i, j, k, kEmpty);
    gl_[n] = band ? (own ? gl_[n] : lab_.level[n]) : kLevelMin;
  });
  grid_.forward(gl_.data(), 1);
}

bool Projection::mark_front() {
  bool any = false;
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (!front_[n]) return;
    bool edge = false;
    if (lab_.kind[n] == kFluid)
      for (int d = 0; d < 3 && !edge; ++d)
        for (int side = -1; side <= 1 && !edge; side += 2) {
          std::size_t m = n;
          edge = open_face(grid_, lab_, i, j, k, d, side, &m) && lab_.kind[m] == kEmpty && lab_.dry[m];
        }
    front_[n] = edge;
    any = any || edge;
  });
  return any;
}

/* The node mass with the mass of its mirror images behind the box walls added (the padding nodes
   the B-spline gives part of the wall-side points' mass): the mass a fluid continued by
   reflection at the walls would give. Without it the nodes next to a wall read a fill 1-3 % low,
   the ghost surface sits lower there and a column at rest starts to circulate (F1: 0.02 m/s after
   1 s, docs/theory/projection.md). Reads fold_mass_ on the owned nodes and halos. */
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

/* Mesh walls (docs/theory/projection.md, "Mesh walls"). A grid face whose segment between its two nodes
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
  // the volume correction's expected fill beside the walls: the distance to the nearest triangle
  // that is not in a face of the box (there mirror_sum adds the fluid's image behind it)
  const bool cover = opt_.volume_correction > 0.0;
  std::vector<std::pair<int, double>> planes;
  if (cover) {
    wall_dist_.assign(WallGeometry::kWallDirs * grid_.size(), kWallFar);
    for (int d = 0; d < 3; ++d)
      if (!gs.periodic[d]) {
        planes.emplace_back(d, gs.origin[d]);
        planes.emplace_back(d, gs.origin[d] + gs.ncell[d] * dx);
      }
  }
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] == kSolid) return;
    const double x[3] = {gs.origin[0] + i * dx, gs.origin[1] + j * dx, gs.origin[2] + k * dx};
    // faces first: a face from a node behind the wall carries the wall's velocity too
    for (int d = 0; d < 3; ++d) {
      if (!gs.periodic[d] && (d == 0 ? i : d == 1 ? j : k) >= gs.ncell[d]) continue;
      double w = 0.0;
      if (walls.crosses(x, d, dx, &w)) lab_.close_face(grid_, i, j, k, d, w);
    }
    double dist, off[WallGeometry::kWallDirs];
    const int side = walls.node_side(x, 2.0 * dx, &dist, &planes, cover ? off : nullptr);
    if (side < 0) lab_.kind[n] = kSolid;
    if (side > 0) frac_[n] = std::min(1.0, 0.5 + dist / dx);
    if (cover && side > 0)
      for (int q = 0; q < WallGeometry::kWallDirs; ++q)
        wall_dist_[WallGeometry::kWallDirs * n + q] = std::min(off[q] / dx, kWallFar);
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
  // per node: 1 if its gradient (gk_) / pressure (pk_) is known: FLUID nodes, and EMPTY nodes next
  // to a FLUID one for the gradient (pressure_gradient's one-sided surface face)
  zero_for_sweep(gk_);
  zero_for_sweep(pk_);
  // found from the FLUID side (a face is open from both of its nodes or from neither): the FLUID
  // nodes of the owned nodes (of the work box) grown by one node, and their EMPTY owned neighbours
  // across open faces (surface_, the first layer above the surface)
  const IndexBox ob = grid_.restricted() ? grid_.owned().cut(grid_.work()) : grid_.owned();
  IndexBox fb = ob;
  for (int d = 0; d < 3; ++d) {
    --fb.lo[d];
    ++fb.hi[d];
  }
  fb = fb.cut(grid_.patch());
  surface_.clear();
  if (!ob.empty())
    grid_.for_box(fb, [&](int i, int j, int k, std::size_t n) {
      if (lab_.kind[n] != kFluid) return;
      if (ob.contains(i, j, k)) gk_[n] = pk_[n] = 1.0;
      for (int d = 0; d < 3; ++d)
        for (int side = -1; side <= 1; side += 2) {
          int q[3] = {i, j, k};
          q[d] += side;
          std::size_t m;
          if (!ob.contains(q[0], q[1], q[2]) || !open_face(grid_, lab_, i, j, k, d, side, &m)) continue;
          if (lab_.kind[m] != kEmpty || gk_[m] != 0.0) continue;
          gk_[m] = 1.0;
          surface_.push_back({m, q[0], q[1], q[2]});
        }
    });
  gradient_along_surface(grad);
  grid_.forward({{gk_.data(), 1}, {pk_.data(), 1}, {grad.data(), 3}});
  // the owned EMPTY nodes holding fluid, in the order of the owned nodes (the passes visit them only)
  ghost_.clear();
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] != kEmpty) return;
    const double m = p2g[P2gRec::N * n + P2gRec::M];
    if (m > mmin && m > 0.0) ghost_.push_back({n, i, j, k});
  });
  for (int pass = 0; pass < 3; ++pass) extrapolation_pass(p, grad, with_p);
}

/* An EMPTY node next to the fluid has from pressure_gradient only the components along its faces
   to FLUID nodes: above a level surface the vertical one, and 0 along the surface, so the points
   near the surface read an unaccelerated velocity along it from the nodes above them and the
   standing wave ran slow (20 cells across: 0.962 of its frequency). The other components are the
   mean of the FLUID neighbours' (docs/theory/projection.md, "Free surface: the gradient along the
   surface"). Owned nodes (halos not forwarded). */
void Projection::gradient_along_surface(std::vector<double> &grad) {
  std::vector<std::pair<std::size_t, int>> fill;
  std::vector<double> val;
  // the owned EMPTY nodes with a known gradient: surface_ (the values come from FLUID nodes only,
  // and are written after the loop: the order of the nodes does not matter)
  for (const SurfaceNode &s : surface_) {
    const std::size_t n = s.n;
    const int i = s.i, j = s.j, k = s.k;
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
  }
  for (std::size_t q = 0; q < fill.size(); ++q) grad[3 * fill[q].first + fill[q].second] = val[q];
}

/* One layer of the continuation above the surface: an EMPTY node holding fluid whose gradient is
   not known takes the mean of its face neighbours' that are known, and one whose pressure is not
   known the linear continuation from the neighbours whose pressure is (with_p). The nodes that
   become known in a pass are marked after it (the pass reads the flags before it); halos
   forwarded. The pass visits ghost_, the owned EMPTY nodes holding fluid (the nodes every other
   owned node would return at once), and keeps for the next pass those whose gradient, or
   pressure with with_p, is still unknown after it (a node with both known changes nothing). */
void Projection::extrapolation_pass(std::vector<double> &p, std::vector<double> &grad, bool with_p) {
  const double dx = opt_.grid.dx;
  std::vector<double> &gk = gk_, &pk = pk_;
  std::vector<std::size_t> &gnew = gnew_, &pnew = pnew_;
  gnew.clear();
  pnew.clear();
  for (const SurfaceNode &s : ghost_) {
    const std::size_t n = s.n;
    const int i = s.i, j = s.j, k = s.k;
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
  }
  for (const std::size_t n : gnew) gk[n] = 1.0;
  for (const std::size_t n : pnew) pk[n] = 1.0;
  ghost_next_.clear();
  for (const SurfaceNode &s : ghost_)
    if (gk[s.n] == 0.0 || (with_p && pk[s.n] == 0.0)) ghost_next_.push_back(s);
  ghost_.swap(ghost_next_);
  grid_.forward({{gk.data(), 1}, {pk.data(), 1}, {grad.data(), 3}, {with_p ? p.data() : nullptr, 1}});
}

}  // namespace mpm
