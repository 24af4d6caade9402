// Fluid boundary conditions on LIGGGHTS wall meshes: reading the meshes and gathering their
// triangles; see mesh_walls.h and docs/theory/mesh_walls.md.
#include "mesh_walls.h"

#include <mpi.h>

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <utility>

// LIGGGHTS
#include "domain.h"
#include "fix.h"
#include "fix_mesh_surface.h"
#include "lammps.h"
#include "modify.h"
#include "multi_vector_container.h"
#include "tri_mesh.h"
#include "mpm/mpi_exchange.h"

using LAMMPS_NS::FixMeshSurface;
using LAMMPS_NS::MultiVectorContainer;
using LAMMPS_NS::TriMesh;

namespace mpm {

namespace {

constexpr int kPack = 21;  // doubles per packed triangle: 9 positions, 9 velocities, mesh index,
                           // global triangle ID, periodic image code

std::string fix_msg(const std::string &id, const std::string &what) {
  return "keyword 'mesh_wall': fix ID '" + id + "': " + what;
}

std::vector<WallSpec> checked(const std::vector<MeshWallSpec> &specs) {
  std::vector<WallSpec> walls;
  for (size_t k = 0; k < specs.size(); ++k) {
    for (size_t j = 0; j < k; ++j)
      if (specs[j].fix_id == specs[k].fix_id) throw std::runtime_error(fix_msg(specs[k].fix_id, "given twice"));
    walls.push_back(specs[k]);
    const std::string problem = check_wall(walls.back());
    if (!problem.empty()) throw std::runtime_error(fix_msg(specs[k].fix_id, problem));
  }
  return walls;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

MeshWalls::MeshWalls(LAMMPS_NS::LAMMPS *lmp, std::vector<MeshWallSpec> specs)
    : lmp_(lmp), geo_(checked(specs)) {
  if (!lmp_) throw std::runtime_error("mesh wall: no LAMMPS instance");
  for (const MeshWallSpec &s : specs) ids_.push_back(s.fix_id);
  for (size_t k = 0; k < ids_.size(); ++k) resolve(static_cast<int>(k));  // throws with the reason
}

void *MeshWalls::resolve(int k) const {
  const std::string &id = ids_[k];
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

namespace {

// A triangle's record rec (bounds lo, hi) appended to out[q] for every rank q whose box (boxes,
// 6 per rank; empty if lo > hi) it or one of its periodic images (shifts per direction) touches,
// shifted by the image, with the image's index in rec[20].
void pack_for_ranks(const double *rec, const double lo[3], const double hi[3], const std::vector<double> &boxes,
                    const std::vector<double> shifts[3], std::vector<std::vector<double>> &out) {
  const int nprocs = static_cast<int>(out.size());
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

// a triangle from its packed record (finish_tri still to do)
WallGeometry::Tri unpack_tri(const double *r) {
  WallGeometry::Tri t;
  for (int j = 0; j < 3; ++j)
    for (int d = 0; d < 3; ++d) {
      t.p[j][d] = r[3 * j + d];
      t.w[j][d] = r[9 + 3 * j + d];
    }
  t.mesh = static_cast<int>(r[18]);
  t.key = static_cast<long long>(r[19]) * 27 + static_cast<long long>(r[20]);
  return t;
}

}  // namespace

bool MeshWalls::refresh(const double patch_lo[3], const double patch_hi[3], double margin) {
  MPI_Comm world = lmp_->world;
  int me = 0, nprocs = 1;
  MPI_Comm_rank(world, &me);
  MPI_Comm_size(world, &nprocs);
  margin = std::max(0.0, margin);

  // everyone's box (patch widened by the margin); empty if lo > hi
  double mybox[6];
  for (int d = 0; d < 3; ++d) {
    mybox[d] = patch_lo[d] - margin;
    mybox[3 + d] = patch_hi[d] + margin;
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

  // pack my triangles for every rank whose box they (or an image) touch; the first time, all of
  // them for every rank as well (the corner frames)
  std::vector<std::vector<double>> out(nprocs);
  std::vector<double> whole;
  for (size_t k = 0; k < ids_.size(); ++k) {
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
      rec[20] = 0.0;  // no periodic image
      if (!frames_set_) whole.insert(whole.end(), rec, rec + kPack);
      double lo[3], hi[3];
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min({rec[d], rec[3 + d], rec[6 + d]});
        hi[d] = std::max({rec[d], rec[3 + d], rec[6 + d]});
      }
      pack_for_ranks(rec, lo, hi, boxes, shifts, out);
    }
  }

  if (!frames_set_) {
    set_corner_frames(whole);
    frames_set_ = true;
  }

  // exchange
  int rtot = 0;
  const std::vector<double> rbuf = exchange_records(world, out, rtot);

  // unpack
  std::vector<WallGeometry::Tri> tris;
  tris.reserve(rtot / kPack);
  for (int at = 0; at + kPack <= rtot; at += kPack) {
    WallGeometry::Tri t = unpack_tri(&rbuf[at]);
    if (WallGeometry::finish_tri(t)) tris.push_back(t);  // degenerate (zero area) ones are dropped
  }
  return geo_.set_triangles(std::move(tris), mybox, margin);
}

/* Every triangle of every mesh on every rank, once (collective): the corner frames of the smooth
   surface the meshes stand for (WallGeometry::set_corner_frames). 'mine' holds this rank's records. */
void MeshWalls::set_corner_frames(const std::vector<double> &mine) {
  MPI_Comm world = lmp_->world;
  int nprocs = 1;
  MPI_Comm_size(world, &nprocs);
  const int n = static_cast<int>(mine.size());
  std::vector<int> counts(nprocs), displs(nprocs, 0);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, world);
  for (int r = 1; r < nprocs; ++r) displs[r] = displs[r - 1] + counts[r - 1];
  std::vector<double> all(static_cast<std::size_t>(displs[nprocs - 1]) + counts[nprocs - 1]);
  MPI_Allgatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, world);
  std::vector<WallGeometry::Tri> tris;
  tris.reserve(all.size() / kPack);
  for (std::size_t at = 0; at + kPack <= all.size(); at += kPack) {
    WallGeometry::Tri t = unpack_tri(&all[at]);
    if (WallGeometry::finish_tri(t)) tris.push_back(t);
  }
  geo_.set_corner_frames(tris);
}

// ---------------------------------------------------------------------------------------------
// Fluid side from the points

std::string MeshWalls::infer_sides(const double *const *x, int n, double reach, bool check_given) {
  const size_t nm = ids_.size();
  std::vector<long> votes(2 * nm, 0);  // [k][0] normal side, [k][1] opposite side
  geo_.side_votes(x, n, reach, votes.data());
  std::vector<long> total(2 * nm, 0);
  MPI_Allreduce(votes.data(), total.data(), static_cast<int>(2 * nm), MPI_LONG, MPI_SUM, lmp_->world);
  std::ostringstream log;
  for (size_t k = 0; k < nm; ++k) {
    const int side = geo_.wall(static_cast<int>(k)).side;
    const long np = total[2 * k], no = total[2 * k + 1];
    if (check_given && (side == SIDE_NORMAL || side == SIDE_OPPOSITE)) {
      const long on = side == SIDE_NORMAL ? np : no, off = side == SIDE_NORMAL ? no : np;
      if (off > on) {
        std::ostringstream os;
        os << "side " << (side == SIDE_NORMAL ? "normal" : "opposite") << " holds the fluid on the "
           << (side == SIDE_NORMAL ? "side its normals point to" : "side against its normals") << ", but " << off
           << " of the " << on + off << " material points within " << reach << " of its faces lie on the other side ("
           << on << " on the given side): that fluid would be held behind the wall; give 'side "
           << (side == SIDE_NORMAL ? "opposite" : "normal") << "' or 'side auto'";
        throw std::runtime_error(fix_msg(ids_[k], os.str()));
      }
    }
    if (side != SIDE_AUTO) continue;
    if (np == 0 && no == 0)
      throw std::runtime_error(fix_msg(ids_[k], "no fluid point lies within reach of a triangle face; "
                                                 "cannot infer the fluid side (give it explicitly)"));
    geo_.set_side(static_cast<int>(k), np >= no ? SIDE_NORMAL : SIDE_OPPOSITE);
    log << "mesh wall " << ids_[k] << ": fluid on the " << (np >= no ? "normal" : "opposite")
        << " side (" << std::max(np, no) << " of " << np + no << " points near its faces agree)\n";
  }
  return log.str();
}

long MeshWalls::global_triangles() const {
  int me = 0;
  MPI_Comm_rank(lmp_->world, &me);
  long mine = 0;
  for (size_t k = 0; k < ids_.size(); ++k) {
    TriMesh *m = static_cast<FixMeshSurface *>(resolve(static_cast<int>(k)))->triMesh();
    if (m->isParallel() || me == 0) mine += m->sizeLocal();
  }
  long all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_LONG, MPI_SUM, lmp_->world);
  return all;
}

}  // namespace mpm
