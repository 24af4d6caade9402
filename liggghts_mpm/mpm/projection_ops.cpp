#include "mpm/projection_ops.h"

#include <algorithm>

namespace mpm {

namespace {

// One face of an owned node n, towards its neighbour m = n + side e_d.
struct Face {
  bool wall = true;       // no neighbour, a SOLID one, or flagged closed
  std::size_t m = 0;      // neighbour's flat index (valid unless beyond the grid)
  bool has_m = false;
  double wall_u = 0.0;    // wall velocity along +d (wall faces)
  double area = 1.0;      // units of dx^2
};

Face face_of(const LocalGrid &grid, const NodeLabels &lab, const ProjectionGeometry &geo, int i, int j,
             int k, std::size_t n, int d, int side) {
  Face f;
  // The face's area is the same seen from either node (their other indices agree).
  f.area = geo.area(d, i, j, k);
  f.wall = !open_face(grid, lab, i, j, k, d, side, &f.m);
  int q[3] = {i, j, k};
  q[d] += side;
  f.has_m = grid.in_patch(q[0], q[1], q[2]);
  bool flagged = false;
  if (f.wall && f.has_m) {
    const std::size_t lower = side > 0 ? n : f.m;
    flagged = (lab.closed[lower] >> d) & 1u;
    if (flagged && !lab.wall_u.empty()) f.wall_u = lab.wall_u[3 * lower + d];
  }
  // a face across a grid face (to the padding or beyond the grid) not closed with a velocity of its
  // own: that grid face's velocity (inflow)
  const GridSpec &gs = grid.spec();
  if (f.wall && !flagged && !gs.periodic[d] && (q[d] < 0 || q[d] > gs.ncell[d]))
    f.wall_u = lab.grid_face_u[2 * d + (side > 0)];
  return f;
}

// Calls fn(n, f, d, side) for the six faces of every owned non-SOLID node for which
// want(i, j, k, n) holds.
template <class Want, class Fn>
void for_faces_if(const LocalGrid &grid, const NodeLabels &lab, const ProjectionGeometry &geo, Want &&want, Fn &&fn) {
  grid.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab.kind[n] == kSolid || !want(i, j, k, n)) return;
    for (int d = 0; d < 3; ++d)
      for (int side = -1; side <= 1; side += 2) fn(n, face_of(grid, lab, geo, i, j, k, n, d, side), d, side);
  });
}

template <class Fn>
void for_faces(const LocalGrid &grid, const NodeLabels &lab, const ProjectionGeometry &geo, Fn &&fn) {
  for_faces_if(grid, lab, geo, [](int, int, int, std::size_t) { return true; }, fn);
}

// An EMPTY node none of whose six neighbours in the patch is FLUID (its pressure gradient is 0).
bool empty_away_from_fluid(const LocalGrid &grid, const NodeLabels &lab, int i, int j, int k, std::size_t n) {
  return lab.kind[n] == kEmpty && !neighbour_of_kind(grid, lab, i, j, k, kFluid);
}

// Flux theta u along +d through face f of node n (see flux_divergence).
// mix false: the FLUID node's value alone on FLUID-EMPTY faces (a field given at the FLUID nodes only).
double face_flux(const NodeLabels &lab, std::size_t n, const Face &f, int d, const double *u,
                 const double *theta, bool mix = true) {
  if (f.wall) {
    const bool other = f.has_m && lab.kind[f.m] != kSolid;
    const double th = other ? 0.5 * (theta[n] + theta[f.m]) : theta[n];
    return th * f.wall_u;
  }
  const double th = 0.5 * (theta[n] + theta[f.m]);
  const std::uint8_t a = lab.kind[n], b = lab.kind[f.m];
  double uf;
  if (a == b)
    uf = 0.5 * (u[3 * n + d] + u[3 * f.m + d]);
  else {
    // FLUID-EMPTY: the FLUID node's velocity, and the EMPTY node's with surface_weight if it holds fluid
    const double al = mix ? surface_weight(lab, n, f.m) : 0.0;
    const std::size_t fl = a == kFluid ? n : f.m, em = a == kFluid ? f.m : n;
    uf = (1.0 - al) * u[3 * fl + d] + al * u[3 * em + d];
  }
  return th * uf;
}

}  // namespace

bool neighbour_of_kind(const LocalGrid &grid, const NodeLabels &lab, int i, int j, int k, NodeKind kind) {
  for (int d = 0; d < 3; ++d)
    for (int side = -1; side <= 1; side += 2) {
      int q[3] = {i, j, k};
      q[d] += side;
      if (grid.in_patch(q[0], q[1], q[2]) && lab.kind[grid.index(q[0], q[1], q[2])] == kind) return true;
    }
  return false;
}

void NodeLabels::reset(const LocalGrid &grid, const IndexBox *work) {
  const GridSpec &g = grid.spec();
  const IndexBox &pb = grid.patch();
  kind.assign(grid.size(), work ? kEmpty : kFluid);
  if (work) grid.for_box(work->cut(pb), [&](int, int, int, std::size_t n) { kind[n] = kFluid; });
  closed.assign(grid.size(), 0);
  wet.clear();
  dry.clear();
  wall_u.clear();
  if (!work) level.clear();  // with a work box the caller fills the level in the box (kept sized)
  // the padding: the slabs of the patch below node 0 and above node ncell of each non-periodic d
  for (int d = 0; d < 3; ++d) {
    if (g.periodic[d]) continue;
    for (const IndexBox &layer : g.padding_layers(pb, d))
      grid.for_box(layer, [&](int, int, int, std::size_t n) { kind[n] = kSolid; });
  }
}

void NodeLabels::close_face(const LocalGrid &grid, int i, int j, int k, int d, double wall_velocity) {
  const std::size_t n = grid.index(i, j, k);
  closed[n] |= std::uint8_t(1u << d);
  if (wall_velocity != 0.0 && wall_u.empty()) wall_u.assign(3 * grid.size(), 0.0);
  if (!wall_u.empty()) wall_u[3 * n + d] = wall_velocity;
}

void NodeLabels::exchange(LocalGrid &grid, MPI_Comm comm, LocalGrid::Field with, LocalGrid::Field with2) {
  // One forward of small integers packed in doubles (exact), with the wall velocities when some
  // rank has moving walls and the level set when there is one, all in one message per peer.
  // Only the nodes the forward reads or writes are packed and unpacked (a surface, not the patch).
  int moving = wall_u.empty() ? 0 : 1, any = 0;
  MPI_Allreduce(&moving, &any, 1, MPI_INT, MPI_MAX, comm);
  if (any && wall_u.empty()) wall_u.assign(3 * grid.size(), 0.0);
  buf_.resize(grid.size());
  const std::vector<IndexBox> boxes = grid.exchanged_boxes();
  for (const IndexBox &b : boxes)
    grid.for_box(b, [&](int, int, int, std::size_t n) {
      buf_[n] = kind[n] + 4.0 * closed[n] + (wet.empty() ? 0.0 : 256.0 * wet[n]) + (dry.empty() ? 0.0 : 512.0 * dry[n]);
    });
  grid.forward({{buf_.data(), 1}, {any ? wall_u.data() : nullptr, 3}, {level.empty() ? nullptr : level.data(), 1}, with,
                with2});
  for (const IndexBox &b : boxes)
    grid.for_box(b, [&](int, int, int, std::size_t n) {
      const int v = static_cast<int>(buf_[n]);
      kind[n] = std::uint8_t(v & 3);
      closed[n] = std::uint8_t((v >> 2) & 63);
      if (!wet.empty()) wet[n] = std::uint8_t((v >> 8) & 1);
      if (!dry.empty()) dry[n] = std::uint8_t((v >> 9) & 1);
    });
}

void flux_divergence(const LocalGrid &grid, const NodeLabels &labels, const ProjectionGeometry &geo,
                     const double *u, const double *theta, double *div) {
  const double inv_dx = 1.0 / grid.spec().dx;
  grid.for_owned([&](int, int, int, std::size_t n) { div[n] = 0.0; });
  for_faces(grid, labels, geo, [&](std::size_t n, const Face &f, int d, int side) {
    div[n] += side * f.area * face_flux(labels, n, f, d, u, theta) * inv_dx;
  });
}

void pressure_rhs(const LocalGrid &grid, const NodeLabels &labels, const ProjectionGeometry &geo,
                  const double *u, const double *theta, const double *theta_prev, double dt, double *rhs) {
  // flux_divergence at the FLUID nodes only (the rest of rhs is 0)
  const double inv_dx = 1.0 / grid.spec().dx;
  grid.for_owned([&](int, int, int, std::size_t n) { rhs[n] = 0.0; });
  for_faces_if(
      grid, labels, geo, [&](int, int, int, std::size_t n) { return labels.kind[n] == kFluid; },
      [&](std::size_t n, const Face &f, int d, int side) {
        rhs[n] += side * f.area * face_flux(labels, n, f, d, u, theta) * inv_dx;
      });
  grid.for_owned([&](int i, int j, int k, std::size_t n) {
    if (labels.kind[n] != kFluid) {
      rhs[n] = 0.0;
      return;
    }
    double s = rhs[n];
    if (theta_prev) s += geo.volume(i, j, k) * (theta[n] - theta_prev[n]) / dt;
    rhs[n] = s / dt;
  });
}

void relax_front_source(const LocalGrid &grid, const NodeLabels &labels, const ProjectionGeometry &geo,
                        const std::uint8_t *front, const double *u_old, const double *theta, double c, double *rhs) {
  const double s = c / grid.spec().dx;
  for_faces_if(
      grid, labels, geo, [&](int, int, int, std::size_t n) { return front[n] != 0; },
      [&](std::size_t n, const Face &f, int d, int side) {
        if (!f.wall) rhs[n] -= s * side * f.area * face_flux(labels, n, f, d, u_old, theta);
      });
}

void acceleration_rhs(const LocalGrid &grid, const NodeLabels &labels, const ProjectionGeometry &geo,
                      const double *a, const double *theta, double *rhs) {
  const double inv_dx = 1.0 / grid.spec().dx;
  grid.for_owned([&](int, int, int, std::size_t n) { rhs[n] = 0.0; });
  for_faces_if(
      grid, labels, geo, [&](int, int, int, std::size_t n) { return labels.kind[n] == kFluid; },
      [&](std::size_t n, const Face &f, int d, int side) {
        if (!f.wall) rhs[n] += side * f.area * face_flux(labels, n, f, d, a, theta, false) * inv_dx;
      });
}

void apply_laplacian(const LocalGrid &grid, const NodeLabels &labels, const ProjectionGeometry &geo,
                     const double *beta, const double *p, double *out) {
  const double inv_dx2 = 1.0 / (grid.spec().dx * grid.spec().dx);
  grid.for_owned([&](int, int, int, std::size_t n) { out[n] = 0.0; });
  for_faces(grid, labels, geo, [&](std::size_t n, const Face &f, int, int) {
    if (labels.kind[n] != kFluid || f.wall) return;
    out[n] += f.area * 0.5 * (beta[n] + beta[f.m]) * surface_scale(labels, n, f.m) * (p[f.m] - p[n]) * inv_dx2;
  });
}

void corrected_flux_divergence(const LocalGrid &grid, const NodeLabels &labels,
                               const ProjectionGeometry &geo, const double *u, const double *theta,
                               const double *beta, const double *p, double dt, double *div) {
  const double inv_dx = 1.0 / grid.spec().dx;
  grid.for_owned([&](int, int, int, std::size_t n) { div[n] = 0.0; });
  for_faces(grid, labels, geo, [&](std::size_t n, const Face &f, int d, int side) {
    double flux = face_flux(labels, n, f, d, u, theta);
    // gradient along +d across the face: (p_upper - p_lower) / dx
    if (!f.wall)
      flux -= dt * 0.5 * (beta[n] + beta[f.m]) * surface_scale(labels, n, f.m) * side * (p[f.m] - p[n]) * inv_dx;
    div[n] += side * f.area * flux * inv_dx;
  });
}

void pressure_gradient(const LocalGrid &grid, const NodeLabels &labels, const double *p, double *grad,
                       const double *theta) {
  const double inv_dx = 1.0 / grid.spec().dx;
  // Face areas do not enter a nodal gradient (the two faces of a node along d have the same
  // area): any geometry will do.
  ProjectionGeometry geo;
  geo.spec = grid.spec();
  geo.half_cells = false;
  grid.for_owned([&](int, int, int, std::size_t n) {
    for (int d = 0; d < 3; ++d) grad[3 * n + d] = 0.0;
  });
  // for_faces visits the faces of a node in the order (x,-), (x,+), (y,-), ...
  double num = 0.0, den = 0.0;
  for_faces_if(grid, labels, geo,
               [&](int i, int j, int k, std::size_t n) { return !empty_away_from_fluid(grid, labels, i, j, k, n); },
               [&](std::size_t n, const Face &f, int d, int side) {
    if (side < 0) num = den = 0.0;
    double w = 0.0, s = 1.0;
    bool plain = false;
    if (!f.wall && gradient_face(labels, theta, n, f.m, &w, &s, &plain)) {
      // the denominator sum theta_f w_n s_f is the node's share of the faces' fluid lengths
      // (hydrostatic exact); a dry EMPTY node continues the gradient of its faces to FLUID nodes
      const double G = side * (p[f.m] - p[n]) * inv_dx;  // face gradient along +d, p = 0 at EMPTY
      if (plain) {
        num += G / s;
        den += 1.0;
      } else {
        num += w * G;
        den += w * s;
      }
    }
    if (side > 0) grad[3 * n + d] = den > 0.0 ? num / den : 0.0;
  });
}

bool gradient_weights(const LocalGrid &grid, const NodeLabels &labels, const double *theta, int i, int j, int k,
                      std::size_t n, int d, double c[2], std::size_t m[2]) {
  c[0] = c[1] = 0.0;
  m[0] = m[1] = n;
  if (labels.kind[n] == kSolid || empty_away_from_fluid(grid, labels, i, j, k, n)) return false;
  double den = 0.0;
  for (int side = -1; side <= 1; side += 2) {
    std::size_t nb = n;
    if (!open_face(grid, labels, i, j, k, d, side, &nb)) continue;
    const int q = side > 0;
    m[q] = nb;
    double w = 0.0, s = 1.0;
    bool plain = false;
    if (!gradient_face(labels, theta, n, nb, &w, &s, &plain)) continue;
    c[q] = plain ? 1.0 / s : w;
    den += plain ? 1.0 : w * s;
  }
  if (!(den > 0.0)) {
    c[0] = c[1] = 0.0;
    return true;
  }
  c[0] /= den;
  c[1] /= den;
  return true;
}

void correct_velocity(const LocalGrid &grid, const NodeLabels &labels, const double *grad,
                      const double *inv_rho, double dt, double *u) {
  grid.for_owned([&](int, int, int, std::size_t n) {
    if (labels.kind[n] == kSolid) return;
    for (int d = 0; d < 3; ++d) u[3 * n + d] -= dt * inv_rho[n] * grad[3 * n + d];
  });
}

}  // namespace mpm
