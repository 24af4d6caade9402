// The fill inside closed LIGGGHTS meshes: see mesh_fill_host.h.
#include "mesh_fill_host.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <sstream>

// LIGGGHTS
#include "fix.h"
#include "fix_mesh_surface.h"
#include "lammps.h"
#include "modify.h"
#include "tri_mesh.h"

#include "mpm/error.h"

namespace mpm {

std::vector<Tri9> gather_closed_mesh(LAMMPS_NS::LAMMPS *lmp, const std::string &id, const char *keyword) {
  const std::string head = std::string("Fix mpm/fluid: keyword '") + keyword + "' expects ";
  const int ifix = lmp->modify->find_fix(id.c_str());
  if (ifix < 0) throw Error(head + "the ID of a fix mesh/surface, got '" + id + "' (no such fix)");
  LAMMPS_NS::Fix *f = lmp->modify->fix[ifix];
  auto *fm = dynamic_cast<LAMMPS_NS::FixMeshSurface *>(f);
  if (!fm || !fm->triMesh() || fm->triMesh()->numNodes() != 3)
    throw Error(head + "the ID of a fix mesh/surface of triangles, got '" + id + "' (a fix " +
                (f->style ? f->style : "?") + ")");
  LAMMPS_NS::TriMesh *m = fm->triMesh();
  int me = 0, nprocs = 1;
  MPI_Comm_rank(lmp->world, &me);
  MPI_Comm_size(lmp->world, &nprocs);
  // a parallel mesh holds each triangle on one rank; before the first setup every rank holds all
  // of it, and rank 0 speaks for all
  std::vector<double> mine;
  if (m->isParallel() || me == 0)
    for (int i = 0; i < m->sizeLocal(); ++i)
      for (int j = 0; j < 3; ++j) {
        double p[3];
        m->node(i, j, p);
        mine.insert(mine.end(), p, p + 3);
      }
  int n = static_cast<int>(mine.size());
  std::vector<int> counts(nprocs), disp(nprocs);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, lmp->world);
  int tot = 0;
  for (int q = 0; q < nprocs; ++q) {
    disp[q] = tot;
    tot += counts[q];
  }
  std::vector<double> all(std::max(tot, 1));
  MPI_Allgatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), disp.data(), MPI_DOUBLE, lmp->world);
  std::vector<Tri9> tris(tot / 9);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int c = 0; c < 9; ++c) tris[t][c] = all[9 * t + c];
  const std::string problem = mesh_closed_problem(tris);
  if (!problem.empty())
    throw Error(head + "a closed mesh (every edge shared by two triangles), got '" + id + "': " + problem);
  return tris;
}

std::vector<char> fill_mesh_mask(LAMMPS_NS::LAMMPS *lmp, const Options &o, const FillLattice &lat, double gap) {
  std::vector<Tri9> inside;
  if (!o.fill_inside.empty()) inside = gather_closed_mesh(lmp, o.fill_inside, "fill inside");
  std::vector<std::vector<Tri9>> outside;
  for (const std::string &id : o.fill_outside) outside.push_back(gather_closed_mesh(lmp, id, "fill outside"));
  return mesh_fill_mask(lat, o.fill_inside.empty() ? nullptr : &inside, outside, gap);
}

std::vector<std::string> grain_walls_beside_fluid(LAMMPS_NS::LAMMPS *lmp, const std::vector<std::string> &fluid_walls,
                                                  const double lo[3], const double hi[3], const double glo[3],
                                                  const double ghi[3], double reach) {
  const double eps = 0.01 * reach;
  int me = 0;
  MPI_Comm_rank(lmp->world, &me);
  std::vector<std::string> out;
  for (int f = 0; f < lmp->modify->nfix; ++f) {
    auto *fm = dynamic_cast<LAMMPS_NS::FixMeshSurface *>(lmp->modify->fix[f]);
    if (!fm || !fm->hasNeighList() || !fm->triMesh() || fm->triMesh()->numNodes() != 3) continue;
    const std::string id = fm->id;
    if (std::find(fluid_walls.begin(), fluid_walls.end(), id) != fluid_walls.end()) continue;
    LAMMPS_NS::TriMesh *m = fm->triMesh();
    double mb[6] = {HUGE_VAL, HUGE_VAL, HUGE_VAL, HUGE_VAL, HUGE_VAL, HUGE_VAL};  // -max -lo, -max hi as minima
    if (m->isParallel() || me == 0)
      for (int i = 0; i < m->sizeLocal(); ++i) {
        double p[3][3];
        for (int j = 0; j < 3; ++j) m->node(i, j, p[j]);
        bool on_face = false;
        for (int d = 0; d < 3 && !on_face; ++d)
          on_face = (p[0][d] <= glo[d] + eps && p[1][d] <= glo[d] + eps && p[2][d] <= glo[d] + eps) ||
                    (p[0][d] >= ghi[d] - eps && p[1][d] >= ghi[d] - eps && p[2][d] >= ghi[d] - eps);
        if (on_face) continue;
        for (int j = 0; j < 3; ++j)
          for (int d = 0; d < 3; ++d) {
            mb[d] = std::min(mb[d], p[j][d]);
            mb[3 + d] = std::min(mb[3 + d], -p[j][d]);
          }
      }
    MPI_Allreduce(MPI_IN_PLACE, mb, 6, MPI_DOUBLE, MPI_MIN, lmp->world);
    bool near = true;
    for (int d = 0; d < 3; ++d)
      near = near && mb[d] <= hi[d] + reach && -mb[3 + d] >= lo[d] - reach;
    if (near) out.push_back(id);
  }
  return out;
}

}  // namespace mpm
