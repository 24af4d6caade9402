// The fill inside closed meshes: see mesh_fill.h.
#include "mpm/mesh_fill.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <utility>

namespace mpm {

namespace {

constexpr double kEps = 1e-9;  // relative round-off band of a barycentric coordinate

void sub(const double *a, const double *b, double *c) {
  for (int d = 0; d < 3; ++d) c[d] = a[d] - b[d];
}
double dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
void cross(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

// Ray x + t dir (t > 0) against triangle tr: 1 crossing, 0 none, -1 grazes an edge or a vertex
// (or lies in the triangle's plane across it): undecided.
int ray_hit(const Tri9 &tr, const double x[3], const double dir[3]) {
  const double *a = &tr[0], *b = &tr[3], *c = &tr[6];
  double e1[3], e2[3], pv[3], tv[3], qv[3];
  sub(b, a, e1);
  sub(c, a, e2);
  cross(dir, e2, pv);
  const double det = dot(e1, pv);
  double n[3];
  cross(e1, e2, n);
  const double nn = std::sqrt(dot(n, n));
  sub(x, a, tv);
  if (std::fabs(det) <= kEps * nn) {  // ray parallel to the plane
    return std::fabs(dot(tv, n)) <= kEps * nn * std::sqrt(std::max(dot(e1, e1), dot(e2, e2))) ? -1 : 0;
  }
  const double u = dot(tv, pv) / det;
  cross(tv, e1, qv);
  const double v = dot(dir, qv) / det;
  const double t = dot(e2, qv) / det;
  const double w = 1.0 - u - v;
  if (u < -kEps || v < -kEps || w < -kEps) return 0;
  const double len = std::sqrt(std::max(dot(e1, e1), dot(e2, e2)));
  if (std::fabs(t) <= kEps * len) return -1;  // x on the triangle (the gap rejects it anyway)
  if (t < 0.0) return 0;
  if (u <= kEps || v <= kEps || w <= kEps) return -1;
  return 1;
}

// per mesh: 1 inside, for every lattice point (column parity along z, point parity where undecided)
std::vector<char> inside_mask(const FillLattice &lat, const std::vector<Tri9> &tris) {
  const int nx = lat.hi[0] - lat.lo[0] + 1, ny = lat.hi[1] - lat.lo[1] + 1, nz = lat.hi[2] - lat.lo[2] + 1;
  std::vector<char> in(lat.size(), 0);
  if (nx <= 0 || ny <= 0 || nz <= 0) return in;
  std::vector<std::vector<double>> zc(static_cast<std::size_t>(nx) * ny);
  std::vector<char> undecided(zc.size(), 0);
  for (const Tri9 &t : tris) {
    double lo[2], hi[2];
    for (int d = 0; d < 2; ++d) {
      lo[d] = std::min({t[d], t[3 + d], t[6 + d]});
      hi[d] = std::max({t[d], t[3 + d], t[6 + d]});
    }
    const double ext = std::max(hi[0] - lo[0], hi[1] - lo[1]);
    int ilo[2], ihi[2];
    for (int d = 0; d < 2; ++d) {
      const double pad = kEps * std::max(ext, lat.s[d]);
      ilo[d] = std::max(lat.lo[d], static_cast<int>(std::ceil((lo[d] - pad - lat.first[d]) / lat.s[d])));
      ihi[d] = std::min(lat.hi[d], static_cast<int>(std::floor((hi[d] + pad - lat.first[d]) / lat.s[d])));
    }
    // 2-D barycentric coordinates of the column (x, y) in the projected triangle
    const double ax = t[0], ay = t[1], bx = t[3], by = t[4], cx = t[6], cy = t[7];
    const double area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
    const double scale = std::max(ext * ext, 1e-300);
    for (int j = ilo[1]; j <= ihi[1]; ++j)
      for (int i = ilo[0]; i <= ihi[0]; ++i) {
        const double px = lat.first[0] + i * lat.s[0], py = lat.first[1] + j * lat.s[1];
        const std::size_t col = static_cast<std::size_t>(j - lat.lo[1]) * nx + (i - lat.lo[0]);
        const double w0 = (bx - px) * (cy - py) - (by - py) * (cx - px);
        const double w1 = (cx - px) * (ay - py) - (cy - py) * (ax - px);
        const double w2 = (ax - px) * (by - py) - (ay - py) * (bx - px);
        if (std::fabs(area) <= kEps * scale) {
          // triangle parallel to z: undecided where the column touches its projected outline
          const double ps[3][2] = {{ax, ay}, {bx, by}, {cx, cy}};
          for (int e = 0; e < 3; ++e) {
            const double *p = ps[e], *q = ps[(e + 1) % 3];
            const double ex = q[0] - p[0], ey = q[1] - p[1], l2 = ex * ex + ey * ey;
            double u = l2 > 0 ? ((px - p[0]) * ex + (py - p[1]) * ey) / l2 : 0.0;
            u = std::min(1.0, std::max(0.0, u));
            const double dx = px - p[0] - u * ex, dy = py - p[1] - u * ey;
            if (dx * dx + dy * dy <= kEps * kEps * scale) undecided[col] = 1;
          }
          continue;
        }
        const double l0 = w0 / area, l1 = w1 / area, l2 = w2 / area;
        if (l0 < -kEps || l1 < -kEps || l2 < -kEps) continue;
        if (l0 <= kEps || l1 <= kEps || l2 <= kEps) {
          undecided[col] = 1;
          continue;
        }
        zc[col].push_back(l0 * t[2] + l1 * t[5] + l2 * t[8]);
      }
  }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const std::size_t col = static_cast<std::size_t>(j) * nx + i;
      std::vector<double> &z = zc[col];
      std::sort(z.begin(), z.end());
      for (int k = 0; k < nz; ++k) {
        const double x[3] = {lat.first[0] + (lat.lo[0] + i) * lat.s[0], lat.first[1] + (lat.lo[1] + j) * lat.s[1],
                             lat.first[2] + (lat.lo[2] + k) * lat.s[2]};
        const long long at = lat.index(lat.lo[0] + i, lat.lo[1] + j, lat.lo[2] + k);
        if (undecided[col])
          in[at] = inside_closed(tris, x) ? 1 : 0;
        else
          in[at] = ((std::lower_bound(z.begin(), z.end(), x[2]) - z.begin()) % 2) == 1 ? 1 : 0;
      }
    }
  return in;
}

}  // namespace

long long FillLattice::size() const {
  long long n = 1;
  for (int d = 0; d < 3; ++d) n *= std::max(0, hi[d] - lo[d] + 1);
  return n;
}

std::string mesh_closed_problem(const std::vector<Tri9> &tris) {
  if (tris.empty()) return "it has no triangle";
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (const Tri9 &t : tris)
    for (int v = 0; v < 3; ++v)
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], t[3 * v + d]);
        hi[d] = std::max(hi[d], t[3 * v + d]);
      }
  const double tol = 1e-9 * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-300});
  std::map<std::array<long long, 3>, int> ids;
  auto vid = [&](const double *p) {
    std::array<long long, 3> key;
    for (int d = 0; d < 3; ++d) key[d] = std::llround((p[d] - lo[d]) / tol);
    auto it = ids.emplace(key, static_cast<int>(ids.size())).first;
    return it->second;
  };
  std::map<std::pair<int, int>, int> edges;
  for (const Tri9 &t : tris) {
    const int v[3] = {vid(&t[0]), vid(&t[3]), vid(&t[6])};
    for (int e = 0; e < 3; ++e) ++edges[std::minmax(v[e], v[(e + 1) % 3])];
  }
  long long one = 0, more = 0;
  for (const auto &e : edges) {
    if (e.second == 1) ++one;
    if (e.second > 2) ++more;
  }
  if (one == 0 && more == 0) return "";
  std::ostringstream os;
  os << "it is not closed: of its " << edges.size() << " edges " << one << " belong to one triangle only and " << more
     << " to more than two";
  return os.str();
}

bool inside_closed(const std::vector<Tri9> &tris, const double x[3]) {
  // oblique directions, none along a lattice axis or diagonal
  static const double dirs[5][3] = {{0.2718281828, 0.5772156649, 0.7706709180},
                                    {-0.6180339887, 0.3141592654, 0.7207006137},
                                    {0.4142135624, -0.8660254038, 0.2801016536},
                                    {-0.1732050808, -0.2236067977, -0.9591329542},
                                    {0.8414709848, 0.0998334166, -0.5311874224}};
  bool in = false;
  for (const auto &d0 : dirs) {
    const double nd = std::sqrt(dot(d0, d0));
    const double dir[3] = {d0[0] / nd, d0[1] / nd, d0[2] / nd};
    int count = 0;
    bool graze = false;
    for (const Tri9 &t : tris) {
      const int h = ray_hit(t, x, dir);
      if (h < 0) {
        graze = true;
        break;
      }
      count += h;
    }
    in = (count % 2) == 1;
    if (!graze) return in;
  }
  return in;
}

double tri_distance2(const Tri9 &t, const double p[3]) {
  // closest point on a triangle (Voronoi regions of the vertices, edges and face)
  const double *a = &t[0], *b = &t[3], *c = &t[6];
  double ab[3], ac[3], ap[3], q[3];
  sub(b, a, ab);
  sub(c, a, ac);
  sub(p, a, ap);
  auto dist2 = [&](const double *r) {
    double e[3];
    sub(p, r, e);
    return dot(e, e);
  };
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return dist2(a);
  double bp[3];
  sub(p, b, bp);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return dist2(b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    for (int d = 0; d < 3; ++d) q[d] = a[d] + v * ab[d];
    return dist2(q);
  }
  double cp[3];
  sub(p, c, cp);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return dist2(c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    for (int d = 0; d < 3; ++d) q[d] = a[d] + w * ac[d];
    return dist2(q);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    for (int d = 0; d < 3; ++d) q[d] = b[d] + w * (c[d] - b[d]);
    return dist2(q);
  }
  const double den = 1.0 / (va + vb + vc);
  const double v = vb * den, w = vc * den;
  for (int d = 0; d < 3; ++d) q[d] = a[d] + ab[d] * v + ac[d] * w;
  return dist2(q);
}

std::vector<char> mesh_fill_mask(const FillLattice &lat, const std::vector<Tri9> *inside,
                                 const std::vector<std::vector<Tri9>> &outside, double gap) {
  std::vector<char> keep(lat.size(), 1);
  if (keep.empty()) return keep;
  if (inside) keep = inside_mask(lat, *inside);
  for (const std::vector<Tri9> &m : outside) {
    const std::vector<char> in = inside_mask(lat, m);
    for (std::size_t q = 0; q < keep.size(); ++q)
      if (in[q]) keep[q] = 0;
  }
  // the gap: bins of 4 x 4 x 4 lattice points, each with the triangles that come within gap of it
  std::vector<const Tri9 *> all;
  if (inside)
    for (const Tri9 &t : *inside) all.push_back(&t);
  for (const std::vector<Tri9> &m : outside)
    for (const Tri9 &t : m) all.push_back(&t);
  const double smin = std::min({lat.s[0], lat.s[1], lat.s[2]});
  const double g = std::max(0.0, gap - 1e-6 * smin);
  constexpr int B = 4;
  int nb[3];
  for (int d = 0; d < 3; ++d) nb[d] = (lat.hi[d] - lat.lo[d]) / B + 1;
  std::vector<std::vector<const Tri9 *>> bins(static_cast<std::size_t>(nb[0]) * nb[1] * nb[2]);
  double half = 0.0;  // half the diagonal of a bin
  for (int d = 0; d < 3; ++d) half += 0.25 * (B * lat.s[d]) * (B * lat.s[d]);
  half = std::sqrt(half);
  for (const Tri9 *t : all) {
    int blo[3], bhi[3];
    for (int d = 0; d < 3; ++d) {
      const double lo = std::min({(*t)[d], (*t)[3 + d], (*t)[6 + d]}) - g;
      const double hi = std::max({(*t)[d], (*t)[3 + d], (*t)[6 + d]}) + g;
      // lattice indices within [lo, hi], as bins
      const double ilo = std::ceil((lo - lat.first[d]) / lat.s[d]), ihi = std::floor((hi - lat.first[d]) / lat.s[d]);
      blo[d] = static_cast<int>(std::max(0.0, std::floor((ilo - lat.lo[d]) / B)));
      bhi[d] = static_cast<int>(std::min(nb[d] - 1.0, std::floor((ihi - lat.lo[d]) / B)));
    }
    for (int k = blo[2]; k <= bhi[2]; ++k)
      for (int j = blo[1]; j <= bhi[1]; ++j)
        for (int i = blo[0]; i <= bhi[0]; ++i) {
          const int b[3] = {i, j, k};
          double c[3];
          for (int d = 0; d < 3; ++d) c[d] = lat.first[d] + (lat.lo[d] + B * b[d] + 0.5 * (B - 1)) * lat.s[d];
          const double r = half + g;
          if (tri_distance2(*t, c) <= r * r) bins[(static_cast<std::size_t>(k) * nb[1] + j) * nb[0] + i].push_back(t);
        }
  }
  for (int k = lat.lo[2]; k <= lat.hi[2]; ++k)
    for (int j = lat.lo[1]; j <= lat.hi[1]; ++j)
      for (int i = lat.lo[0]; i <= lat.hi[0]; ++i) {
        const long long at = lat.index(i, j, k);
        if (!keep[at]) continue;
        const double x[3] = {lat.first[0] + i * lat.s[0], lat.first[1] + j * lat.s[1], lat.first[2] + k * lat.s[2]};
        const std::size_t bin =
            (static_cast<std::size_t>((k - lat.lo[2]) / B) * nb[1] + (j - lat.lo[1]) / B) * nb[0] + (i - lat.lo[0]) / B;
        for (const Tri9 *t : bins[bin])
          if (tri_distance2(*t, x) < g * g) {
            keep[at] = 0;
            break;
          }
      }
  return keep;
}

}  // namespace mpm
