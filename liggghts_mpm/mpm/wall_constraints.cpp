// Fluid wall conditions on triangle walls: the conditions at the grid nodes (collect, impose,
// nearest_face) and the push-back of the material points; the geometry queries are in
// wall_geometry.cpp. See wall_geometry.h and docs/theory/mesh_walls.md.
#include "mpm/wall_geometry.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cstring>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "mpm/wall_tri_ops.h"

namespace mpm {

namespace {

using geom::dot3;
using geom::sub3;
using wall_tri::beyond_box;
using wall_tri::set_normal_part;
using wall_tri::smooth_normal_speed;
using wall_tri::wall_velocity;

// Relative velocity r = v - w: normal part along unit n -> max(0, r.n) (fluid side) or 0 (behind).
// Tangential part: v_t -> target w_t + keep (v_t - target w_t), with
//   noslip / freeslip / partial f: target 1, keep 1 - f (0, 1, 1 - f);
//   sticky f (imposed): target f, keep 0: the tangential velocity becomes f times the wall's (the
//     text's "50 % sticky wall" of C4), whatever it was;
//   shear delta f: target f, keep exp(-rate h): the exact solution over h of
//     dv_t/dt = -rate (v_t - f w_t), the wall shear stress mu (f w_t - v_t) / delta acting on the
//     fluid within 'reach' of the wall, rate = nu / (delta reach) (docs/theory/mesh_walls.md).
inline void constrain(double v[3], const WallConstraint &c, double h) {
  double r[3];
  sub3(v, c.w, r);
  const double rn = dot3(r, c.n);
  const double rn_new = c.behind ? 0.0 : std::max(0.0, rn);
  const double wn = dot3(c.w, c.n), vn = dot3(v, c.n);
  double keep = 1.0 - c.sticky, target = 1.0;
  if (c.imposed) {
    keep = 0.0;
    target = c.sticky;
  } else if (c.rate > 0.0) {
    keep = wall_slip_decay(c.rate, h);
    target = c.sticky;
  }
  for (int d = 0; d < 3; ++d) {
    const double wt = c.w[d] - wn * c.n[d], vt = v[d] - vn * c.n[d];
    v[d] = (wn + rn_new) * c.n[d] + target * wt + keep * (vt - target * wt);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Grid nodes

bool WallGeometry::apply(const double x[3], double vel[3], double reach_fluid, double reach_behind,
                      double h) const {
  WallConstraint c[kMaxConstraints];
  const int nc = collect(x, reach_fluid, reach_behind, c);
  impose(c, nc, vel, h);
  return nc > 0;
}

void WallGeometry::impose(const WallConstraint *c, int nc, double vel[3], double h) {
  for (int k = 0; k < nc; ++k) constrain(vel, c[k], h);
}

int WallGeometry::collect(const double x[3], double reach_fluid, double reach_behind, WallConstraint *out,
                       bool *near) const {
  if (near) *near = false;
  if (tris_.empty()) return 0;
  if (reach_behind < 0.0) reach_behind = reach_fluid;
  const double reach = std::max(reach_fluid, reach_behind);
  const std::vector<int> *cand = reach <= margin_ ? candidates(x) : nullptr;
  const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
  const double r2 = reach * reach, rf2 = reach_fluid * reach_fluid, rb2 = reach_behind * reach_behind;
  std::pair<double, int> cl[kCand];
  const int ncl = nearest_candidates(x, reach, cand, ncand, cl);
  if (near) *near = ncl > 0 || !cand;
  if (ncl == 0) return 0;
  KeptHits kept;
  keep_hits(x, reach, r2, cl, ncl, kept);
  if (kept.nh == 0) return 0;
  return constraints(kept, reach, reach_fluid, rf2, rb2, out);
}

// Candidates by a lower bound of their distance (plane, bounding box), nearest first. One wall direction is one
// constraint: of the hits of a mesh whose directions (face normal, or the direction from an
// edge/vertex) lie within 30 degrees of each other only the nearest is kept. A finely
// tessellated curved wall (a jar) thus constrains a node once, along its nearest facet, and not
// dozens of times along normals up to tens of degrees off (which would also take away the
// tangential velocity that a free-slip or partial wall keeps); distinct walls meeting at an
// edge or corner (a box) still act together. A candidate whose plane is farther than a kept
// hit of a similar direction cannot be nearer, so its closest point is not computed.
int WallGeometry::nearest_candidates(const double x[3], double reach, const std::vector<int> *cand, int ncand,
                                     std::pair<double, int> *cl) const {
  int ncl = 0;
  for (int c = 0; c < ncand && ncl < kCand; ++c) {
    const int i = cand ? (*cand)[c] : c;
    const Tri &t = tris_[i];
    if (beyond_box(t, x, reach)) continue;
    // lower bound of the distance: to the plane and to the bounding box
    double a[3], bd2 = 0.0;
    sub3(x, t.p[0], a);
    const double pd = std::fabs(dot3(a, t.n));
    for (int q = 0; q < 3; ++q) {
      const double e = std::max({t.lo[q] - x[q], 0.0, x[q] - t.hi[q]});
      bd2 += e * e;
    }
    const double lb = std::max(pd, std::sqrt(bd2));
    if (lb > reach) continue;
    cl[ncl++] = {lb, i};
  }
  std::sort(cl, cl + ncl);
  return ncl;
}

// collect's hits at x of the candidates cl (nearest first): one per wall direction of a mesh.
void WallGeometry::keep_hits(const double x[3], double reach, double r2, const std::pair<double, int> *cl, int ncl,
                             KeptHits &kept) const {
  int *const idx = kept.idx;
  Hit *const hits = kept.hits;
  double(*const dd)[3] = kept.dd;
  double(*const dir)[3] = kept.dir;
  bool *const back = kept.back;
  int &nh = kept.nh;
  for (int c = 0; c < ncl; ++c) {
    const int i = cl[c].second;
    const Tri &t = tris_[i];
    // a kept hit of a similar direction that is nearer than this triangle can be makes it
    // redundant (a face hit also when equally near: a coplanar neighbour adds nothing)
    bool skip = false;
    const double lb2 = cl[c].first * cl[c].first;
    for (int h = 0; h < nh && !skip; ++h)
      skip = tris_[idx[h]].mesh == t.mesh && std::fabs(dot3(dir[h], t.n)) > kCos &&
             (hits[h].face ? hits[h].dist2 <= lb2 + 1e-12 * r2 : hits[h].dist2 + 1e-12 * r2 < lb2);
    if (skip) continue;
    Hit hit;
    closest_point(t, x, hit);
    if (hit.dist2 > r2) continue;
    double dv[3], dn[3];
    sub3(x, hit.p, dv);
    const double dl = std::sqrt(hit.dist2);
    if (hit.face || dl <= 1e-12 * reach) {
      for (int q = 0; q < 3; ++q) dn[q] = t.n[q];
    } else {
      for (int q = 0; q < 3; ++q) dn[q] = dv[q] / dl;
    }
    const int side = walls_[t.mesh].side;
    const bool one_sided = side == SIDE_NORMAL || side == SIDE_OPPOSITE;
    const bool is_back = one_sided && side * dot3(dv, t.n) < 0.0;
    int slot = nh;
    for (int h = 0; h < nh; ++h)
      if (tris_[idx[h]].mesh == t.mesh && std::fabs(dot3(dir[h], dn)) > kCos) {
        if (std::fabs(hit.dist2 - hits[h].dist2) <= 1e-12 * r2) {
          // the same nearest point seen from another triangle: a face hit takes precedence
          // over edge/vertex hits; of those, the node is behind only if behind all of them
          if (hit.face && !hits[h].face) {
            slot = h;
          } else {
            if (hit.face == hits[h].face) back[h] = back[h] && is_back;
            slot = -1;
          }
        } else {
          slot = hit.dist2 < hits[h].dist2 ? h : -1;  // nearer: replaces it; else redundant
        }
        break;
      }
    if (slot < 0 || slot >= kMax) continue;
    hits[slot] = hit;
    for (int q = 0; q < 3; ++q) {
      dd[slot][q] = dv[q];
      dir[slot][q] = dn[q];
    }
    back[slot] = is_back;
    idx[slot] = i;
    if (slot == nh) ++nh;
  }
}

namespace {
// The smooth surface's normal at barycentric weights b of triangle t (its corner normals
// interpolated), oriented as n: in n if it lies within kSmoothCos of n (an edge between facets of
// one smooth surface, seen from a node near it), and true; else n is left (a real edge).
bool smooth_normal(const WallGeometry::Tri &t, const double b[3], double n[3]) {
  double s[3];
  for (int q = 0; q < 3; ++q) s[q] = b[0] * t.cn[0][q] + b[1] * t.cn[1][q] + b[2] * t.cn[2][q];
  const double len = std::sqrt(dot3(s, s));
  if (!(len > 0.0)) return false;
  double c = dot3(s, n) / len;
  const double sg = c < 0.0 ? -1.0 : 1.0;
  if (sg * c < WallGeometry::kSmoothCos) return false;
  for (int q = 0; q < 3; ++q) n[q] = sg * s[q] / len;
  return true;
}
}  // namespace

// collect's constraints from the kept hits (at most kMaxConstraints in out); returns their number.
int WallGeometry::constraints(const KeptHits &kept, double reach, double reach_fluid, double rf2, double rb2,
                              WallConstraint *out) const {
  const int *const idx = kept.idx;
  const Hit *const hits = kept.hits;
  const double(*const dd)[3] = kept.dd;
  const bool *const back = kept.back;
  const int nh = kept.nh;
  int nout = 0;
  for (size_t k = 0; k < walls_.size(); ++k) {
    // Face-region hits of a mesh take precedence over its edge/vertex hits, so that the internal
    // edges of a flat or gently curved wall add no constraint. A node near edges/vertices only is
    // behind the mesh if it is behind the planes of all those triangles (outside a closed box's
    // edge or corner); else it faces a rounded edge. Of edge/vertex hits only the nearest one acts:
    // the others are farther points of the same surface (beyond a jar's rim, the vertices of its
    // end cap along the rim, at directions tens of degrees apart, which together imposed the whole
    // wall velocity of a turning jar on the node).
    bool any_face = false, any = false, all_back = true;
    int nearest = -1;
    for (int h = 0; h < nh; ++h) {
      if (tris_[idx[h]].mesh != static_cast<int>(k)) continue;
      any = true;
      if (hits[h].face) any_face = true;
      if (nearest < 0 || hits[h].dist2 < hits[nearest].dist2) nearest = h;
    }
    if (!any) continue;
    if (!any_face)
      for (int h = 0; h < nh; ++h)
        if (tris_[idx[h]].mesh == static_cast<int>(k) && !back[h]) all_back = false;
    const int side = walls_[k].side;
    const double sticky = walls_[k].sticky;
    for (int h = 0; h < nh; ++h) {
      const Tri &t = tris_[idx[h]];
      if (t.mesh != static_cast<int>(k) || hits[h].face != any_face) continue;
      if (!any_face && h != nearest) continue;
      double n[3];
      bool behind, smooth_edge = false;
      if (any_face) {
        double sg;
        if (side == SIDE_NORMAL) sg = 1.0;
        else if (side == SIDE_OPPOSITE) sg = -1.0;
        else sg = dot3(dd[h], t.n) >= 0.0 ? 1.0 : -1.0;  // both sides (or side not decided yet)
        for (int q = 0; q < 3; ++q) n[q] = sg * t.n[q];
        behind = back[h];
        // a node in the plane of a two-sided wall is inside the wall: no normal motion either way
        if (side != SIDE_NORMAL && side != SIDE_OPPOSITE && hits[h].dist2 <= 1e-18 * reach * reach)
          behind = true;
      } else {
        const double dl = std::sqrt(hits[h].dist2);
        if (dl <= 1e-12 * reach) continue;
        behind = all_back;
        // normal from the edge towards the fluid
        const double f = behind ? -1.0 / dl : 1.0 / dl;
        for (int q = 0; q < 3; ++q) n[q] = f * dd[h][q];
        smooth_edge = t.smooth && smooth_normal(t, hits[h].b, n);
      }
      // strictly within the reach: a node exactly one cell from a wall (a wall on a lattice plane)
      // gets no condition, whatever the rounding of its distance. Decided by the rounding, one of
      // two parallel walls 4 cells apart held its nodes one cell off and the other not; the
      // one-sided condition there pumped the water away from it (water released in a closed mesh
      // box 4 cells wide: its centre moved 2.7 mm across in 0.6 s, 0.4 mm with the strict reach;
      // in the drum of inputs/drum the beads went with the water, docs/validation/drum.md)
      if (hits[h].dist2 > (behind ? rb2 : rf2) * (1.0 - 1e-9)) continue;
      if (nout >= kMaxConstraints) continue;
      WallConstraint &o = out[nout++];
      wall_velocity(t, hits[h].b, o.w);
      // at an edge of a smooth surface: its normal there, and its normal speed along it
      if (smooth_edge) set_normal_part(o.w, n, smooth_normal_speed(t, hits[h].b));
      for (int q = 0; q < 3; ++q) o.n[q] = n[q];
      o.sticky = sticky;
      o.rate = walls_[k].kind == WALL_SHEAR ? wall_layer_rate(nu_, layer_thickness(static_cast<int>(k)), reach_fluid) : 0.0;
      o.behind = behind;
      o.imposed = walls_[k].kind == WALL_STICKY;
      o.wall = static_cast<int>(k);
    }
  }
  return nout;
}

bool WallGeometry::nearest_face(const double x[3], double reach, double q[3], double n[3], int *wall) const {
  if (tris_.empty()) return false;
  const std::vector<int> *cand = reach <= margin_ ? candidates(x) : nullptr;
  const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
  double best = reach * reach;
  int bi = -1;
  Hit bh;
  for (int c = 0; c < ncand; ++c) {
    const int i = cand ? (*cand)[c] : c;
    const Tri &t = tris_[i];
    if (beyond_box(t, x, reach)) continue;
    double a[3];
    sub3(x, t.p[0], a);
    const double pd = dot3(a, t.n);
    if (pd * pd >= best) continue;  // its plane is farther than the best hit
    Hit h;
    closest_point(t, x, h);
    if (h.dist2 >= best) continue;
    best = h.dist2;
    bi = i;
    bh = h;
  }
  if (bi < 0 || !bh.face) return false;
  const Tri &t = tris_[bi];
  double d[3];
  sub3(x, bh.p, d);
  const double s = dot3(d, t.n);
  const int side = walls_[t.mesh].side;
  double sg;
  if (side == SIDE_NORMAL || side == SIDE_OPPOSITE) {
    sg = side;
    if (sg * s < 0.0) return false;  // behind a one-sided wall
  } else {
    sg = s >= 0.0 ? 1.0 : -1.0;
  }
  for (int k = 0; k < 3; ++k) {
    q[k] = bh.p[k];
    n[k] = sg * t.n[k];
  }
  if (wall) *wall = t.mesh;
  return true;
}

int WallGeometry::nearest_wall(const double x[3], double reach, double *dist) const {
  *dist = reach;
  if (tris_.empty()) return -1;
  const std::vector<int> *cand = reach <= margin_ ? candidates(x) : nullptr;
  const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
  double best = reach * reach;
  int bw = -1;
  for (int c = 0; c < ncand; ++c) {
    const Tri &t = tris_[cand ? (*cand)[c] : c];
    if (beyond_box(t, x, reach)) continue;
    double a[3];
    sub3(x, t.p[0], a);
    const double pd = dot3(a, t.n);
    if (pd * pd >= best) continue;
    Hit h;
    closest_point(t, x, h);
    if (h.dist2 >= best) continue;
    best = h.dist2;
    bw = t.mesh;
  }
  if (bw >= 0) *dist = std::sqrt(best);
  return bw;
}

int WallGeometry::ray_wall(const double x[3], int d, int side, double len, double *t) const {
  int bw = -1;
  double best = len;
  for (const Tri &tr : tris_) {
    if (tr.n[d] == 0.0) continue;
    // box test across the ray
    bool out = false;
    for (int e = 0; e < 3 && !out; ++e)
      if (e != d) out = x[e] < tr.lo[e] - 1e-12 * len || x[e] > tr.hi[e] + 1e-12 * len;
    if (out) continue;
    double a[3];
    sub3(tr.p[0], x, a);
    const double s = side * dot3(a, tr.n) / tr.n[d];  // distance along the ray to the plane
    if (!(s >= -1e-12 * len) || s >= best) continue;
    double y[3] = {x[0], x[1], x[2]};
    y[d] += side * s;
    Hit h;
    closest_point(tr, y, h);
    if (h.dist2 > 1e-18 * len * len) continue;
    best = s;
    bw = tr.mesh;
  }
  *t = best;
  return bw;
}

// ---------------------------------------------------------------------------------------------
// Material points

bool WallGeometry::push_back(double x[3], double v[3], double reach, const double *x_old, int *wall) const {
  if (tris_.empty()) return false;
  const double off = 1e-3 * reach;
  bool moved = false;

  // (a) crossings of the segment x_old -> x
  if (x_old) {
    for (int iter = 0; iter < 4; ++iter) {
      if (!push_across(x, v, x_old, off, wall)) break;
      moved = true;
    }
  }

  // (b) one-sided meshes: a point behind the mesh (push_from_behind)
  for (int iter = 0; iter < 4; ++iter) {
    if (!push_from_behind(x, v, reach, off, wall)) break;
    moved = true;
  }
  return moved;
}

// push_back (a), one crossing: the first crossing of the segment x_old -> x from the fluid side
// of a triangle; x goes back to the fluid side, 'off' from the plane, and v loses its normal
// velocity relative to the wall. Returns false if there is none.
bool WallGeometry::push_across(double x[3], double v[3], const double *x_old, double off, int *wall) const {
  double seg[3];
  sub3(x, x_old, seg);
  const double len = std::sqrt(dot3(seg, seg));
  if (len == 0.0) return false;
  const std::vector<int> *cand = (len <= margin_) ? candidates(x) : nullptr;
  const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
  double best = 2.0, bq[3] = {0, 0, 0}, bn[3] = {0, 0, 0}, bb[3] = {0, 0, 0};
  int bi = -1;
  for (int c = 0; c < ncand; ++c) {
    const int i = cand ? (*cand)[c] : c;
    const Tri &t = tris_[i];
    bool out = false;
    for (int d = 0; d < 3 && !out; ++d)
      out = std::max(x[d], x_old[d]) < t.lo[d] || std::min(x[d], x_old[d]) > t.hi[d];
    if (out) continue;
    double a0[3], a1[3];
    sub3(x_old, t.p[0], a0);
    sub3(x, t.p[0], a1);
    const double sa = dot3(a0, t.n), sb = dot3(a1, t.n);
    const int side = walls_[t.mesh].side;
    double sg;
    if (side == SIDE_NORMAL) sg = 1.0;
    else if (side == SIDE_OPPOSITE) sg = -1.0;
    else if (sa != 0.0) sg = sa > 0.0 ? 1.0 : -1.0;
    else sg = sb >= 0.0 ? 1.0 : -1.0;  // two-sided, starting on the plane: leaving it is fine
    // only a move from the fluid side (or the plane) to the other side counts
    if (!(sg * sa >= 0.0 && sg * sb < 0.0)) continue;
    const double f = sa / (sa - sb);
    if (f >= best) continue;
    double q[3];
    for (int d = 0; d < 3; ++d) q[d] = x_old[d] + f * seg[d];
    Hit h;
    closest_point(t, q, h);
    const double tol = 1e-10 * (len + std::sqrt(dot3(a0, a0)));
    if (h.dist2 > tol * tol) continue;  // q lies outside the triangle
    best = f;
    bi = i;
    for (int d = 0; d < 3; ++d) {
      bq[d] = q[d];
      bn[d] = sg * t.n[d];
      bb[d] = h.b[d];
    }
  }
  if (bi < 0) return false;
  if (wall) *wall = tris_[bi].mesh;
  double w[3];
  wall_velocity(tris_[bi], bb, w);
  // back to the fluid side, 'off' from the plane
  for (int d = 0; d < 3; ++d) x[d] = bq[d] + off * bn[d];
  double r[3];
  sub3(v, w, r);
  const double rn = dot3(r, bn);
  for (int d = 0; d < 3; ++d) v[d] -= rn * bn[d];
  return true;
}

// push_back (b), one step, for one-sided meshes: a point behind the mesh, less than 'reach' deep.
// Behind = behind the planes of all the triangles whose closest point is the nearest one (one
// triangle in its face region, or the triangles sharing the nearest edge or vertex); the point
// goes to the nearest point of the mesh plus 'off' towards the fluid. Returns false if x is not
// behind such a mesh.
bool WallGeometry::push_from_behind(double x[3], double v[3], double reach, double off, int *wall) const {
  const std::vector<int> *cand = reach <= margin_ ? candidates(x) : nullptr;
  const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
  const double r2 = reach * reach;
  // Behind the nearest triangles means behind (or on) their planes, and x - q . n is the plane
  // distance for any point q of a triangle: if x is in front of the plane of every one-sided
  // triangle within reach (inside a closed convex mesh: always), nothing is to be done.
  bool any_behind = false;
  for (int c = 0; c < ncand && !any_behind; ++c) {
    const Tri &t = tris_[cand ? (*cand)[c] : c];
    const int side = walls_[t.mesh].side;
    if (side != SIDE_NORMAL && side != SIDE_OPPOSITE) continue;
    double a[3];
    sub3(x, t.p[0], a);
    const double pd = side * dot3(a, t.n);
    any_behind = pd < 1e-12 * reach && pd > -reach;
  }
  if (!any_behind) return false;
  constexpr int kMax = 64;
  int idx[kMax];
  Hit hits[kMax];
  int nh = 0;
  double dmin = r2;
  for (int c = 0; c < ncand && nh < kMax; ++c) {
    const int i = cand ? (*cand)[c] : c;
    const Tri &t = tris_[i];
    const int side = walls_[t.mesh].side;
    if (side != SIDE_NORMAL && side != SIDE_OPPOSITE) continue;
    if (beyond_box(t, x, reach)) continue;
    double a[3];
    sub3(x, t.p[0], a);
    const double pd = dot3(a, t.n);
    if (pd * pd > dmin + 1e-12 * r2) continue;  // its plane is farther than the nearest hit
    closest_point(t, x, hits[nh]);
    if (hits[nh].dist2 >= r2) continue;
    dmin = std::min(dmin, hits[nh].dist2);
    idx[nh++] = i;
  }
  if (nh == 0) return false;
  const double tie = dmin + 1e-12 * r2;
  bool behind = true;
  int first = -1;
  for (int h = 0; h < nh && behind; ++h) {
    if (hits[h].dist2 > tie) continue;
    const Tri &t = tris_[idx[h]];
    double d[3];
    sub3(x, hits[h].p, d);
    if (walls_[t.mesh].side * dot3(d, t.n) >= 0.0) behind = false;
    if (first < 0) first = h;
  }
  if (!behind || first < 0) return false;
  const Tri &t = tris_[idx[first]];
  const Hit &bh = hits[first];
  if (wall) *wall = t.mesh;
  double d[3], bn[3];
  sub3(x, bh.p, d);
  const double dl = std::sqrt(bh.dist2);
  if (bh.face || dl <= 1e-12 * reach) {
    for (int q = 0; q < 3; ++q) bn[q] = walls_[t.mesh].side * t.n[q];
  } else {
    for (int q = 0; q < 3; ++q) bn[q] = -d[q] / dl;
  }
  double w[3];
  wall_velocity(t, bh.b, w);
  for (int q = 0; q < 3; ++q) x[q] = bh.p[q] + off * bn[q];
  double r[3];
  sub3(v, w, r);
  const double rn = dot3(r, bn);
  for (int q = 0; q < 3; ++q) v[q] -= rn * bn[q];
  return true;
}

}  // namespace mpm
