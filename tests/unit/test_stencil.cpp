// The transfer kernels' node loop (mpm/stencil.h): for_stencil visits the
// NS^3 nodes of a point with the flat index of LocalGrid::index and the
// weights and gradients of the 3-D tensor product; the weights reproduce
// constant and linear fields and their gradients (what P2G/G2P rely on).
// Row4, the kernels' 4-wide row, is checked against scalar arithmetic; the
// suite is built twice, portable and (where the machine has them) with
// AVX2 + FMA, the two forms Row4 takes.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <random>

#include "mpm/boundaries.h"
#include "mpm/shape_functions.h"
#include "mpm/stencil.h"

namespace {

// A patch of nx x ny x nz nodes with its first node at global index lo.
struct Patch {
  int lo[3], n[3];
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(k - lo[2]) * n[1] + (j - lo[1])) * n[0] + (i - lo[0]);
  }
};

template <int NS>
int check_point(mpm::ShapeKind kind, const double xp[3], double dx) {
  const Patch patch{{-1, -2, -1}, {9, 7, 8}};
  mpm::Stencil st;
  for (int d = 0; d < 3; ++d) {
    mpm::Shape1D s;
    mpm::shape_eval(kind, xp[d] / dx, s);
    st.base[d] = s.base;
    for (int a = 0; a < 3; ++a) {
      st.w[d][a] = s.w[a];
      st.dw[d][a] = s.dw[a] / dx;
    }
  }
  st.n0 = patch.index(st.base[0], st.base[1], st.base[2]);
  const std::size_t sy = patch.n[0], sz = std::size_t(patch.n[0]) * patch.n[1];
  int count = 0;
  double sum_w = 0, first[3] = {0, 0, 0}, grad_sum[3] = {0, 0, 0}, grad_x[3][3] = {{0}};
  mpm::for_stencil<NS>(st, sy, sz, [&](std::size_t n, int a, int b, int c, double w, double gx, double gy,
                                       double gz) {
    const int node[3] = {st.base[0] + a, st.base[1] + b, st.base[2] + c};
    EXPECT_EQ(n, patch.index(node[0], node[1], node[2]));
    EXPECT_DOUBLE_EQ(w, st.w[0][a] * st.w[1][b] * st.w[2][c]);
    EXPECT_DOUBLE_EQ(gx, st.dw[0][a] * st.w[1][b] * st.w[2][c]);
    EXPECT_DOUBLE_EQ(gy, st.w[0][a] * st.dw[1][b] * st.w[2][c]);
    EXPECT_DOUBLE_EQ(gz, st.w[0][a] * st.w[1][b] * st.dw[2][c]);
    const double g[3] = {gx, gy, gz};
    sum_w += w;
    for (int d = 0; d < 3; ++d) {
      first[d] += w * node[d] * dx;
      grad_sum[d] += g[d];
      for (int e = 0; e < 3; ++e) grad_x[d][e] += node[d] * dx * g[e];
    }
    ++count;
  });
  EXPECT_NEAR(sum_w, 1.0, 1e-14);
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(first[d], xp[d], 1e-13 * dx);       // sum w x_i = x_p
    EXPECT_NEAR(grad_sum[d], 0.0, 1e-12 / dx);      // gradient of a constant
    for (int e = 0; e < 3; ++e)
      EXPECT_NEAR(grad_x[d][e], d == e ? 1.0 : 0.0, 1e-12);  // gradient of x is I
  }
  return count;
}

// points along a line through a few cells (no coordinate at a cell centre): every node is visited
template <int NS>
void sweep(mpm::ShapeKind kind) {
  const double dx = 0.05;
  for (double t = 0.0; t < 1.0; t += 0.0731) {
    const double xp[3] = {0.1 + 0.13 * t, 0.07 + 0.11 * t, 0.2 - 0.09 * t};
    EXPECT_EQ(check_point<NS>(kind, xp, dx), NS * NS * NS);
  }
}

TEST(Stencil, QuadraticBSplineNodesWeightsAndCompleteness) { sweep<3>(mpm::ShapeKind::QuadraticBSpline); }

TEST(Stencil, PlaneOfZeroWeightAtACellCentreIsSkipped) {
  // y and z at cell centres (the 2-D slab one cell thick): the B-spline's third node plane
  // has weight and gradient exactly 0 there; the loop skips it, the sums stay complete
  const double dx = 0.25;
  const double xp[3] = {0.3, 0.125, 0.625};
  EXPECT_EQ(check_point<3>(mpm::ShapeKind::QuadraticBSpline, xp, dx), 12);
  const double xq[3] = {0.3, 0.125, 0.6};
  EXPECT_EQ(check_point<3>(mpm::ShapeKind::QuadraticBSpline, xq, dx), 18);
}

TEST(Stencil, LinearNodesWeightsAndCompleteness) { sweep<2>(mpm::ShapeKind::Linear); }

TEST(Row4, ArithmeticMatchesScalarsOnUnalignedRecords) {
  // records of 4 doubles at an odd offset (the kernels' rows need not be 32-byte aligned)
  std::vector<double> buf(13);
  for (int q = 0; q < 13; ++q) buf[q] = 0.5 * q - 1.0;
  double *p = buf.data() + 1;
  const mpm::Row4 a = {1.0, -2.0, 3.5, 0.25}, b = {0.5, 4.0, -1.0, 2.0};
  const double w = 0.375, gx = -1.25;
  mpm::row4(p) += w * a + gx * b;
  mpm::row4(p + 4) += w * (a - b);
  const mpm::Row4 r = mpm::row4(p + 4);
  for (int q = 0; q < 4; ++q) {
    EXPECT_DOUBLE_EQ(buf[1 + q], 0.5 * (1 + q) - 1.0 + w * a[q] + gx * b[q]);
    EXPECT_DOUBLE_EQ(buf[5 + q], 0.5 * (5 + q) - 1.0 + w * (a[q] - b[q]));
    EXPECT_DOUBLE_EQ(r[q], buf[5 + q]);
  }
  EXPECT_DOUBLE_EQ(buf[0], -1.0);  // neighbours untouched
  EXPECT_DOUBLE_EQ(buf[9], 3.5);
}

}  // namespace

// Boundaries::near_grid_face, the early-out of the grid-face traction, is false only for points
// more than a cell from every non-periodic face along which add_face_traction pushes (dimensions of
// two cells or more): random points and the cells' edges, quadratic B-spline bases.
TEST(WallTraction, NearGridFaceNeverMissesAPointWithinACell) {
  mpm::Options o;
  o.grid.ncell[0] = 7;
  o.grid.ncell[1] = 1;  // a slab: no traction along y
  o.grid.ncell[2] = 2;
  o.grid.periodic[0] = o.grid.periodic[1] = o.grid.periodic[2] = false;
  mpm::Boundaries bc;
  bc.setup(&o, nullptr);
  std::mt19937 gen(3);
  std::vector<double> xs = {0.0, 0.5, 0.999999, 1.0, 1.5, 2.0, 5.0, 5.5, 6.0, 6.000001, 6.5, 7.0};
  for (int t = 0; t < 2000; ++t) xs.push_back(std::uniform_real_distribution<double>(0.0, 7.0)(gen));
  long far = 0;
  for (double xi : xs) {
    mpm::Stencil ps{};
    mpm::Shape1D s;
    mpm::shape_bspline2(xi, s);
    ps.base[0] = s.base;
    ps.base[1] = 0;
    mpm::shape_bspline2(1.0, s);  // z: the middle node of two cells, within a cell of both faces
    ps.base[2] = s.base;
    EXPECT_TRUE(bc.near_grid_face(ps)) << "z within a cell of both faces";
    ps.base[2] = 100;  // a z the test takes out of play: x alone decides
    o.grid.ncell[2] = 1000;
    const bool near_x = xi < 1.0 || xi > 6.0;
    if (near_x) EXPECT_TRUE(bc.near_grid_face(ps)) << "xi = " << xi;
    far += !bc.near_grid_face(ps);
    o.grid.ncell[2] = 2;
  }
  EXPECT_GT(far, 1000);  // and it does skip the interior
}


