// Distributed grid: every node of the global grid has exactly one owner, and
// halo exchanges neither lose nor duplicate anything, for uneven subdomains,
// walls with padding nodes and periodic images. Run with 1 and 2 MPI ranks.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <vector>

#include "mpm/grid.h"

namespace {

struct Case {
  int ncell[3];
  bool periodic[3];
  int pad;
  int halo;
  double split;  // where rank 0's subdomain ends, fraction of x (2 ranks)
};

int wrap(int i, int n) { return ((i % n) + n) % n; }

void run_case(const Case &c) {
  int me, np;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  MPI_Comm_size(MPI_COMM_WORLD, &np);
  mpm::GridSpec g;
  g.dx = 0.5;
  for (int d = 0; d < 3; ++d) {
    g.origin[d] = -1.0;
    g.ncell[d] = c.ncell[d];
    g.periodic[d] = c.periodic[d];
  }
  g.pad = c.pad;
  double sublo[3], subhi[3];
  for (int d = 0; d < 3; ++d) {
    sublo[d] = g.origin[d];
    subhi[d] = g.upper(d);
  }
  if (np == 2) {
    const double cut = g.origin[0] + c.split * (g.upper(0) - g.origin[0]);
    if (me == 0) subhi[0] = cut; else sublo[0] = cut;
  }
  mpm::LocalGrid grid;
  grid.setup(g, MPI_COMM_WORLD, sublo, subhi, c.halo);
  const mpm::IndexBox &pb = grid.patch(), &ob = grid.owned();

  // Owned boxes tile the global node range exactly once.
  long nglobal = 1;
  for (int d = 0; d < 3; ++d) nglobal *= g.node_hi(d) - g.node_lo(d) + 1;
  long nowned = ob.count(), total = 0;
  MPI_Allreduce(&nowned, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, nglobal);

  auto gid = [&](int i, int j, int k) {
    int idx[3] = {i, j, k};
    for (int d = 0; d < 3; ++d)
      if (g.periodic[d]) idx[d] = wrap(idx[d], g.ncell[d]);
    return 1.0 + idx[0] + 1000.0 * idx[1] + 1.0e6 * idx[2];
  };

  // Reverse: every patch node contributes gid; the owner must receive gid
  // times the number of patch copies of that node, and the grand total is kept.
  std::vector<double> a(grid.size() * 2, 0.0);
  double local_in = 0.0;
  for (int k = pb.lo[2]; k <= pb.hi[2]; ++k)
    for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
      for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) {
        const std::size_t n = grid.index(i, j, k);
        a[2 * n] = gid(i, j, k);
        a[2 * n + 1] = 1.0;
        local_in += gid(i, j, k);
      }
  grid.reverse_sum(a.data(), 2);
  double local_out = 0.0;
  for (int k = ob.lo[2]; k <= ob.hi[2]; ++k)
    for (int j = ob.lo[1]; j <= ob.hi[1]; ++j)
      for (int i = ob.lo[0]; i <= ob.hi[0]; ++i) {
        const std::size_t n = grid.index(i, j, k);
        EXPECT_GE(a[2 * n + 1], 1.0);
        EXPECT_DOUBLE_EQ(a[2 * n], gid(i, j, k) * a[2 * n + 1]);
        local_out += a[2 * n];
      }
  double in = 0, out = 0;
  MPI_Allreduce(&local_in, &in, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(&local_out, &out, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_NEAR(out, in, 1e-9 * in);

  // Forward: owners write gid, every patch node (halo or periodic image) must see it.
  std::vector<double> b(grid.size(), -7.0);
  for (int k = ob.lo[2]; k <= ob.hi[2]; ++k)
    for (int j = ob.lo[1]; j <= ob.hi[1]; ++j)
      for (int i = ob.lo[0]; i <= ob.hi[0]; ++i) b[grid.index(i, j, k)] = gid(i, j, k);
  grid.forward(b.data(), 1);
  for (int k = pb.lo[2]; k <= pb.hi[2]; ++k)
    for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
      for (int i = pb.lo[0]; i <= pb.hi[0]; ++i)
        ASSERT_DOUBLE_EQ(b[grid.index(i, j, k)], gid(i, j, k)) << "node " << i << " " << j << " " << k;
}

TEST(GridHalo, WallsWithPadding) { run_case({{12, 5, 4}, {false, false, false}, 1, 3, 0.5}); }
TEST(GridHalo, UnevenSplitOffNode) { run_case({{12, 5, 4}, {false, false, false}, 1, 3, 0.3717}); }
TEST(GridHalo, PeriodicThinSlab) { run_case({{10, 1, 6}, {false, true, false}, 1, 4, 0.45}); }
TEST(GridHalo, PeriodicAcrossRanks) { run_case({{9, 4, 3}, {true, false, true}, 1, 3, 0.61}); }
TEST(GridHalo, LinearNoPadding) { run_case({{8, 3, 3}, {false, false, false}, 0, 2, 0.5}); }

}  // namespace
