// The largest cell-mean point pressure of f_ID[10] (mpm/cell_pressure.h), on 1 and 2 ranks: one
// cell's points split over the ranks, a single point far above its cell's others.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <vector>

#include "mpi_test_util.h"
#include "mpm/cell_pressure.h"

TEST(CellPressure, CellKey) {
  mpm::GridSpec g;
  g.dx = 0.5;
  g.ncell[0] = 4;
  g.ncell[1] = 2;
  g.ncell[2] = 3;
  g.periodic[1] = true;
  const double a[3] = {0.6, 0.1, 1.2}, wrapped[3] = {0.6, -0.1, 1.2}, outside[3] = {-1e-12, 0.1, 1.6};
  EXPECT_EQ(mpm::cell_key(g, a), (2 * 2 + 0) * 4 + 1);
  EXPECT_EQ(mpm::cell_key(g, wrapped), (2 * 2 + 1) * 4 + 1);  // y wrapped to the last cell
  EXPECT_EQ(mpm::cell_key(g, outside), (2 * 2 + 0) * 4 + 0);  // x clamped into cell 0, z 1.6 in cell 2 (clamped)
}

TEST(CellPressure, MeanOverRanksNotSinglePoint) {
  const int me = mpm_test::rank_of(MPI_COMM_WORLD), np = mpm_test::size_of(MPI_COMM_WORLD);
  // cell 7: eight points of 100 and one of 900 -> mean 188.9 (the single point's 900 is not it);
  // cell 3: four points of 150 -> 150. The points are dealt round-robin over the ranks.
  std::vector<long long> all_key;
  std::vector<double> all_p;
  for (int i = 0; i < 8; ++i) {
    all_key.push_back(7);
    all_p.push_back(100.0);
  }
  all_key.push_back(7);
  all_p.push_back(900.0);
  for (int i = 0; i < 4; ++i) {
    all_key.push_back(3);
    all_p.push_back(150.0);
  }
  std::vector<long long> key;
  std::vector<double> p;
  for (std::size_t i = 0; i < all_key.size(); ++i)
    if (static_cast<int>(i % np) == me) {
      key.push_back(all_key[i]);
      p.push_back(all_p[i]);
    }
  EXPECT_NEAR(mpm::largest_cell_mean(MPI_COMM_WORLD, key, p), 1700.0 / 9.0, 1e-12);
  // no entries anywhere
  EXPECT_EQ(mpm::largest_cell_mean(MPI_COMM_WORLD, {}, {}), -HUGE_VAL);
}
