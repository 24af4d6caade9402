// Discrete operators of the pressure projection on the node lattice of the
// background grid (docs/theory/projection.md): the approximate projection of Almgren,
// Bell & Szymczak (1996) moved from cells to nodes. Velocities and pressure
// live at the nodes; the faces of the dual cells, halfway between neighbouring
// nodes, carry the fluxes theta u of the volume-averaged continuity equation
//   d(theta)/dt + div(theta u) = 0,   u = u* - (dt / rho) grad p
// and the compact 7-point operator div(beta grad p), beta = theta / rho.
// Independent of LIGGGHTS; the hypre solve is in pressure_solver.h.
//
// Conventions for every function below: node arrays are indexed by the
// LocalGrid's flat patch index (vectors: 3 doubles per node); inputs must be
// valid on the owned nodes and on one halo layer around them (forward() after
// writing the owned ones); outputs are written on the owned nodes only.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "mpm/grid.h"
#include "mpm/shape_functions.h"

namespace mpm {

// FLUID nodes carry an unknown pressure; EMPTY nodes (no fluid: the free
// surface) hold a known pressure, 0 unless the solve is given other values;
// SOLID nodes (outside the box, inside obstacles) take part in nothing, and
// every face that touches one is a wall.
enum NodeKind : std::uint8_t { kFluid = 0, kEmpty = 1, kSolid = 2 };

// Per patch node: its kind, and which of its three upper faces (towards
// index + 1 along x, y, z) are walls. A wall face carries no flux relative to
// the wall: its flux is theta times the wall's velocity along +d, wall_u[3 n + d]
// (wall_u empty: walls at rest). Faces to SOLID nodes and to nodes beyond the
// grid are walls at rest unless flagged closed with a velocity.
struct NodeLabels {
  std::vector<std::uint8_t> kind;
  std::vector<std::uint8_t> closed;  // bit d: the face to index + e_d is a wall
  // Ghost-fluid surface: 1 at the EMPTY nodes that hold fluid mass (the B-spline spreads the points'
  // mass up to 1.5 cells beyond the surface): their velocity takes part in the flux of their faces
  // to FLUID nodes (surface_weight). Empty: none (free_surface node, or set by the caller).
  std::vector<std::uint8_t> wet;
  // Node surface (no level): 1 at the EMPTY nodes that hold no fluid (mass at most the threshold),
  // for the film's front (Projection::mark_front). Empty: not kept (ghost surface).
  std::vector<std::uint8_t> dry;
  std::vector<double> wall_u;
  // the velocity along +d through the grid face f = 2 d (low) or 2 d + 1 (high) of a face of a
  // node on it towards the padding or beyond the grid (keyword boundary ... inflow U; 0: at rest)
  double grid_face_u[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  // Ghost-fluid free surface (docs/theory/projection.md, "Free surface"): per node the signed distance
  // to the free surface in units of dx, positive inside the fluid (empty: p = 0 at the EMPTY
  // nodes themselves). A face between a FLUID node n and an EMPTY node m then holds p = 0 at the
  // fraction s_f = level_n / (level_n - level_m) of the face's length from n (at least
  // kMinSurfaceFraction): its coefficient and gradient are divided by s_f (Gibou et al. 2002).
  std::vector<double> level;

  // Every node FLUID with open faces, except the padding nodes behind the box
  // walls (indices < 0 or > ncell in non-periodic dimensions), which are SOLID.
  // work (the projection's sparse sweeps): only the nodes of that box FLUID, the others EMPTY
  // (they hold no fluid, which is what the labelling of their mass would find); the level keeps
  // its size and values (the caller sets it in the box).
  void reset(const LocalGrid &grid, const IndexBox *work = nullptr);
  void close_face(const LocalGrid &grid, int i, int j, int k, int d, double wall_velocity = 0.0);
  // Copies the owned nodes' labels into the halos (collective over the grid's comm); with, with2:
  // more arrays forwarded in the same messages (none if their data is null).
  void exchange(LocalGrid &grid, MPI_Comm comm, LocalGrid::Field with = {nullptr, 0},
                LocalGrid::Field with2 = {nullptr, 0});

 private:
  std::vector<double> buf_;  // exchange: kind and closed packed (only the exchanged nodes used)
};

// Control volumes of the nodes. The box walls pass through the nodes with index
// 0 and ncell (non-periodic dimensions): with half_cells the dual cell of a wall
// node is cut by the wall (volume 1/2, 1/4 on an edge, 1/8 in a corner, in units
// of dx^3) and so are its faces along the wall (area 1/2 or 1/4 of dx^2). This
// keeps the Neumann walls second-order accurate and the flux theta u through a
// wall node's face consistent with its theta, which the fix computes on the
// half cell (docs/theory/projection.md, the measurement). Without it every dual cell
// is a full cube, i.e. the wall sits half a cell behind the wall nodes.
struct ProjectionGeometry {
  GridSpec spec;
  bool half_cells = true;

  double h(int d, int i) const {
    if (!half_cells || spec.periodic[d]) return 1.0;
    return (i == 0 || i == spec.ncell[d]) ? 0.5 : 1.0;
  }
  double volume(int i, int j, int k) const { return h(0, i) * h(1, j) * h(2, k); }
  // Face between (i, j, k) and (i, j, k) + e_d, in units of dx^2.
  double area(int d, int i, int j, int k) const {
    const int idx[3] = {i, j, k};
    double a = 1.0;
    for (int e = 0; e < 3; ++e)
      if (e != d) a *= h(e, idx[e]);
    return a;
  }
};

// The signed distance (units of dx, positive inside) from a node to a plane free surface whose
// fluid gives the node the fill f, the fluid being points of the fill's lattice, np points per cell
// along the surface's normal: the inverse of the lattice's fill
//   G(s) = (1 / np) sum_{j >= 0} N(s - (j + 1/2) / np)
// of a node s cells below the surface, its top layer of points half a spacing below it (N the
// shape function; docs/theory/projection.md, "Free surface: energy and stiffness"). G is the fill
// the node's mass gives wherever the plane lies relative to the nodes and moves with the points:
// the level is the distance itself. The continuous F(s) = int_{-inf}^{s} N (the limit np -> inf)
// read the points' samples as a continuum: with 2 points per cell the EMPTY node above a surface on
// a node plane has the fill N(5/4) / 2 = 1/64 against F(-1) = 1/48, its level read -1.046 and the
// ghost surface moved 0.956 times as far as the water (the standing wave 3 % slow at 20 cells).
// G is 0 up to s = -r + 1 / (2 np) (r the support's half width) and 1 from r - 1 / (2 np): a fill
// of 0 or 1 reads those ends (the level continuous in the fill).
// lattice_fill: G(s) (slope: dG/ds, if not null); surface_distance: the level of the fill f, G^-1(f).
double lattice_fill(double s, ShapeKind shape, int np, double *slope = nullptr);
double surface_distance(double f, ShapeKind shape, int np);
// The limit np -> inf of G: F(s) = int_{-s}^{inf} N, the share of a node's shape function on the
// fluid side of a plane s cells from it (s < 0: the node beyond the plane). A lattice of points
// whose layers lie at random offsets from the plane (a wall at an angle to the lattice, or one
// the points move along) gives the node this fill on average; a lattice parallel to the plane
// gives G(s), up to 5.4 % more with one point per cell, 1.3 % with two (the quadratic B-spline).
double continuum_fill(double s, ShapeKind shape);

// Smallest fraction of a cell between a FLUID node and the surface (clamp of the ghost-fluid
// coefficient 1 / s_f: at most 20x the face's own).
constexpr double kMinSurfaceFraction = 1e-3;

// Ghost surface: a node is FLUID when its level exceeds this bound. The level, the distance to the
// surface in cells, is at least -kLevelMin (the shape function's support: 3/2 for the quadratic
// B-spline, 1 for the hat), so a FLUID node's fraction s_f = level_n / (level_n - level_m) is then
// at least kMinSurfaceFraction on each face and the clamp never binds. With a smaller bound (1e-9
// measured) a node a hair inside the surface (a fluid filled up to a node plane: level 0 up to
// round-off, some 1e-7 where grains displace it) was FLUID with its surface face clamped, and
// the fraction of its face to an EMPTY neighbour as near the surface, l_n / (l_n - l_m) with both
// levels near 0, made the pressure oversensitive to the levels: a level moved by delta changed
// the pressure by 11 rho g dx delta instead of 0.45 (PressureSolver.GhostSurfaceOnANodePlane-
// IsWellConditioned), and np 2 drifted from np 1 (docs/theory/projection.md). The bound also keeps a
// fluid filled up to a node plane from flipping its nodes between EMPTY and FLUID.
constexpr double kLevelMin = 1.5;
constexpr double kLevelTie = kLevelMin * kMinSurfaceFraction / (1.0 - kMinSurfaceFraction);
inline bool level_is_fluid(double level) { return level > kLevelTie; }

// 1 / s_f for a face between a FLUID and an EMPTY node when labels.level is set, 1 otherwise.
inline double surface_scale(const NodeLabels &labels, std::size_t n, std::size_t m) {
  if (labels.level.empty() || labels.kind[n] == labels.kind[m]) return 1.0;
  const bool nf = labels.kind[n] == kFluid;
  if (!nf && labels.kind[m] != kFluid) return 1.0;  // EMPTY-SOLID faces are walls anyway
  const double lf = nf ? labels.level[n] : labels.level[m], le = nf ? labels.level[m] : labels.level[n];
  const double s = (lf - le > 0.0) ? lf / (lf - le) : 1.0;
  return 1.0 / std::min(1.0, std::max(kMinSurfaceFraction, s));
}

// The weight of the EMPTY node's velocity in the flux through a face between a FLUID node and an
// EMPTY node: s_f / 2 if the EMPTY node holds fluid (labels.wet), 0 otherwise (the FLUID node's
// velocity alone: the velocity extended into the empty region). s_f / 2 places the face's velocity
// at the middle of the wetted part of the segment between the two nodes (linear interpolation);
// a surface at the EMPTY node (s_f = 1) gives the mean of two FLUID nodes' faces.
inline double surface_weight(const NodeLabels &labels, std::size_t n, std::size_t m) {
  if (labels.wet.empty()) return 0.0;
  const std::size_t e = labels.kind[n] == kEmpty ? n : m;
  if (!labels.wet[e]) return 0.0;
  return 0.5 / surface_scale(labels, n, m);
}

// Whether one of the six face neighbours of node (i, j, k) that lie in the patch is of this kind
// (faces open or not).
bool neighbour_of_kind(const LocalGrid &grid, const NodeLabels &lab, int i, int j, int k, NodeKind kind);

// True if the face of node (i, j, k) towards (i, j, k) + side e_d (side = -1 or
// +1) is open: both nodes in the patch, neither SOLID, not flagged closed.
// *m: the neighbour's flat index when it lies in the patch.
// (inline: it is called for every face of every node in most of the projection's sweeps)
inline bool open_face(const LocalGrid &grid, const NodeLabels &labels, int i, int j, int k, int d, int side,
                      std::size_t *m) {
  int q[3] = {i, j, k};
  q[d] += side;
  if (!grid.in_patch(q[0], q[1], q[2])) return false;  // beyond the grid: the halo covers all else
  const std::size_t n = grid.index(i, j, k), nb = grid.index(q[0], q[1], q[2]);
  *m = nb;
  const std::size_t lower = side > 0 ? n : nb;
  return !((labels.closed[lower] >> d) & 1u) && labels.kind[n] != kSolid && labels.kind[nb] != kSolid;
}

// pressure_gradient's weight of the open face of node n towards m (theta: the fluid fractions, or
// null): false if the face carries no pressure information (n not FLUID and not wet, m not
// FLUID). *s: the face's s_f = 1 / surface_scale. *plain false: the face adds w G to the
// gradient's numerator and w s_f to its denominator (G the face gradient; the adjoint of
// flux_divergence: w = theta_f w_n, w_n = 1/2 between two FLUID nodes, 1 - surface_weight towards
// an EMPTY one, surface_weight for a wet EMPTY node towards a FLUID one); *plain true (a dry EMPTY
// node towards a FLUID one: the gradient continued from the fluid side): G / s_f and 1.
inline bool gradient_face(const NodeLabels &labels, const double *theta, std::size_t n, std::size_t m, double *w,
                          double *s, bool *plain) {
  const std::uint8_t a = labels.kind[n], b = labels.kind[m];
  *s = 1.0 / surface_scale(labels, n, m);
  *plain = false;
  if (a == kFluid) {
    const double th = theta ? 0.5 * (theta[n] + theta[m]) : 1.0;
    *w = th * (b == kFluid ? 0.5 : 1.0 - surface_weight(labels, n, m));
    return true;
  }
  if (b != kFluid) return false;
  if (!labels.wet.empty() && labels.wet[n]) {
    *w = (theta ? 0.5 * (theta[n] + theta[m]) : 1.0) * surface_weight(labels, n, m);
    return true;
  }
  *plain = true;
  return true;
}

// The integrated divergence of theta u at the owned non-SOLID nodes:
// D_n = sum over the faces of n of (area x outward flux) / dx, per dx^3 (the
// divergence per volume is D_n / volume(n)). The flux through an open face is
// theta_f u_f with theta_f the mean of the two nodes' theta and u_f the mean
// of their velocity components along the face normal; between a FLUID and an
// EMPTY node u_f is the FLUID node's (the velocity is extended across the
// free surface, so a falling body of fluid is not squeezed at its surface),
// mixed with the EMPTY node's by surface_weight where that node holds fluid.
void flux_divergence(const LocalGrid &grid, const NodeLabels &labels, const ProjectionGeometry &geo,
                     const double *u, const double *theta, double *div);

// Right-hand side of the pressure equation at the owned FLUID nodes (0 elsewhere):
// rhs_n = (D_n + volume(n) (theta_n - theta_prev_n) / dt) / dt, D_n of
// flux_divergence; theta_prev null: no d(theta)/dt term.
void pressure_rhs(const LocalGrid &grid, const NodeLabels &labels, const ProjectionGeometry &geo,
                  const double *u, const double *theta, const double *theta_prev, double dt, double *rhs);

// The film's front (docs/theory/projection.md, "The step size"): at the owned nodes with front[n]
// set, rhs_n -= c D'_n(u_old), D'_n the part of flux_divergence through the node's open faces (a
// wall face's flux is the wall's and stays in full). With c = (1 - f) / (s h) the source there is
// that of u* - (1 - f) u_old / s: the divergence of the step's increment removed in full, that of
// the P2G velocity u_old the share f per step.
void relax_front_source(const LocalGrid &grid, const NodeLabels &labels, const ProjectionGeometry &geo,
                        const std::uint8_t *front, const double *u_old, const double *theta, double c, double *rhs);

// Right-hand side of the pressure of an acceleration field a (keyword pressure_output
// acceleration): rhs_n = D_n of flux_divergence with a for u, at the owned FLUID nodes (0
// elsewhere), but no flux through wall faces (a wall at rest or moving at a constant velocity has
// no normal acceleration) and on FLUID-EMPTY faces the FLUID node's a alone (a is given at the
// FLUID nodes only). The solve then gives the p of div(beta grad p) = div(theta a).
void acceleration_rhs(const LocalGrid &grid, const NodeLabels &labels, const ProjectionGeometry &geo,
                      const double *a, const double *theta, double *rhs);
// The operator the solver inverts, at the owned FLUID nodes (0 elsewhere):
// (L p)_n = sum over the open faces f = (n, m) of area_f beta_f (p_m - p_n) / dx^2,
// beta_f = (beta_n + beta_m) / 2, EMPTY neighbours entering with their p.
// The solver makes (L p)_n = rhs_n.
void apply_laplacian(const LocalGrid &grid, const NodeLabels &labels, const ProjectionGeometry &geo,
                     const double *beta, const double *p, double *out);

// The divergence (as flux_divergence) of the corrected face fluxes
// theta_f u*_f - dt beta_f (p_m - p_n) / dx: the exact projection on the faces,
// whose D_n + volume(n) d(theta)/dt vanishes to the solver's tolerance.
void corrected_flux_divergence(const LocalGrid &grid, const NodeLabels &labels,
                               const ProjectionGeometry &geo, const double *u, const double *theta,
                               const double *beta, const double *p, double dt, double *div);

// Nodal pressure gradient at the owned non-SOLID nodes (0 at SOLID ones). At a FLUID node, per
// direction d, the adjoint of flux_divergence divided by the node's share of fluid length:
//   g_n = sum_f theta_f w_f G_f / sum_f theta_f w_f s_f
// over its two open faces f along d, G_f = (p_upper - p_lower) / dx with p = 0 at EMPTY nodes,
// w_f the weight of u_n in the face's flux (1/2 towards a FLUID node, 1 - surface_weight towards an
// EMPTY one), s_f the ghost-fluid fraction of the face (1 off the surface); wall faces carry no u_n
// (w = 0): the open face alone next to a wall, 0 between two walls. At an EMPTY node holding fluid
// (labels.wet) the same over its faces to FLUID nodes with w_f = surface_weight. With u -= h g / rho the projection then removes
// kinetic energy (in the norm sum rho theta_f w_f s_f u^2) and a hydrostatic pressure is balanced
// exactly (docs/theory/projection.md, "Free surface: energy and stiffness"). Off the surface and with
// theta = 1 it is the mean of the two face gradients. At another EMPTY node: the mean of the
// ghost-fluid gradients of its faces to FLUID nodes (continued from the fluid side). theta null: 1. The
// gradient the fluid's nodes feel and the one to interpolate to grains.
void pressure_gradient(const LocalGrid &grid, const NodeLabels &labels, const double *p, double *grad,
                       const double *theta = nullptr);

// pressure_gradient's gradient at node (i, j, k) = n along d as weights of its two faces:
// g_d = sum over side = -1, +1 of c[side > 0] side (p[m] - p[n]) / dx, m[side > 0] the neighbour
// (c = 0 for a face that is not open). False where pressure_gradient gives 0 (SOLID node, EMPTY
// node away from the fluid). For the wall loads (FluidSolver::wall_pressure_loads).
bool gradient_weights(const LocalGrid &grid, const NodeLabels &labels, const double *theta, int i, int j, int k,
                      std::size_t n, int d, double c[2], std::size_t m[2]);

// u -= dt inv_rho grad at the owned non-SOLID nodes (inv_rho per node).
void correct_velocity(const LocalGrid &grid, const NodeLabels &labels, const double *grad,
                      const double *inv_rho, double dt, double *u);

}  // namespace mpm
