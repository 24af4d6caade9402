#include "mpm/boundaries.h"

#include <algorithm>
#include <cmath>

#include "mpm/grid_fields.h"
#include "mpm/shape_functions.h"

namespace mpm {

void Boundaries::walls_moved() {
  if (!walls_) return;
  ++epoch_;
  cache_.clear();
  if (stamp_.size() != grid_->size()) {
    stamp_.assign(grid_->size(), -1);
    first_.assign(grid_->size(), 0);
    count_.assign(grid_->size(), 0);
    near_.assign(grid_->size(), 1);
  }
}

void Boundaries::apply(double *vel, int i, int j, int k, double h, double m) {
  const GridSpec &gs = opt_->grid;
  const int idx[3] = {i, j, k};
  for (int d = 0; d < 3; ++d) {
    if (gs.periodic[d]) continue;
    int fc = -1;
    if (idx[d] <= 0)
      fc = 2 * d;
    else if (idx[d] >= gs.ncell[d])
      fc = 2 * d + 1;
    if (fc < 0) continue;
    // normal component: no penetration; tangential: keep (1 - sticky) of it, or for a shear
    // face the exact decay over h under the wall stress mu v_t / delta on the fluid within a cell
    // of the face, rate nu / (delta dx) (as mesh_wall ... shear, docs/theory/mesh_walls.md)
    const Face &f = opt_->face[fc];
    // outflow: no velocity condition (zero normal gradient; the projection holds p = 0 there);
    // inflow: the inflow's velocity, normal to the face, no tangential component
    if (f.kind == BcKind::Outflow) continue;
    if (f.kind == BcKind::Inflow) {
      for (int e = 0; e < 3; ++e) vel[e] = (e == d) ? opt_->face_velocity(fc) : 0.0;
      continue;
    }
    const double keep = f.kind == BcKind::Shear
                            ? wall_slip_decay(wall_layer_rate(opt_->viscosity / opt_->eos.rho0, f.delta, gs.dx), h)
                            : 1.0 - f.sticky;
    for (int e = 0; e < 3; ++e) vel[e] = (e == d) ? 0.0 : keep * vel[e];
  }
  if (walls_) {
    // The triangles near a node and the closest points do not change between two wall moves (one
    // per fluid step): the grid update and the MUSL remap, and every sub-step, reuse the node's
    // constraints (node_walls).
    const std::size_t n = node_walls(i, j, k);
    if (rec_on_ && m > 0.0 && count_[n] > 0) {
      // one condition at a time, each one's change of momentum to its wall
      const double xn[3] = {gs.origin[0] + i * gs.dx, gs.origin[1] + j * gs.dx, gs.origin[2] + k * gs.dx};
      for (int c = 0; c < count_[n]; ++c) {
        const WallConstraint &wc = cache_[first_[n] + c];
        const double v0[3] = {vel[0], vel[1], vel[2]};
        WallGeometry::impose(&wc, 1, vel, h);
        const double ms = m * rec_s_;
        const double J[3] = {ms * (vel[0] - v0[0]), ms * (vel[1] - v0[1]), ms * (vel[2] - v0[2])};
        add_impulse(wc.wall, xn, J);
      }
    } else {
      WallGeometry::impose(cache_.data() + first_[n], count_[n], vel, h);
    }
  }
  const Gate &g = opt_->gate;
  if (g.active) {
    const int d = g.dim;
    const double xn = gs.origin[d] + idx[d] * gs.dx;
    if (g.fluid_below && xn >= g.pos - 1e-9 * gs.dx) vel[d] = std::min(vel[d], 0.0);
    if (!g.fluid_below && xn <= g.pos + 1e-9 * gs.dx) vel[d] = std::max(vel[d], 0.0);
  }
}

/* The mesh-wall constraints of node (i, j, k) (in the patch) for the wall positions of the last
   move, collected at the node's first use after it, and near_[n] = some triangle within 2 cells of
   the node. Returns the flat index. */
std::size_t Boundaries::node_walls(int i, int j, int k) {
  const std::size_t n = grid_->index(i, j, k);
  if (stamp_[n] != epoch_) {
    const GridSpec &gs = opt_->grid;
    const double xn[3] = {gs.origin[0] + i * gs.dx, gs.origin[1] + j * gs.dx, gs.origin[2] + k * gs.dx};
    WallConstraint c[WallGeometry::kMaxConstraints];
    bool near = true;
    const int nc = walls_->collect(xn, 1.0 * gs.dx, 2.0 * gs.dx, c, &near);
    stamp_[n] = epoch_;
    first_[n] = static_cast<int>(cache_.size());
    count_[n] = nc;
    near_[n] = near ? 1 : 0;
    cache_.insert(cache_.end(), c, c + nc);
  }
  return n;
}

/* False if no triangle comes within 2 cells of the node nearest to x, which then lies more than
   1.1 cells from every wall: no wall traction (reach 1 cell) and, for a point that moved less than
   half a cell (the acoustic limit), no crossing to undo. True if unsure (outside the patch). */
bool Boundaries::near_wall(const double *x) {
  const GridSpec &gs = opt_->grid;
  int c[3];
  for (int d = 0; d < 3; ++d) c[d] = static_cast<int>(std::floor((x[d] - gs.origin[d]) / gs.dx + 0.5));
  if (!grid_->in_patch(c[0], c[1], c[2])) return true;
  return near_[node_walls(c[0], c[1], c[2])] != 0;
}

/* Wall traction, the boundary term (8-23) f_j = int_wall S_j sigma n ds, for the quadratic
   B-spline. Its shape function of the first node inside a wall is 1/8 on the wall, so that node
   must carry 1/8 of the wall's pressure push; the internal force (8-24) alone pulls it towards the
   wall by exactly that much (in a uniformly pressurised box the fluid would be drawn to the
   walls). The wall and padding nodes get their share from the velocity condition anyway.
   Quadrature: the points of the cell next to the wall, each standing for the wall area V_p / dx,
   with their in-plane weights. */
void Boundaries::add_face_traction(const Stencil &ps, const double *xp, double V, double p, double *p2g) {
  const GridSpec &gs = opt_->grid;
  const double inv = 1.0 / gs.dx;
  const std::size_t stride[3] = {1, grid_->stride_y(), grid_->stride_z()};
  for (int d = 0; d < 3; ++d) {
    // A dimension one cell wide (the slab of a 2-D run) has no node inside its walls: both are
    // face nodes, whose velocity along d the wall condition sets to 0 whatever force they get.
    if (gs.periodic[d] || gs.ncell[d] < 2) continue;
    const double xi = (xp[d] - gs.origin[d]) * inv;
    int node, dir;
    if (xi < 1.0) {
      node = 1;
      dir = 1;  // the low wall pushes towards +d
    } else if (xi > gs.ncell[d] - 1.0) {
      node = gs.ncell[d] - 1;
      dir = -1;
    } else
      continue;
    const int e = (d + 1) % 3, f = (d + 2) % 3;
    const double push = face_traction_push(dir, p, V, inv);
    // the node's flat index from the stencil's: node - base along d, the stencil's planes along
    // e and f (those with weight exactly 0, as for_stencil leaves out, would add only zeros)
    const std::size_t row = ps.n0 + static_cast<std::size_t>(node - ps.base[d]) * stride[d];
    for (int b = 0; b < 3; ++b) {
      if (ps.w[e][b] == 0.0) continue;
      for (int c = 0; c < 3; ++c) {
        if (ps.w[f][c] == 0.0) continue;
        p2g[P2gRec::N * (row + b * stride[e] + c * stride[f]) + P2gRec::F + d] += push * ps.w[e][b] * ps.w[f][c];
      }
    }
  }
}

/* The same boundary term (8-23) at mesh walls: a point closer than one cell to a triangle face
   stands for the wall area V_p / dx at its nearest point q on the face (the points of the layer
   next to the wall tile it), and the wall pushes the fluid with p V_p / dx along the face normal
   towards the fluid, shared among the nodes by their weights at q. Nodes behind the wall take
   their share out again through the velocity condition; the nodes in front get the push that the
   internal force (8-24) alone lacks there (without it a curved mesh wall draws the fluid in:
   docs/theory/mesh_walls.md). */
void Boundaries::add_mesh_traction(const double *xp, double V, double p, double *p2g) {
  const GridSpec &gs = opt_->grid;
  double q[3], nrm[3];
  int wall = -1;
  if (p == 0.0 || !near_wall(xp) || !walls_->nearest_face(xp, gs.dx, q, nrm, &wall)) return;
  const double inv = 1.0 / gs.dx;
  const IndexBox &pb = grid_->patch();
  int base[3];
  double w[3][3];
  for (int d = 0; d < 3; ++d) {
    double xi = (q[d] - gs.origin[d]) * inv;
    if (!gs.periodic[d]) xi = std::min(std::max(xi, 0.0), static_cast<double>(gs.ncell[d]));
    Shape1D sh;
    shape_eval(opt_->shape, xi, sh);
    if (sh.base < pb.lo[d] || sh.base + 2 > pb.hi[d]) return;
    base[d] = sh.base;
    for (int a = 0; a < 3; ++a) w[d][a] = sh.w[a];
  }
  const double push = p * V * inv;
  if (rec_on_) {
    const double J[3] = {rec_h_ * push * nrm[0], rec_h_ * push * nrm[1], rec_h_ * push * nrm[2]};
    add_impulse(wall, q, J);
  }
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b)
      for (int a = 0; a < 3; ++a) {
        const double wt = push * w[0][a] * w[1][b] * w[2][c];
        double *g = &p2g[P2gRec::N * grid_->index(base[0] + a, base[1] + b, base[2] + c) + P2gRec::F];
        for (int d = 0; d < 3; ++d) g[d] += wt * nrm[d];
      }
}

int Boundaries::put_back(double x[3], double v[3], const double xold[3], double m, bool *gone) {
  const GridSpec &gs = opt_->grid;
  const double eps = 1e-6 * gs.dx;
  int n = 0;
  if (gone) *gone = false;
  if (walls_ && near_wall(x)) {
    const double v0[3] = {v[0], v[1], v[2]};
    int wall = -1;
    if (walls_->push_back(x, v, 1.0 * gs.dx, xold, &wall)) {
      ++n;
      if (rec_on_ && m > 0.0) {
        const double J[3] = {m * (v[0] - v0[0]), m * (v[1] - v0[1]), m * (v[2] - v0[2])};
        add_impulse(wall, x, J);
      }
    }
  }
  for (int d = 0; d < 3; ++d) {
    if (gs.periodic[d]) continue;
    const double lo = gs.origin[d], hi = gs.upper(d);
    if (x[d] < lo || x[d] > hi) {
      if (x[d] < lo - gs.dx || x[d] > hi + gs.dx) continue;  // the shape functions report it
      const bool out = opt_->face[2 * d + (x[d] < lo ? 0 : 1)].kind == BcKind::Outflow;
      x[d] = x[d] < lo ? lo + eps : hi - eps;
      v[d] = 0.0;
      // through an outflow face: the point has left (the caller removes it), not put back
      if (out && gone) {
        *gone = true;
        continue;
      }
      ++n;
    }
  }
  const Gate &g = opt_->gate;
  if (g.active) {
    const int d = g.dim;
    if (g.fluid_below && x[d] > g.pos) {
      x[d] = g.pos - eps;
      v[d] = std::min(v[d], 0.0);
      ++n;
    } else if (!g.fluid_below && x[d] < g.pos) {
      x[d] = g.pos + eps;
      v[d] = std::max(v[d], 0.0);
      ++n;
    }
  }
  return n;
}

void Boundaries::record_loads(double h) {
  const int nw = walls_ ? walls_->walls() : 0;
  if (rec_.size() != 6 * static_cast<std::size_t>(nw)) rec_.assign(6 * static_cast<std::size_t>(nw), 0.0);
  rec_on_ = nw > 0;
  rec_h_ = h;
  rec_s_ = 1.0 + h * opt_->damping;
}

void Boundaries::add_impulse(int k, const double *x, const double *J) {
  if (k < 0 || !walls_->wall(k).loads) return;
  const double *ref = walls_->wall(k).ref;
  const double r[3] = {x[0] - ref[0], x[1] - ref[1], x[2] - ref[2]};
  double *o = &rec_[6 * static_cast<std::size_t>(k)];
  o[0] += J[0];
  o[1] += J[1];
  o[2] += J[2];
  o[3] += r[1] * J[2] - r[2] * J[1];
  o[4] += r[2] * J[0] - r[0] * J[2];
  o[5] += r[0] * J[1] - r[1] * J[0];
}

int Boundaries::line_wall(int i, int j, int k, const double x[3], int d, double sign) {
  if (!walls_) return -1;
  const std::size_t n = grid_->index(i, j, k);
  if (ln_stamp_.size() != 3 * grid_->size()) {
    ln_stamp_.assign(3 * grid_->size(), -1);
    ln_.assign(6 * grid_->size(), -1);
    lt_.assign(6 * grid_->size(), 0.0);
  }
  const std::size_t c = 3 * n + d;
  if (ln_stamp_[c] != epoch_) {
    const GridSpec &gs = opt_->grid;
    for (int s = 0; s < 2; ++s) {
      const int side = s ? 1 : -1;
      // the grid face along the ray (none along a periodic d)
      double face = HUGE_VAL;
      if (!gs.periodic[d]) face = side > 0 ? gs.upper(d) - x[d] : x[d] - gs.origin[d];
      const double len = std::isfinite(face) ? std::max(face, 0.0) + gs.dx : (gs.ncell[d] + 1.0) * gs.dx;
      double t = len;
      int w = walls_->ray_wall(x, d, side, len, &t);
      if (w >= 0 && !(t <= face)) w = -1, t = face;
      if (w < 0) t = face;
      ln_[2 * c + s] = w;
      lt_[2 * c + s] = t;
    }
    ln_stamp_[c] = epoch_;
  }
  const double tl = lt_[2 * c], th = lt_[2 * c + 1];
  // nearer side; on a tie the side the impulse points away from (sign > 0: the wall below)
  const bool low = tl < th || (tl == th && sign > 0.0);
  return ln_[2 * c + (low ? 0 : 1)];
}

void Boundaries::take_loads(std::vector<double> &out) {
  if (out.size() < rec_.size()) out.resize(rec_.size(), 0.0);
  for (std::size_t c = 0; c < rec_.size(); ++c) {
    out[c] += rec_[c];
    rec_[c] = 0.0;
  }
}

}  // namespace mpm
