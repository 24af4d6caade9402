// The pressure solver's sealed components (pressure_solver.h, PressureSolver::seal_components):
// the sets of FLUID nodes that closed faces cut off from every EMPTY node, found by a flood fill
// from the free surface and labelled with the smallest global node key of each set.
#include <mpi.h>

#include <algorithm>
#include <map>
#include <vector>

#include "mpm/pressure_solver.h"

namespace mpm {

namespace {
// seal_components' flood fill: a node reached from an EMPTY one / a FLUID node not yet reached
constexpr double kReached = -1.0, kUnreached = -2.0;
}  // namespace

/* Sealed components: the FLUID nodes that open faces connect into one set without reaching an
   EMPTY node (a pocket closed off by mesh-wall or gate faces, or all the fluid when no node is
   EMPTY). Their block of the operator has the constants as null space, and the moving wall faces
   around such a pocket (a lifter bar turning through the grid: its staircase of closed faces
   changes the pocket's volume from step to step) give it a right-hand side that sums to a
   nonzero value: no solution, and PCG diverges (docs/theory/projection.md, "Sealed pockets"). Labels
   each FLUID node with the smallest global key of its set (-1 if the set reaches an EMPTY node)
   by sweeps forward and backward over the owned nodes and halo exchanges until nothing changes
   on any rank. Returns the number of FLUID nodes in sealed sets on all ranks. Collective. */
long PressureSolver::seal_components(const NodeLabels &labels) {
  std::vector<double> &c = comp_;
  if (flood_from_surface(labels) == 0) {
    c.clear();
    return 0;
  }
  // The nodes left are sealed: each takes the smallest key of its set.
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (labels.kind[n] == kFluid && c[n] == kUnreached) c[n] = double(node_key(i, j, k));
  });
  grid_.forward(c.data(), 1);
  least_keys(labels);
  long sealed = 0, gsealed = 0;
  grid_.for_owned([&](int, int, int, std::size_t n) {
    if (labels.kind[n] == kFluid && c[n] >= 0.0) ++sealed;
  });
  MPI_Allreduce(&sealed, &gsealed, 1, MPI_LONG, MPI_SUM, comm_);
  if (gsealed == 0) c.clear();
  return gsealed;
}

/* seal_components' first step: a flood fill from the FLUID nodes next to an EMPTY one (comp
   kReached: reached; kUnreached: FLUID not yet reached), across the ranks through the halos until
   no rank finds a new seed: in the common case it reaches every FLUID node and that is all the
   cost. Returns the FLUID nodes not reached (all ranks). Collective. */
long PressureSolver::flood_from_surface(const NodeLabels &labels) {
  std::vector<double> &c = comp_;
  const IndexBox &ob = grid_.owned();
  c.assign(grid_.size(), kReached);
  std::vector<std::size_t> queue;
  std::vector<int> qi;  // i, j, k of the queued nodes
  auto push = [&](int i, int j, int k, std::size_t n) {
    c[n] = kReached;
    queue.push_back(n);
    qi.insert(qi.end(), {i, j, k});
  };
  auto next_to = [&](int i, int j, int k, bool empty) {
    for (int d = 0; d < 3; ++d)
      for (int side = -1; side <= 1; side += 2) {
        std::size_t m;
        if (!open_face(grid_, labels, i, j, k, d, side, &m)) continue;
        if (empty ? labels.kind[m] == kEmpty : (labels.kind[m] == kFluid && c[m] == kReached)) return true;
      }
    return false;
  };
  grid_.for_owned([&](int, int, int, std::size_t n) {
    if (labels.kind[n] == kFluid) c[n] = kUnreached;
  });
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (labels.kind[n] == kFluid && next_to(i, j, k, true)) push(i, j, k, n);
  });
  for (;;) {
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int i = qi[3 * q], j = qi[3 * q + 1], k = qi[3 * q + 2];
      for (int d = 0; d < 3; ++d)
        for (int side = -1; side <= 1; side += 2) {
          std::size_t m;
          if (!open_face(grid_, labels, i, j, k, d, side, &m) || labels.kind[m] != kFluid || c[m] != kUnreached)
            continue;
          int a[3] = {i, j, k};
          a[d] += side;
          if (ob.contains(a[0], a[1], a[2])) push(a[0], a[1], a[2], m);
        }
    }
    queue.clear();
    qi.clear();
    grid_.forward(c.data(), 1);
    grid_.for_owned([&](int i, int j, int k, std::size_t n) {
      if (labels.kind[n] == kFluid && c[n] == kUnreached && next_to(i, j, k, false)) push(i, j, k, n);
    });
    long seeds = long(queue.size()), gseeds = 0;
    MPI_Allreduce(&seeds, &gseeds, 1, MPI_LONG, MPI_SUM, comm_);
    if (gseeds == 0) break;
  }
  long unreached = 0, gunreached = 0;
  grid_.for_owned([&](int, int, int, std::size_t n) {
    if (labels.kind[n] == kFluid && c[n] == kUnreached) ++unreached;
  });
  MPI_Allreduce(&unreached, &gunreached, 1, MPI_LONG, MPI_SUM, comm_);
  return gunreached;
}

/* seal_components' second step: every sealed FLUID node takes the smallest key among the nodes
   its open faces connect it to, by sweeps forward and backward over the owned nodes and halo
   exchanges until nothing changes on any rank. Collective. */
void PressureSolver::least_keys(const NodeLabels &labels) {
  std::vector<double> &c = comp_;
  const IndexBox &ob = grid_.owned();
  auto relax = [&](int i, int j, int k) {
    const std::size_t n = grid_.index(i, j, k);
    if (labels.kind[n] != kFluid || c[n] < 0.0) return false;
    double low = c[n];
    for (int d = 0; d < 3; ++d)
      for (int side = -1; side <= 1; side += 2) {
        std::size_t m;
        if (open_face(grid_, labels, i, j, k, d, side, &m) && labels.kind[m] == kFluid) low = std::min(low, c[m]);
      }
    if (!(low < c[n])) return false;
    c[n] = low;
    return true;
  };
  for (;;) {
    bool changed = false, pass = true;
    while (pass) {
      pass = false;
      for (int k = ob.lo[2]; k <= ob.hi[2]; ++k)
        for (int j = ob.lo[1]; j <= ob.hi[1]; ++j)
          for (int i = ob.lo[0]; i <= ob.hi[0]; ++i) pass = relax(i, j, k) || pass;
      for (int k = ob.hi[2]; k >= ob.lo[2]; --k)
        for (int j = ob.hi[1]; j >= ob.lo[1]; --j)
          for (int i = ob.hi[0]; i >= ob.lo[0]; --i) pass = relax(i, j, k) || pass;
      changed = changed || pass;
    }
    grid_.forward(c.data(), 1);
    int mine = changed ? 1 : 0, any = 0;
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, comm_);
    if (!any) break;
  }
}

/* Per sealed component (key -> sum, count) of values at its owned FLUID nodes, summed over the
   ranks. Collective. */
std::map<long, std::pair<double, long>> PressureSolver::component_sums(
    const std::map<long, std::pair<double, long>> &mine) const {
  std::vector<double> out;
  for (const auto &e : mine) {
    out.push_back(double(e.first));
    out.push_back(e.second.first);
    out.push_back(double(e.second.second));
  }
  int size = 0;
  MPI_Comm_size(comm_, &size);
  int len = int(out.size());
  std::vector<int> lens(size), offs(size, 0);
  MPI_Allgather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, comm_);
  for (int r = 1; r < size; ++r) offs[r] = offs[r - 1] + lens[r - 1];
  std::vector<double> all(std::size_t(offs[size - 1] + lens[size - 1]));
  MPI_Allgatherv(out.data(), len, MPI_DOUBLE, all.data(), lens.data(), offs.data(), MPI_DOUBLE, comm_);
  std::map<long, std::pair<double, long>> sums;
  for (std::size_t q = 0; q + 2 < all.size(); q += 3) {
    auto &e = sums[long(all[q])];
    e.first += all[q + 1];
    e.second += long(all[q + 2]);
  }
  return sums;
}

}  // namespace mpm
