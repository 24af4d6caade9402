// fill ... inside / outside closed meshes (mpm/mesh_fill.h): closedness, parity where the lattice's
// columns lie in a face's plane or run through an edge or a vertex, the gap, outside meshes.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "mpm/mesh_fill.h"

using mpm::FillLattice;
using mpm::Tri9;

namespace {

// the cube [a, b]^3 as 12 triangles (the diagonals of opposite faces crossed, orientation mixed:
// parity needs none)
std::vector<Tri9> cube(double a, double b) {
  std::vector<Tri9> t;
  auto quad = [&](const double p[4][3]) {
    t.push_back({p[0][0], p[0][1], p[0][2], p[1][0], p[1][1], p[1][2], p[2][0], p[2][1], p[2][2]});
    t.push_back({p[0][0], p[0][1], p[0][2], p[2][0], p[2][1], p[2][2], p[3][0], p[3][1], p[3][2]});
  };
  for (int d = 0; d < 3; ++d)
    for (double c : {a, b}) {
      const int u = (d + 1) % 3, v = (d + 2) % 3;
      double p[4][3];
      const double uv[4][2] = {{a, a}, {b, a}, {b, b}, {a, b}};
      for (int k = 0; k < 4; ++k) {
        p[k][d] = c;
        p[k][u] = uv[k][0];
        p[k][v] = uv[k][1];
      }
      quad(p);
    }
  return t;
}

FillLattice lattice(double first, double s, int n) {
  FillLattice lat;
  for (int d = 0; d < 3; ++d) {
    lat.first[d] = first;
    lat.s[d] = s;
    lat.lo[d] = 0;
    lat.hi[d] = n - 1;
  }
  return lat;
}

long count(const std::vector<char> &m) {
  long n = 0;
  for (char c : m) n += c;
  return n;
}

}  // namespace

TEST(MeshFill, ClosedMeshAccepted) { EXPECT_EQ(mpm::mesh_closed_problem(cube(0, 1)), ""); }

TEST(MeshFill, OpenMeshRefused) {
  std::vector<Tri9> t = cube(0, 1);
  t.pop_back();
  const std::string p = mpm::mesh_closed_problem(t);
  EXPECT_NE(p.find("not closed"), std::string::npos) << p;
  EXPECT_NE(p.find("3 belong to one triangle only"), std::string::npos) << p;
  EXPECT_NE(mpm::mesh_closed_problem({}), "");
}

// columns at x or y = 0 and 1 lie in the planes of the side faces, the column x = y = 0.5 runs
// along the diagonals of the top and bottom faces, the column x = y = 0 along a vertical edge:
// all must fall back to the point-by-point test and still give the cube
TEST(MeshFill, CubeWithDegenerateColumns) {
  const std::vector<Tri9> c = cube(0, 1);
  const FillLattice lat = lattice(-0.5, 0.25, 9);  // -0.5, -0.25, 0, ..., 1.5
  // gap 0.1: the points on the faces go; inside: {0.25, 0.5, 0.75}^3
  const std::vector<char> m = mpm::mesh_fill_mask(lat, &c, {}, 0.1);
  EXPECT_EQ(count(m), 27);
  for (int k = 0; k < 9; ++k)
    for (int j = 0; j < 9; ++j)
      for (int i = 0; i < 9; ++i) {
        const bool in = i >= 3 && i <= 5 && j >= 3 && j <= 5 && k >= 3 && k <= 5;
        EXPECT_EQ(m[lat.index(i, j, k)] != 0, in) << i << " " << j << " " << k;
      }
}

TEST(MeshFill, GapKeepsHalfSpacingOnLatticeFaces) {
  // points half a spacing from the faces stay (the 1e-6 allowance), closer ones go
  const std::vector<Tri9> c = cube(0, 1);
  const FillLattice lat = lattice(0.125, 0.25, 4);  // 0.125 .. 0.875
  EXPECT_EQ(count(mpm::mesh_fill_mask(lat, &c, {}, 0.125)), 64);
  EXPECT_EQ(count(mpm::mesh_fill_mask(lat, &c, {}, 0.13)), 8);
}

TEST(MeshFill, OutsideMeshes) {
  const std::vector<Tri9> box = cube(0, 1), hole = cube(0.3, 0.7);
  const FillLattice lat = lattice(0.05, 0.1, 10);  // 0.05 .. 0.95
  // without a container: everything outside the hole, 0.05 or more from its faces
  const std::vector<char> m = mpm::mesh_fill_mask(lat, nullptr, {hole}, 0.05);
  const std::vector<char> m2 = mpm::mesh_fill_mask(lat, &box, {hole}, 0.05);
  long expect = 0;
  for (int k = 0; k < 10; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 10; ++i) {
        const double x[3] = {0.05 + 0.1 * i, 0.05 + 0.1 * j, 0.05 + 0.1 * k};
        bool in_hole = true;
        for (double v : x) in_hole = in_hole && v > 0.3 && v < 0.7;
        double d2 = HUGE_VAL;
        for (const Tri9 &t : hole) d2 = std::min(d2, mpm::tri_distance2(t, x));
        const bool keep = !in_hole && d2 >= 0.05 * 0.05 * (1 - 1e-5);
        expect += keep;
        EXPECT_EQ(m[lat.index(i, j, k)] != 0, keep) << i << " " << j << " " << k;
        EXPECT_EQ(m2[lat.index(i, j, k)], m[lat.index(i, j, k)]) << i << " " << j << " " << k;
      }
  EXPECT_EQ(count(m), expect);
  // the 64 points inside the hole go; those 0.05 from its faces (exactly the gap) stay
  EXPECT_EQ(expect, 1000 - 64);
}

TEST(MeshFill, PointParity) {
  const std::vector<Tri9> c = cube(0, 1);
  const double in[3] = {0.5, 0.5, 0.5}, corner[3] = {0.999, 0.001, 0.5}, out[3] = {1.5, 0.5, 0.5};
  EXPECT_TRUE(mpm::inside_closed(c, in));
  EXPECT_TRUE(mpm::inside_closed(c, corner));
  EXPECT_FALSE(mpm::inside_closed(c, out));
}

TEST(MeshFill, TriangleDistance) {
  const Tri9 t = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const double above[3] = {0.2, 0.2, 0.5}, beyond_edge[3] = {0.5, -1.0, 0.0}, beyond_vertex[3] = {2.0, 0.0, 0.0};
  EXPECT_NEAR(mpm::tri_distance2(t, above), 0.25, 1e-15);
  EXPECT_NEAR(mpm::tri_distance2(t, beyond_edge), 1.0, 1e-15);
  EXPECT_NEAR(mpm::tri_distance2(t, beyond_vertex), 1.0, 1e-15);
}
