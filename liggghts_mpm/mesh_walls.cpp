// Fluid boundary conditions on LIGGGHTS wall meshes; see mesh_walls.h and docs/mesh_walls.md.
#include "mesh_walls.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

// LIGGGHTS
#include "domain.h"
#include "fix.h"
#include "fix_mesh_surface.h"
#include "lammps.h"
#include "modify.h"
#include "multi_vector_container.h"
#include "tri_mesh.h"

using LAMMPS_NS::FixMeshSurface;
using LAMMPS_NS::MultiVectorContainer;
using LAMMPS_NS::TriMesh;

namespace mpm {

namespace {

constexpr int kPack = 21;  // doubles per packed triangle: 9 positions, 9 velocities, mesh index,
                           // global triangle ID, periodic image code

inline double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline void sub3(const double *a, const double *b, double *c) {
  c[0] = a[0] - b[0];
  c[1] = a[1] - b[1];
  c[2] = a[2] - b[2];
}

std::string fix_msg(const std::string &id, const std::string &what) {
  return "mesh wall: fix ID '" + id + "': " + what;
}

// x lies farther than r from the triangle's bounding box along some axis (cannot be within r).
inline bool beyond_box(const MeshWalls::Tri &t, const double x[3], double r) {
  return x[0] < t.lo[0] - r || x[0] > t.hi[0] + r || x[1] < t.lo[1] - r || x[1] > t.hi[1] + r ||
         x[2] < t.lo[2] - r || x[2] > t.hi[2] + r;
}

// Velocity of the wall at barycentric weights b.
inline void wall_velocity(const MeshWalls::Tri &t, const double b[3], double w[3]) {
  for (int d = 0; d < 3; ++d) w[d] = b[0] * t.w[0][d] + b[1] * t.w[1][d] + b[2] * t.w[2][d];
}

// Relative velocity r = v - w: normal part along unit n -> max(0, r.n) (fluid side) or 0 (behind).
// Tangential part: v_t -> target w_t + keep (v_t - target w_t), with
//   noslip / freeslip / partial f: target 1, keep 1 - f (0, 1, 1 - f);
//   sticky f (imposed): target f, keep 0: the tangential velocity becomes f times the wall's (the
//     text's "50 % sticky wall" of C4), whatever it was;
//   shear delta f: target f, keep exp(-rate h): the exact solution over h of
//     dv_t/dt = -rate (v_t - f w_t), the wall shear stress mu (f w_t - v_t) / delta acting on the
//     fluid within 'reach' of the wall, rate = nu / (delta reach) (docs/mesh_walls.md).
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
    keep = std::exp(-c.rate * h);
    target = c.sticky;
  }
  for (int d = 0; d < 3; ++d) {
    const double wt = c.w[d] - wn * c.n[d], vt = v[d] - vn * c.n[d];
    v[d] = (wn + rn_new) * c.n[d] + target * wt + keep * (vt - target * wt);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------

MeshWalls::MeshWalls(LAMMPS_NS::LAMMPS *lmp, std::vector<MeshWallSpec> specs)
    : lmp_(lmp), specs_(std::move(specs)) {
  if (!lmp_) throw std::runtime_error("mesh wall: no LAMMPS instance");
  for (size_t k = 0; k < specs_.size(); ++k) {
    MeshWallSpec &s = specs_[k];
    for (size_t j = 0; j < k; ++j)
      if (specs_[j].fix_id == s.fix_id) throw std::runtime_error(fix_msg(s.fix_id, "given twice"));
    switch (s.kind) {
      case 0: s.sticky = 1.0; break;
      case 1: s.sticky = 0.0; break;
      case 2:
      case 3:
      case 4:
        if (!(s.sticky >= 0.0 && s.sticky <= 1.0)) {
          std::ostringstream m;
          m << "sticky fraction " << s.sticky << " of a partial-slip wall must lie in [0,1]";
          throw std::runtime_error(fix_msg(s.fix_id, m.str()));
        }
        if (s.kind == 4 && !(s.delta > 0.0 && std::isfinite(s.delta))) {
          std::ostringstream m;
          m << "wall layer thickness " << s.delta << " of a shear wall must be positive";
          throw std::runtime_error(fix_msg(s.fix_id, m.str()));
        }
        break;
      default:
        throw std::runtime_error(fix_msg(s.fix_id, "unknown wall kind " + std::to_string(s.kind) +
                                                       " (0 noslip, 1 freeslip, 2 partial, 3 sticky, 4 shear)"));
    }
    if (s.side != SIDE_NORMAL && s.side != SIDE_OPPOSITE && s.side != SIDE_AUTO && s.side != SIDE_BOTH)
      throw std::runtime_error(fix_msg(s.fix_id, "unknown fluid side " + std::to_string(s.side)));
    resolve(static_cast<int>(k));  // throws with the reason
  }
}

void *MeshWalls::resolve(int k) const {
  const std::string &id = specs_[k].fix_id;
  const int ifix = lmp_->modify->find_fix(id.c_str());
  if (ifix < 0) throw std::runtime_error(fix_msg(id, "no such fix"));
  LAMMPS_NS::Fix *f = lmp_->modify->fix[ifix];
  auto *fm = dynamic_cast<FixMeshSurface *>(f);
  if (!fm)
    throw std::runtime_error(fix_msg(id, std::string("is a fix ") + (f->style ? f->style : "?") +
                                             ", not a fix mesh/surface"));
  if (!fm->triMesh() || fm->triMesh()->numNodes() != 3)
    throw std::runtime_error(fix_msg(id, "has no triangle mesh"));
  return fm;
}

// ---------------------------------------------------------------------------------------------
// Gathering

void MeshWalls::refresh(const double patch_lo[3], const double patch_hi[3], double margin) {
  MPI_Comm world = lmp_->world;
  int me = 0, nprocs = 1;
  MPI_Comm_rank(world, &me);
  MPI_Comm_size(world, &nprocs);
  margin_ = std::max(0.0, margin);

  // everyone's box (patch widened by the margin); empty if lo > hi
  double mybox[6];
  for (int d = 0; d < 3; ++d) {
    mybox[d] = patch_lo[d] - margin_;
    mybox[3 + d] = patch_hi[d] + margin_;
  }
  std::vector<double> boxes(6 * nprocs);
  MPI_Allgather(mybox, 6, MPI_DOUBLE, boxes.data(), 6, MPI_DOUBLE, world);

  // periodic image shifts
  const LAMMPS_NS::Domain *dom = lmp_->domain;
  std::vector<double> shifts[3];
  for (int d = 0; d < 3; ++d) {
    shifts[d].push_back(0.0);
    if (dom->periodicity[d]) {
      shifts[d].push_back(-dom->prd[d]);
      shifts[d].push_back(dom->prd[d]);
    }
  }

  // pack my triangles for every rank whose box they (or an image) touch
  std::vector<std::vector<double>> out(nprocs);
  for (size_t k = 0; k < specs_.size(); ++k) {
    auto *fm = static_cast<FixMeshSurface *>(resolve(static_cast<int>(k)));
    TriMesh *m = fm->triMesh();
    // A parallel mesh holds each triangle as local on exactly one rank. Before the first setup
    // a mesh is not parallel yet and every rank holds all of it: rank 0 then speaks for all.
    const bool parallel = m->isParallel();
    if (!parallel && me != 0) continue;
    const int nloc = m->sizeLocal();
    MultiVectorContainer<double, 3, 3> *vel =
        m->prop().getElementProperty<MultiVectorContainer<double, 3, 3>>("v");
    const int nvel = vel ? vel->size() : 0;
    for (int i = 0; i < nloc; ++i) {
      double rec[kPack];
      for (int j = 0; j < 3; ++j) {
        m->node(i, j, &rec[3 * j]);
        for (int d = 0; d < 3; ++d) rec[9 + 3 * j + d] = (i < nvel) ? (*vel)(i)[j][d] : 0.0;
      }
      rec[18] = static_cast<double>(k);
      rec[19] = static_cast<double>(m->id(i));
      double lo[3], hi[3];
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min({rec[d], rec[3 + d], rec[6 + d]});
        hi[d] = std::max({rec[d], rec[3 + d], rec[6 + d]});
      }
      for (int q = 0; q < nprocs; ++q) {
        const double *bx = &boxes[6 * q];
        if (bx[0] > bx[3] || bx[1] > bx[4] || bx[2] > bx[5]) continue;
        for (size_t ix = 0; ix < shifts[0].size(); ++ix)
          for (size_t iy = 0; iy < shifts[1].size(); ++iy)
            for (size_t iz = 0; iz < shifts[2].size(); ++iz) {
              const double s[3] = {shifts[0][ix], shifts[1][iy], shifts[2][iz]};
              bool hit = true;
              for (int d = 0; d < 3 && hit; ++d)
                hit = lo[d] + s[d] <= bx[3 + d] && hi[d] + s[d] >= bx[d];
              if (!hit) continue;
              std::vector<double> &o = out[q];
              const size_t at = o.size();
              o.insert(o.end(), rec, rec + kPack);
              for (int j = 0; j < 3; ++j)
                for (int d = 0; d < 3; ++d) o[at + 3 * j + d] += s[d];
              o[at + 20] = static_cast<double>(9 * ix + 3 * iy + iz);
            }
      }
    }
  }

  // exchange
  std::vector<int> scount(nprocs), rcount(nprocs), sdisp(nprocs), rdisp(nprocs);
  for (int q = 0; q < nprocs; ++q) scount[q] = static_cast<int>(out[q].size());
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, world);
  int stot = 0, rtot = 0;
  for (int q = 0; q < nprocs; ++q) {
    sdisp[q] = stot;
    rdisp[q] = rtot;
    stot += scount[q];
    rtot += rcount[q];
  }
  std::vector<double> sbuf(std::max(stot, 1)), rbuf(std::max(rtot, 1));
  for (int q = 0; q < nprocs; ++q) std::copy(out[q].begin(), out[q].end(), sbuf.begin() + sdisp[q]);
  MPI_Alltoallv(sbuf.data(), scount.data(), sdisp.data(), MPI_DOUBLE, rbuf.data(), rcount.data(),
                rdisp.data(), MPI_DOUBLE, world);

  // unpack
  tris_.clear();
  tris_.reserve(rtot / kPack);
  for (int at = 0; at + kPack <= rtot; at += kPack) {
    Tri t;
    const double *r = &rbuf[at];
    for (int j = 0; j < 3; ++j)
      for (int d = 0; d < 3; ++d) {
        t.p[j][d] = r[3 * j + d];
        t.w[j][d] = r[9 + 3 * j + d];
      }
    t.mesh = static_cast<int>(r[18]);
    t.key = static_cast<long long>(r[19]) * 27 + static_cast<long long>(r[20]);
    double e1[3], e2[3];
    sub3(t.p[1], t.p[0], e1);
    sub3(t.p[2], t.p[0], e2);
    t.n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    t.n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    t.n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double a2 = std::sqrt(dot3(t.n, t.n));
    const double l2 = std::max(dot3(e1, e1), dot3(e2, e2));
    if (!(a2 > 1e-12 * l2) || l2 <= 0.0) continue;  // degenerate (zero area) triangle
    for (int d = 0; d < 3; ++d) {
      t.n[d] /= a2;
      t.lo[d] = std::min({t.p[0][d], t.p[1][d], t.p[2][d]});
      t.hi[d] = std::max({t.p[0][d], t.p[1][d], t.p[2][d]});
    }
    tris_.push_back(t);
  }

  // A fixed order (mesh, triangle ID, image), whatever the ranks: where triangles with different
  // wall velocities act on one node (a rotating mesh), the last one applied wins, so the result
  // must not depend on the decomposition.
  std::sort(tris_.begin(), tris_.end(), [](const Tri &a, const Tri &b) {
    return a.mesh != b.mesh ? a.mesh < b.mesh : a.key < b.key;
  });

  // bins over my box
  for (int d = 0; d < 3; ++d) {
    blo_[d] = mybox[d];
    nb_[d] = 0;
  }
  bins_.clear();
  if (mybox[0] <= mybox[3] && mybox[1] <= mybox[4] && mybox[2] <= mybox[5]) bins_build(mybox);
}

void MeshWalls::bins_build(const double box[6]) {
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

const std::vector<int> *MeshWalls::candidates(const double x[3]) const {
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
void MeshWalls::closest_point(const Tri &t, const double x[3], Hit &h) {
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
// Grid nodes

bool MeshWalls::apply(const double x[3], double vel[3], double reach_fluid, double reach_behind,
                      double h) const {
  WallConstraint c[kMaxConstraints];
  const int nc = collect(x, reach_fluid, reach_behind, c);
  impose(c, nc, vel, h);
  return nc > 0;
}

void MeshWalls::impose(const WallConstraint *c, int nc, double vel[3], double h) {
  for (int k = 0; k < nc; ++k) constrain(vel, c[k], h);
}

int MeshWalls::collect(const double x[3], double reach_fluid, double reach_behind, WallConstraint *out,
                       bool *near) const {
  if (near) *near = false;
  if (tris_.empty()) return 0;
  if (reach_behind < 0.0) reach_behind = reach_fluid;
  const double reach = std::max(reach_fluid, reach_behind);
  const std::vector<int> *cand = reach <= margin_ ? candidates(x) : nullptr;
  const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
  const double r2 = reach * reach, rf2 = reach_fluid * reach_fluid, rb2 = reach_behind * reach_behind;

  // Candidates by a lower bound of their distance (plane, bounding box), nearest first. One wall direction is one
  // constraint: of the hits of a mesh whose directions (face normal, or the direction from an
  // edge/vertex) lie within 30 degrees of each other only the nearest is kept. A finely
  // tessellated curved wall (a jar) thus constrains a node once, along its nearest facet, and not
  // dozens of times along normals up to tens of degrees off (which would also take away the
  // tangential velocity that a free-slip or partial wall keeps); distinct walls meeting at an
  // edge or corner (a box) still act together. A candidate whose plane is farther than a kept
  // hit of a similar direction cannot be nearer, so its closest point is not computed.
  constexpr int kCand = 512, kMax = 16;
  constexpr double kCos = 0.8660;  // 30 degrees
  std::pair<double, int> cl[kCand];
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
  if (near) *near = ncl > 0 || !cand;
  if (ncl == 0) return 0;
  std::sort(cl, cl + ncl);
  int idx[kMax];
  Hit hits[kMax];
  double dd[kMax][3];   // x - closest point
  double dir[kMax][3];  // direction of the hit (unsigned for faces)
  bool back[kMax];      // behind the triangle's plane (one-sided meshes)
  int nh = 0;
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
    const int side = specs_[t.mesh].side;
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
  if (nh == 0) return 0;

  int nout = 0;
  for (size_t k = 0; k < specs_.size(); ++k) {
    // Face-region hits of a mesh take precedence over its edge/vertex hits, so that the internal
    // edges of a flat or gently curved wall add no constraint. A node near edges/vertices only is
    // behind the mesh if it is behind the planes of all those triangles (outside a closed box's
    // edge or corner); else it faces a rounded edge.
    bool any_face = false, any = false, all_back = true;
    for (int h = 0; h < nh; ++h) {
      if (tris_[idx[h]].mesh != static_cast<int>(k)) continue;
      any = true;
      if (hits[h].face) any_face = true;
    }
    if (!any) continue;
    if (!any_face)
      for (int h = 0; h < nh; ++h)
        if (tris_[idx[h]].mesh == static_cast<int>(k) && !back[h]) all_back = false;
    const int side = specs_[k].side;
    const double sticky = specs_[k].sticky;
    for (int h = 0; h < nh; ++h) {
      const Tri &t = tris_[idx[h]];
      if (t.mesh != static_cast<int>(k) || hits[h].face != any_face) continue;
      double n[3];
      bool behind;
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
      }
      if (hits[h].dist2 > (behind ? rb2 : rf2)) continue;
      if (nout >= kMaxConstraints) continue;
      WallConstraint &o = out[nout++];
      wall_velocity(t, hits[h].b, o.w);
      for (int q = 0; q < 3; ++q) o.n[q] = n[q];
      o.sticky = sticky;
      o.rate = specs_[k].kind == 4 ? wall_layer_rate(nu_, specs_[k].delta, reach_fluid) : 0.0;
      o.behind = behind;
      o.imposed = specs_[k].kind == 3;
    }
  }
  return nout;
}

bool MeshWalls::nearest_face(const double x[3], double reach, double q[3], double n[3]) const {
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
  const int side = specs_[t.mesh].side;
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
  return true;
}

// ---------------------------------------------------------------------------------------------
// Material points

bool MeshWalls::push_back(double x[3], double v[3], double reach, const double *x_old) const {
  if (tris_.empty()) return false;
  const double off = offset_ > 0.0 ? offset_ : 1e-3 * reach;
  bool moved = false;

  // (a) crossings of the segment x_old -> x
  if (x_old) {
    for (int iter = 0; iter < 4; ++iter) {
      double seg[3];
      sub3(x, x_old, seg);
      const double len = std::sqrt(dot3(seg, seg));
      if (len == 0.0) break;
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
        const int side = specs_[t.mesh].side;
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
      if (bi < 0) break;
      double w[3];
      wall_velocity(tris_[bi], bb, w);
      // back to the fluid side, 'off' from the plane
      for (int d = 0; d < 3; ++d) x[d] = bq[d] + off * bn[d];
      double r[3];
      sub3(v, w, r);
      const double rn = dot3(r, bn);
      for (int d = 0; d < 3; ++d) v[d] -= rn * bn[d];
      moved = true;
    }
  }

  // (b) one-sided meshes: a point behind the mesh, less than 'reach' deep. Behind = behind the
  // planes of all the triangles whose closest point is the nearest one (one triangle in its face
  // region, or the triangles sharing the nearest edge or vertex); the point goes to the nearest
  // point of the mesh plus 'off' towards the fluid.
  for (int iter = 0; iter < 4; ++iter) {
    const std::vector<int> *cand = reach <= margin_ ? candidates(x) : nullptr;
    const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
    const double r2 = reach * reach;
    // Behind the nearest triangles means behind (or on) their planes, and x - q . n is the plane
    // distance for any point q of a triangle: if x is in front of the plane of every one-sided
    // triangle within reach (inside a closed convex mesh: always), nothing is to be done.
    bool any_behind = false;
    for (int c = 0; c < ncand && !any_behind; ++c) {
      const Tri &t = tris_[cand ? (*cand)[c] : c];
      const int side = specs_[t.mesh].side;
      if (side != SIDE_NORMAL && side != SIDE_OPPOSITE) continue;
      double a[3];
      sub3(x, t.p[0], a);
      const double pd = side * dot3(a, t.n);
      any_behind = pd < 1e-12 * reach && pd > -reach;
    }
    if (!any_behind) break;
    constexpr int kMax = 64;
    int idx[kMax];
    Hit hits[kMax];
    int nh = 0;
    double dmin = r2;
    for (int c = 0; c < ncand && nh < kMax; ++c) {
      const int i = cand ? (*cand)[c] : c;
      const Tri &t = tris_[i];
      const int side = specs_[t.mesh].side;
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
    if (nh == 0) break;
    const double tie = dmin + 1e-12 * r2;
    bool behind = true;
    int first = -1;
    for (int h = 0; h < nh && behind; ++h) {
      if (hits[h].dist2 > tie) continue;
      const Tri &t = tris_[idx[h]];
      double d[3];
      sub3(x, hits[h].p, d);
      if (specs_[t.mesh].side * dot3(d, t.n) >= 0.0) behind = false;
      if (first < 0) first = h;
    }
    if (!behind || first < 0) break;
    const Tri &t = tris_[idx[first]];
    const Hit &bh = hits[first];
    double d[3], bn[3];
    sub3(x, bh.p, d);
    const double dl = std::sqrt(bh.dist2);
    if (bh.face || dl <= 1e-12 * reach) {
      for (int q = 0; q < 3; ++q) bn[q] = specs_[t.mesh].side * t.n[q];
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
    moved = true;
  }
  return moved;
}

// ---------------------------------------------------------------------------------------------
// Fluid side from the points

std::string MeshWalls::infer_sides(const double *const *x, int n, double reach) {
  const size_t nm = specs_.size();
  std::vector<long> votes(2 * nm, 0);  // [k][0] normal side, [k][1] opposite side
  for (int i = 0; i < n; ++i) {
    const double *xi = x[i];
    const std::vector<int> *cand = reach <= margin_ ? candidates(xi) : nullptr;
    const int ncand = cand ? static_cast<int>(cand->size()) : static_cast<int>(tris_.size());
    std::vector<double> best(nm, reach * reach);
    std::vector<int> vote(nm, 0);
    for (int c = 0; c < ncand; ++c) {
      const Tri &t = tris_[cand ? (*cand)[c] : c];
      if (specs_[t.mesh].side != SIDE_AUTO) continue;
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
  std::vector<long> total(2 * nm, 0);
  MPI_Allreduce(votes.data(), total.data(), static_cast<int>(2 * nm), MPI_LONG, MPI_SUM, lmp_->world);
  std::ostringstream log;
  for (size_t k = 0; k < nm; ++k) {
    MeshWallSpec &s = specs_[k];
    if (s.side != SIDE_AUTO) continue;
    const long np = total[2 * k], no = total[2 * k + 1];
    if (np == 0 && no == 0)
      throw std::runtime_error(fix_msg(s.fix_id, "no fluid point lies within reach of a triangle face; "
                                                 "cannot infer the fluid side (give it explicitly)"));
    s.side = np >= no ? SIDE_NORMAL : SIDE_OPPOSITE;
    log << "mesh wall " << s.fix_id << ": fluid on the " << (np >= no ? "normal" : "opposite")
        << " side (" << std::max(np, no) << " of " << np + no << " points near its faces agree)\n";
  }
  return log.str();
}

long MeshWalls::global_triangles() const {
  int me = 0;
  MPI_Comm_rank(lmp_->world, &me);
  long mine = 0;
  for (size_t k = 0; k < specs_.size(); ++k) {
    TriMesh *m = static_cast<FixMeshSurface *>(resolve(static_cast<int>(k)))->triMesh();
    if (m->isParallel() || me == 0) mine += m->sizeLocal();
  }
  long all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_LONG, MPI_SUM, lmp_->world);
  return all;
}

}  // namespace mpm
