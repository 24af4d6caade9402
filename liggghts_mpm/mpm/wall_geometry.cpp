// Fluid wall conditions on triangle walls, the geometry alone: the triangles and their bins,
// closest points, crossings, node sides and the rotation fit (the conditions at the nodes and the
// points are in wall_constraints.cpp); see wall_geometry.h and docs/theory/mesh_walls.md.
#include "mpm/wall_geometry.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "mpm/wall_tri_ops.h"

namespace mpm {

namespace {

using geom::dot3;
using geom::sub3;
using wall_tri::beyond_box;
using wall_tri::wall_velocity;

}  // namespace

std::string check_wall(WallSpec &s) {
  switch (s.kind) {
    case WALL_NOSLIP: s.sticky = 1.0; break;
    case WALL_FREESLIP: s.sticky = 0.0; break;
    case WALL_PARTIAL:
    case WALL_STICKY:
    case WALL_SHEAR:
      if (!(s.sticky >= 0.0 && s.sticky <= 1.0)) {
        std::ostringstream m;
        m << "sticky fraction " << s.sticky << " of a partial-slip wall must lie in [0,1]";
        return m.str();
      }
      if (s.kind == WALL_SHEAR && !s.delta_auto && !(s.delta > 0.0 && std::isfinite(s.delta))) {
        std::ostringstream m;
        m << "wall layer thickness " << s.delta << " of a shear wall must be positive";
        return m.str();
      }
      break;
    default:
      return "unknown wall kind " + std::to_string(static_cast<int>(s.kind)) +
             " (0 noslip, 1 freeslip, 2 partial, 3 sticky, 4 shear)";
  }
  if (s.side != SIDE_NORMAL && s.side != SIDE_OPPOSITE && s.side != SIDE_AUTO && s.side != SIDE_BOTH)
    return "unknown fluid side " + std::to_string(s.side);
  return "";
}

WallGeometry::WallGeometry(std::vector<WallSpec> walls) : walls_(std::move(walls)) {
  for (size_t k = 0; k < walls_.size(); ++k) {
    const std::string problem = check_wall(walls_[k]);
    if (!problem.empty()) throw std::invalid_argument("wall " + std::to_string(k) + ": " + problem);
  }
}

// ---------------------------------------------------------------------------------------------
// Triangles and bins

// The same triangle to the bit (positions, velocities, normal, bounds, wall, key).
static bool same_tri(const WallGeometry::Tri &a, const WallGeometry::Tri &b) {
  static_assert(sizeof(a.p) + sizeof(a.w) + sizeof(a.n) + sizeof(a.lo) + sizeof(a.hi) == 27 * sizeof(double),
                "Tri's leading doubles");
  return a.mesh == b.mesh && a.key == b.key && std::memcmp(&a.p[0][0], &b.p[0][0], 27 * sizeof(double)) == 0;
}

bool WallGeometry::set_triangles(std::vector<Tri> tris, const double box[6], double margin) {
  margin = std::max(0.0, margin);
  // A fixed order (mesh, triangle ID, image), whatever the ranks: where triangles with different
  // wall velocities act on one node (a rotating mesh), the last one applied wins, so the result
  // must not depend on the decomposition.
  std::sort(tris.begin(), tris.end(), [](const Tri &a, const Tri &b) {
    return a.mesh != b.mesh ? a.mesh < b.mesh : a.key < b.key;
  });
  if (have_set_ && margin == margin_ && std::memcmp(box, box_, sizeof(box_)) == 0 && tris.size() == tris_.size() &&
      std::equal(tris.begin(), tris.end(), tris_.begin(), same_tri))
    return false;
  have_set_ = true;
  std::memcpy(box_, box, sizeof(box_));
  tris_ = std::move(tris);
  margin_ = margin;
  fit_rotation();
  normal_speeds();

  // bins over my box
  for (int d = 0; d < 3; ++d) {
    blo_[d] = box[d];
    nb_[d] = 0;
  }
  bins_.clear();
  if (box[0] <= box[3] && box[1] <= box[4] && box[2] <= box[5]) bins_build(box);
  return true;
}

namespace {
// the key of a triangle's corner frames: its wall and triangle ID (key / 27: images share it)
long long frame_key(const WallGeometry::Tri &t, int nwalls) {
  return (t.key / 27) * static_cast<long long>(std::max(nwalls, 1)) + t.mesh;
}

// the triangle's own frame: unit normal n, unit first edge e1, e2 = n x e1
void tri_frame(const WallGeometry::Tri &t, double e1[3], double e2[3]) {
  double len = 0.0;
  for (int d = 0; d < 3; ++d) {
    e1[d] = t.p[1][d] - t.p[0][d];
    len += e1[d] * e1[d];
  }
  len = std::sqrt(len);
  for (int d = 0; d < 3; ++d) e1[d] /= len;
  e2[0] = t.n[1] * e1[2] - t.n[2] * e1[1];
  e2[1] = t.n[2] * e1[0] - t.n[0] * e1[2];
  e2[2] = t.n[0] * e1[1] - t.n[1] * e1[0];
}
}  // namespace

void WallGeometry::set_corner_frames(const std::vector<Tri> &all) {
  frames_.clear();
  have_set_ = false;  // the next set_triangles recomputes the normal speeds
  const int nw = walls();
  // the corners at each vertex of each wall (positions to the bit)
  std::map<std::tuple<int, double, double, double>, std::vector<std::pair<int, int>>> at;
  for (int i = 0; i < static_cast<int>(all.size()); ++i)
    for (int c = 0; c < 3; ++c) at[{all[i].mesh, all[i].p[c][0], all[i].p[c][1], all[i].p[c][2]}].push_back({i, c});
  // interior angle of triangle t at corner c
  auto angle = [](const Tri &t, int c) {
    const double *o = t.p[c], *a = t.p[(c + 1) % 3], *b = t.p[(c + 2) % 3];
    double u[3], v[3];
    sub3(a, o, u);
    sub3(b, o, v);
    const double cr[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    return std::atan2(std::sqrt(dot3(cr, cr)), dot3(u, v));
  };
  for (const Tri &t : all) {
    std::array<double, 9> f{};
    bool flat = true;
    double m[3][3];
    for (int c = 0; c < 3; ++c) {
      double s[3] = {0.0, 0.0, 0.0};
      for (const auto &tc : at[{t.mesh, t.p[c][0], t.p[c][1], t.p[c][2]}]) {
        const Tri &u = all[tc.first];
        if (dot3(u.n, t.n) < kSmoothCos) continue;  // a real edge, or the other side of a wall
        const double a = angle(u, tc.second);
        for (int d = 0; d < 3; ++d) s[d] += a * u.n[d];
      }
      const double len = std::sqrt(dot3(s, s));
      for (int d = 0; d < 3; ++d) m[c][d] = len > 0.0 ? s[d] / len : t.n[d];
      double r[3];
      sub3(m[c], t.n, r);
      if (dot3(r, r) > 1e-24) flat = false;
    }
    if (flat) continue;  // the triangle's own normal at every corner: no frame (crosses as before)
    double e1[3], e2[3];
    tri_frame(t, e1, e2);
    for (int c = 0; c < 3; ++c) {
      f[3 * c] = dot3(m[c], t.n);
      f[3 * c + 1] = dot3(m[c], e1);
      f[3 * c + 2] = dot3(m[c], e2);
    }
    frames_[frame_key(t, nw)] = f;
  }
}

// vn and smooth of every triangle of tris_ from frames_ (set_triangles)
void WallGeometry::normal_speeds() {
  const int nw = walls();
  for (Tri &t : tris_) {
    t.smooth = false;
    if (frames_.empty()) continue;
    const auto it = frames_.find(frame_key(t, nw));
    if (it == frames_.end()) continue;
    const std::array<double, 9> &f = it->second;
    double e1[3], e2[3];
    tri_frame(t, e1, e2);
    for (int c = 0; c < 3; ++c) {
      double *m = t.cn[c];
      for (int d = 0; d < 3; ++d) m[d] = f[3 * c] * t.n[d] + f[3 * c + 1] * e1[d] + f[3 * c + 2] * e2[d];
      t.vn[c] = dot3(t.w[c], m);
    }
    t.smooth = true;
  }
}

void WallGeometry::bins_build(const double box[6]) {
  // Bins of edge >= margin (at most ~1e6 of them); a triangle goes into every bin that its
  // bounding box widened by the margin overlaps and whose centre is within (half diagonal +
  // margin) of the triangle. Any triangle within 'margin' of a point of a bin is then in that bin.
  double ext[3], vol = 1.0;
  for (int d = 0; d < 3; ++d) {
    ext[d] = std::max(box[3 + d] - box[d], 1e-300);
    vol *= ext[d];
  }
  bsize_ = std::max({margin_, std::cbrt(vol / 1.0e6), 1e-12 * std::max({ext[0], ext[1], ext[2]})});
  size_t nbin = 1;
  for (int d = 0; d < 3; ++d) {
    blo_[d] = box[d];
    nb_[d] = std::max(1, static_cast<int>(std::ceil(ext[d] / bsize_)));
    nbin *= nb_[d];
  }
  bins_.assign(nbin, {});
  const double half_diag = 0.5 * std::sqrt(3.0) * bsize_;
  for (size_t i = 0; i < tris_.size(); ++i) {
    const Tri &t = tris_[i];
    int lo[3], hi[3];
    bool out = false;
    for (int d = 0; d < 3; ++d) {
      lo[d] = static_cast<int>(std::floor((t.lo[d] - margin_ - blo_[d]) / bsize_));
      hi[d] = static_cast<int>(std::floor((t.hi[d] + margin_ - blo_[d]) / bsize_));
      lo[d] = std::max(lo[d], 0);
      hi[d] = std::min(hi[d], nb_[d] - 1);
      if (lo[d] > hi[d]) out = true;
    }
    if (out) continue;
    int nwide = 0;
    for (int d = 0; d < 3; ++d) nwide += hi[d] - lo[d] >= 3;
    const bool wide = nwide >= 2;
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int ii = lo[0]; ii <= hi[0]; ++ii) {
          const double c[3] = {blo_[0] + (ii + 0.5) * bsize_, blo_[1] + (j + 0.5) * bsize_,
                               blo_[2] + (k + 0.5) * bsize_};
          double d[3];
          sub3(c, t.p[0], d);
          if (std::fabs(dot3(d, t.n)) > half_diag + margin_) continue;
          // a triangle whose bounding box spans many bins in two directions (the fans of a
          // jar's end caps) is far from most of them: keep a bin only if the triangle comes
          // near the bin's ball
          if (wide) {
            Hit hit;
            closest_point(t, c, hit);
            if (hit.dist2 > (half_diag + margin_) * (half_diag + margin_)) continue;
          }
          bins_[(static_cast<size_t>(k) * nb_[1] + j) * nb_[0] + ii].push_back(static_cast<int>(i));
        }
  }
}

const std::vector<int> *WallGeometry::candidates(const double x[3]) const {
  if (bins_.empty() || !use_bins_) return nullptr;
  int c[3];
  for (int d = 0; d < 3; ++d) {
    const double f = (x[d] - blo_[d]) / bsize_;
    if (!(f >= 0.0) || f >= nb_[d]) return nullptr;
    c[d] = static_cast<int>(f);
  }
  return &bins_[(static_cast<size_t>(c[2]) * nb_[1] + c[1]) * nb_[0] + c[0]];
}

// ---------------------------------------------------------------------------------------------
// Geometry


// Closest point of triangle t to x, with barycentric weights; the case analysis over the
// Voronoi regions of the vertices, edges and face of the triangle.
void WallGeometry::closest_point(const Tri &t, const double x[3], Hit &h) {
  const double *a = t.p[0], *b = t.p[1], *c = t.p[2];
  double ab[3], ac[3], ap[3], bp[3], cp[3];
  sub3(b, a, ab);
  sub3(c, a, ac);
  sub3(x, a, ap);
  auto finish = [&](double wa, double wb, double wc, bool face) {
    if (!face) {
      // A point whose projection falls on the triangle's boundary (a grid node on a box edge or
      // on the diagonal of a split face) counts as facing the triangle: project and test the
      // barycentric weights of the projection with a small tolerance.
      const double s = dot3(ap, t.n);
      const double q[3] = {ap[0] - s * t.n[0], ap[1] - s * t.n[1], ap[2] - s * t.n[2]};
      const double d00 = dot3(ab, ab), d01 = dot3(ab, ac), d11 = dot3(ac, ac);
      const double d20 = dot3(q, ab), d21 = dot3(q, ac);
      const double den = d00 * d11 - d01 * d01;
      if (den > 0.0) {
        const double bv = (d11 * d20 - d01 * d21) / den, bw = (d00 * d21 - d01 * d20) / den;
        const double bu = 1.0 - bv - bw;
        const double tol = 1e-9;
        if (bu >= -tol && bv >= -tol && bw >= -tol) {
          wa = std::max(0.0, bu);
          wb = std::max(0.0, bv);
          wc = std::max(0.0, bw);
          const double sum = wa + wb + wc;
          wa /= sum;
          wb /= sum;
          wc /= sum;
          face = true;
        }
      }
    }
    h.b[0] = wa;
    h.b[1] = wb;
    h.b[2] = wc;
    h.face = face;
    double dd = 0.0;
    for (int d = 0; d < 3; ++d) {
      h.p[d] = wa * a[d] + wb * b[d] + wc * c[d];
      dd += (x[d] - h.p[d]) * (x[d] - h.p[d]);
    }
    h.dist2 = dd;
  };
  const double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return finish(1, 0, 0, false);
  sub3(x, b, bp);
  const double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return finish(0, 1, 0, false);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double s = d1 / (d1 - d3);
    return finish(1 - s, s, 0, false);
  }
  sub3(x, c, cp);
  const double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return finish(0, 0, 1, false);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double s = d2 / (d2 - d6);
    return finish(1 - s, 0, s, false);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return finish(0, 1 - s, s, false);
  }
  const double inv = 1.0 / (va + vb + vc);
  const double sb = vb * inv, sc = vc * inv;
  finish(1 - sb - sc, sb, sc, true);
}

// ---------------------------------------------------------------------------------------------
// Fluid side from the points

void WallGeometry::side_votes(const double *const *x, int n, double reach, long *votes) const {
  const size_t nm = walls_.size();
  for (int i = 0; i < n; ++i) {
    const double *xi = x[i];
    const std::vector<int> *cand = reach <= margin_ ? candidates(xi) : nullptr;
    const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
    std::vector<double> best(nm, reach * reach);
    std::vector<int> vote(nm, 0);
    for (int c = 0; c < ncand; ++c) {
      const Tri &t = tris_[cand ? (*cand)[c] : c];
      if (walls_[t.mesh].side == SIDE_BOTH) continue;
      Hit h;
      closest_point(t, xi, h);
      if (!h.face || h.dist2 > best[t.mesh]) continue;
      double d[3];
      sub3(xi, h.p, d);
      const double s = dot3(d, t.n);
      if (s == 0.0) continue;
      best[t.mesh] = h.dist2;
      vote[t.mesh] = s > 0.0 ? 1 : -1;
    }
    for (size_t k = 0; k < nm; ++k) {
      if (vote[k] > 0) ++votes[2 * k];
      if (vote[k] < 0) ++votes[2 * k + 1];
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The pressure projection: closed grid faces and the nodes behind the walls

namespace {
// Barycentric weights of the projection of x onto t's plane; true if inside (tolerance tol).
bool inside_tri(const WallGeometry::Tri &t, const double x[3], double tol, double b[3]) {
  double ab[3], ac[3], ap[3];
  sub3(t.p[1], t.p[0], ab);
  sub3(t.p[2], t.p[0], ac);
  sub3(x, t.p[0], ap);
  const double d00 = dot3(ab, ab), d01 = dot3(ab, ac), d11 = dot3(ac, ac);
  const double d20 = dot3(ap, ab), d21 = dot3(ap, ac);
  const double den = d00 * d11 - d01 * d01;
  if (!(den > 0.0)) return false;
  b[1] = (d11 * d20 - d01 * d21) / den;
  b[2] = (d00 * d21 - d01 * d20) / den;
  b[0] = 1.0 - b[1] - b[2];
  return b[0] >= -tol && b[1] >= -tol && b[2] >= -tol;
}
}  // namespace

bool WallGeometry::crosses(const double a[3], int d, double len, double *w_d) const {
  if (tris_.empty()) return false;
  const std::vector<int> *cand = len <= margin_ ? candidates(a) : nullptr;
  const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
  const double eps = 1e-9 * len;
  double b[3];
  b[0] = a[0];
  b[1] = a[1];
  b[2] = a[2];
  b[d] += len;
  for (int c = 0; c < ncand; ++c) {
    const Tri &t = tris_[cand ? (*cand)[c] : c];
    if (b[d] < t.lo[d] - eps || a[d] > t.hi[d] + eps) continue;
    bool out = false;
    for (int e = 0; e < 3; ++e)
      if (e != d && (a[e] < t.lo[e] - eps || a[e] > t.hi[e] + eps)) out = true;
    if (out) continue;
    const int side = walls_[t.mesh].side;
    const bool one_sided = side == SIDE_NORMAL || side == SIDE_OPPOSITE;
    const double sg = side == SIDE_OPPOSITE ? -1.0 : 1.0;
    double r[3];
    sub3(a, t.p[0], r);
    const double s0 = sg * dot3(r, t.n), s1 = s0 + sg * len * t.n[d];
    if (one_sided) {
      const bool f0 = s0 >= -eps, f1 = s1 >= -eps;
      if (f0 == f1) continue;
    } else {
      // two-sided: a node in the plane is inside the wall, cut off from both sides
      const bool on0 = std::fabs(s0) <= eps, on1 = std::fabs(s1) <= eps;
      if (on0 && on1) continue;
      if (!on0 && !on1 && (s0 > 0.0) == (s1 > 0.0)) continue;
    }
    const double f = s0 / (s0 - s1);
    double x[3] = {a[0], a[1], a[2]}, bw[3];
    x[d] += std::min(std::max(f, 0.0), 1.0) * len;
    if (!inside_tri(t, x, 1e-9, bw)) continue;
    double w[3];
    wall_velocity(t, bw, w);
    *w_d = dot3(w, t.n) * t.n[d];
    return true;
  }
  return false;
}

namespace {
// t lies in one of the planes x_d = c given as (d, c), to tol
bool in_planes(const WallGeometry::Tri &t, const std::vector<std::pair<int, double>> &planes, double tol) {
  for (const auto &pl : planes)
    if (std::fabs(t.p[0][pl.first] - pl.second) <= tol && std::fabs(t.p[1][pl.first] - pl.second) <= tol &&
        std::fabs(t.p[2][pl.first] - pl.second) <= tol)
      return true;
  return false;
}
}  // namespace

int WallGeometry::node_side(const double x[3], double reach, double *dist,
                            const std::vector<std::pair<int, double>> *planes, double *dist_off) const {
  *dist = reach;
  if (dist_off) std::fill(dist_off, dist_off + kWallDirs, reach);
  if (tris_.empty()) return 0;
  const std::vector<int> *cand = reach <= margin_ ? candidates(x) : nullptr;
  const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
  // nearest distance, then the sides of the triangles at that distance (face hits first); off the
  // planes: the nearest triangle, whether it is a face hit in front, and the nearest face hit in
  // front in each direction
  double best = reach * reach, best_off = best;
  bool any = false, best_face = false, off_face = false;
  int nd = 0;
  double dir_n[kMax][3], dir_d2[kMax];
  for (int c = 0; c < ncand; ++c) {
    const Tri &t = tris_[cand ? (*cand)[c] : c];
    if (beyond_box(t, x, reach)) continue;
    Hit h;
    closest_point(t, x, h);
    const int side = walls_[t.mesh].side;
    if (dist_off && h.dist2 < reach * reach && (side == SIDE_NORMAL || side == SIDE_OPPOSITE) &&
        !(planes && in_planes(t, *planes, 1e-9 * reach))) {
      double r[3];
      sub3(x, h.p, r);
      const bool front_face = h.face && side * dot3(r, t.n) >= -5e-10 * reach;  // on the plane too
      if (h.dist2 < best_off * (1.0 - 1e-9)) off_face = front_face;
      else if (h.dist2 <= best_off * (1.0 + 1e-9)) off_face = off_face || front_face;
      best_off = std::min(best_off, h.dist2);
      if (front_face) {
        int k = 0;
        while (k < nd && side * dot3(dir_n[k], t.n) <= kCos) ++k;
        if (k == nd && nd < kMax) {
          for (int q = 0; q < 3; ++q) dir_n[nd][q] = side * t.n[q];
          dir_d2[nd++] = h.dist2;
        } else if (k < nd) {
          dir_d2[k] = std::min(dir_d2[k], h.dist2);
        }
      }
    }
    if (h.dist2 > best * (1.0 + 1e-9) + 1e-24) continue;
    if (h.dist2 < best * (1.0 - 1e-9)) best_face = false;
    best = std::min(best, h.dist2);
    best_face = best_face || h.face;
    any = true;
  }
  if (dist_off) {
    if (off_face) {
      std::sort(dir_d2, dir_d2 + nd);
      for (int k = 0; k < std::min(nd, kWallDirs); ++k) dist_off[k] = std::sqrt(dir_d2[k]);
    } else {
      dist_off[0] = std::sqrt(best_off);
    }
  }
  if (!any) return 0;
  *dist = std::sqrt(best);
  bool all_back = true, two_sided = false, found = false;
  for (int c = 0; c < ncand; ++c) {
    const Tri &t = tris_[cand ? (*cand)[c] : c];
    if (beyond_box(t, x, reach)) continue;
    Hit h;
    closest_point(t, x, h);
    if (h.dist2 > best * (1.0 + 1e-9) + 1e-24 || (best_face && !h.face)) continue;
    found = true;
    const int side = walls_[t.mesh].side;
    if (side != SIDE_NORMAL && side != SIDE_OPPOSITE) {
      two_sided = true;
      continue;
    }
    double r[3];
    sub3(x, h.p, r);
    if (side * dot3(r, t.n) >= -5e-10 * reach) all_back = false;  // reach 2 dx: the tolerance of crosses()
  }
  if (!found || two_sided) return 0;
  return all_back ? -1 : 1;
}

// The rigid motion w = v0 + omega x (x - c) nearest (least squares) to the node velocities of each
// wall's triangles, c the mean node position, v0 the mean node velocity: with r = x - c and
// u = w - v0, omega solves sum (|r|^2 I - r r^T) omega = sum r x u (exact for a rigid rotation;
// singular only for nodes on one line, then 0).
void WallGeometry::fit_rotation() {
  using Eigen::Matrix3d;
  using Eigen::Vector3d;
  const std::size_t nw = walls_.size();
  omega_.assign(nw, 0.0);
  for (std::size_t k = 0; k < nw; ++k) {
    if (!(walls_[k].kind == WALL_SHEAR && walls_[k].delta_auto)) continue;
    // mean node position c and velocity v0, largest node speed
    long n = 0;
    Vector3d c = Vector3d::Zero(), v0 = Vector3d::Zero();
    double vmax = 0.0;
    for (const Tri &t : tris_) {
      if (t.mesh != static_cast<int>(k)) continue;
      for (int a = 0; a < 3; ++a, ++n) {
        c += Vector3d(t.p[a][0], t.p[a][1], t.p[a][2]);
        const Vector3d w(t.w[a][0], t.w[a][1], t.w[a][2]);
        v0 += w;
        vmax = std::max(vmax, w.norm());
      }
    }
    if (n < 3) continue;
    c /= n;
    v0 /= n;
    Matrix3d A = Matrix3d::Zero();
    Vector3d b = Vector3d::Zero();
    for (const Tri &t : tris_) {
      if (t.mesh != static_cast<int>(k)) continue;
      for (int a = 0; a < 3; ++a) {
        const Vector3d r = Vector3d(t.p[a][0], t.p[a][1], t.p[a][2]) - c;
        A += r.squaredNorm() * Matrix3d::Identity() - r * r.transpose();
        b += r.cross(Vector3d(t.w[a][0], t.w[a][1], t.w[a][2]) - v0);
      }
    }
    const double scale = A.trace();  // 2 sum |r|^2
    if (!(std::fabs(A.determinant()) > 1e-12 * scale * scale * scale)) continue;
    const double om = A.ldlt().solve(b).norm();
    // a turn below the round-off of the node velocities is none (a translating wall)
    omega_[k] = om * std::sqrt(0.5 * scale / n) > 1e-12 * vmax ? om : 0.0;
  }
}

double WallGeometry::layer_thickness(int k) const {
  const WallSpec &s = walls_[k];
  if (!s.delta_auto) return s.delta;
  const double om = rotation_rate(k);
  return om > 0.0 ? std::sqrt(2.0 * nu_ / om) : HUGE_VAL;
}

}  // namespace mpm
