// The state of the last pressure solve that a restart file and the next run carry
// (mpm::ProjectionState, mpm::gather_global, Projection::save / load; docs/theory/projection.md
// "Restart and the state between runs"), serially and on 2 MPI ranks.
#include <gtest/gtest.h>
#include <mpi.h>

#include <vector>

#include "mpm/error.h"
#include "mpm/grid.h"
#include "mpm/options.h"
#include "mpm/projection.h"
#include "mpm/solver.h"
#include "mpi_test_util.h"

namespace {

using mpm_test::rank_of;
using mpm_test::size_of;

mpm::GridSpec spec(bool periodic_y) {
  mpm::GridSpec g;
  g.dx = 0.5;
  g.ncell[0] = 6;
  g.ncell[1] = 4;
  g.ncell[2] = 5;
  g.periodic[1] = periodic_y;
  return g;
}

// slabs along x, rank 0 up to split of the length (2 ranks)
void setup(mpm::LocalGrid &grid, const mpm::GridSpec &g, double split) {
  mpm_test::setup_slabs(grid, g, MPI_COMM_WORLD, split, 3);
}

double field(int i, int j, int k, int c) { return 1000.0 * c + 100.0 * i + 10.0 * j + k + 0.25; }

// this rank's owned nodes of the test fields, as Projection::save would give them
mpm::ProjectionState local_state(const mpm::LocalGrid &grid) {
  mpm::ProjectionState s;
  s.valid = true;
  s.box = grid.owned();
  s.have_theta_last = true;
  s.have_avg = true;
  s.have_acc = true;
  s.have_grain_level = true;
  s.iterations = 7;
  s.residual = 3e-9;
  grid.for_owned([&](int i, int j, int k, std::size_t) {
    s.p.push_back(field(i, j, k, 0));
    for (int d = 0; d < 3; ++d) s.grad.push_back(field(i, j, k, 1 + d));
    s.theta_last.push_back(field(i, j, k, 4));
    s.p_avg.push_back(field(i, j, k, 5));
    s.p_acc.push_back(field(i, j, k, 6));
    s.grain_level.push_back(field(i, j, k, 7));
  });
  return s;
}

}  // namespace

// Every node of the whole grid (padding layers included) gets its owner's values, on every rank.
TEST(ProjectionState, GatherGlobalHasEveryNode) {
  for (bool py : {false, true}) {
    const mpm::GridSpec g = spec(py);
    mpm::LocalGrid grid;
    setup(grid, g, 0.4);
    const mpm::ProjectionState s = mpm::gather_global(local_state(grid), g, MPI_COMM_WORLD);
    ASSERT_TRUE(s.valid);
    EXPECT_TRUE(s.have_theta_last);
    EXPECT_EQ(s.iterations, 7);
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(s.box.lo[d], g.node_lo(d));
      EXPECT_EQ(s.box.hi[d], g.node_hi(d));
    }
    std::size_t q = 0;
    int bad = 0;
    for (int k = s.box.lo[2]; k <= s.box.hi[2]; ++k)
      for (int j = s.box.lo[1]; j <= s.box.hi[1]; ++j)
        for (int i = s.box.lo[0]; i <= s.box.hi[0]; ++i, ++q) {
          if (s.p[q] != field(i, j, k, 0) || s.theta_last[q] != field(i, j, k, 4) ||
              s.p_avg[q] != field(i, j, k, 5) || s.p_acc[q] != field(i, j, k, 6) ||
              s.grain_level[q] != field(i, j, k, 7))
            ++bad;
          for (int d = 0; d < 3; ++d)
            if (s.grad[3 * q + d] != field(i, j, k, 1 + d)) ++bad;
        }
    EXPECT_EQ(q, s.p.size());
    EXPECT_EQ(bad, 0) << "periodic y " << py;
  }
}

// The restart block reads back what was written; a layout this build does not know is an error.
TEST(ProjectionState, PackUnpackRoundTrip) {
  const mpm::GridSpec g = spec(false);
  mpm::LocalGrid grid;
  setup(grid, g, 0.5);
  const mpm::ProjectionState s = mpm::gather_global(local_state(grid), g, MPI_COMM_WORLD);
  std::vector<double> buf = {-2.0};  // something before the block, as in the fix's data
  s.pack(buf);
  mpm::ProjectionState r;
  EXPECT_EQ(r.unpack(buf.data() + 1), buf.size() - 1);
  EXPECT_TRUE(r.valid && r.have_theta_last);
  EXPECT_EQ(r.p, s.p);
  EXPECT_EQ(r.grad, s.grad);
  EXPECT_EQ(r.theta_last, s.theta_last);
  EXPECT_TRUE(r.have_avg);
  EXPECT_EQ(r.p_avg, s.p_avg);
  EXPECT_TRUE(r.have_acc);
  EXPECT_EQ(r.p_acc, s.p_acc);
  EXPECT_TRUE(r.have_grain_level);
  EXPECT_EQ(r.grain_level, s.grain_level);
  EXPECT_EQ(r.residual, s.residual);
  // layout 2 (restart files before the grains' levels): the same block without them reads back
  // without them
  std::vector<double> two(buf.begin(), buf.end() - 1 - static_cast<long>(s.grain_level.size()));
  two[1] = 2.0;
  mpm::ProjectionState r2;
  EXPECT_EQ(r2.unpack(two.data() + 1), two.size() - 1);
  EXPECT_TRUE(r2.valid && r2.have_acc && !r2.have_grain_level && r2.grain_level.empty());
  EXPECT_EQ(r2.p_acc, s.p_acc);
  // layout 1 (restart files before pressure_average): the same block without the averaged
  // pressure reads back without it
  std::vector<double> old(two.begin(), two.end() - 2 - static_cast<long>(s.p_avg.size() + s.p_acc.size()));
  old[1] = 1.0;
  mpm::ProjectionState r1;
  EXPECT_EQ(r1.unpack(old.data() + 1), old.size() - 1);
  EXPECT_TRUE(r1.valid && !r1.have_avg && r1.p_avg.empty());
  EXPECT_EQ(r1.theta_last, s.theta_last);
  std::vector<double> none;
  mpm::ProjectionState().pack(none);
  EXPECT_EQ(none.size(), 1u);
  EXPECT_EQ(r.unpack(none.data()), 1u);
  EXPECT_FALSE(r.valid);
  buf[1] = 7.0;
  EXPECT_THROW(r.unpack(buf.data() + 1), mpm::Error);
}

// A Projection loads the whole-grid state on one decomposition and saves it back on its owned
// nodes; on another decomposition (a changed patch) the same, through gather_global.
TEST(ProjectionState, LoadSaveAcrossDecompositions) {
  const mpm::GridSpec g = spec(false);
  mpm::Options opt;
  opt.grid = g;
  opt.rho0 = 1000.0;
  opt.pressure_average = 0.01;
  opt.pressure_acceleration = true;
  mpm::LocalGrid a;
  setup(a, g, 0.5);
  const mpm::ProjectionState global = mpm::gather_global(local_state(a), g, MPI_COMM_WORLD);
  for (double split : {0.5, 0.25}) {
    mpm::LocalGrid grid;
    setup(grid, g, split);
    mpm::Projection proj(grid, MPI_COMM_WORLD, opt);
    ASSERT_TRUE(proj.load(global));
    mpm::ProjectionState saved;
    proj.save(saved);
    const mpm::ProjectionState want = local_state(grid);
    EXPECT_EQ(saved.p, want.p) << split;
    EXPECT_EQ(saved.grad, want.grad) << split;
    EXPECT_EQ(saved.theta_last, want.theta_last) << split;
    EXPECT_EQ(saved.p_avg, want.p_avg) << split;
    EXPECT_EQ(saved.p_acc, want.p_acc) << split;
    EXPECT_EQ(saved.grain_level, want.grain_level) << split;
    // the grains' levels, halos included: forwarded from the owners
    const double *gl = proj.grain_level();
    ASSERT_NE(gl, nullptr);
    EXPECT_EQ(proj.iterations(), 7);
    // the grains' gradient, halos included: forwarded from the owners (padding: the wall node's)
    const std::vector<double> &ge = proj.gradient();
    int bad = 0;
    const mpm::IndexBox &pb = grid.patch();
    for (int k = pb.lo[2]; k <= pb.hi[2]; ++k)
      for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
        for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) {
          const bool pad = i < 0 || j < 0 || k < 0 || i > g.ncell[0] || j > g.ncell[1] || k > g.ncell[2];
          if (!pad && ge[3 * grid.index(i, j, k)] != field(i, j, k, 1)) ++bad;
          if (!pad && gl[grid.index(i, j, k)] != field(i, j, k, 7)) ++bad;
        }
    EXPECT_EQ(bad, 0) << split;
    // a state for another patch is refused when it does not hold every owned node
    mpm::ProjectionState mine = local_state(a);
    if (size_of(MPI_COMM_WORLD) == 2 && split != 0.5) EXPECT_FALSE(proj.load(mine));
  }
}
