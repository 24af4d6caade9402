// Unit tests of mpm::WallGeometry (liggghts_mpm/mpm/wall_geometry.h) without LIGGGHTS: closest
// points against a dense sampling of the triangle, the five wall kinds on a plate against the
// formulas of docs/theory/mesh_walls.md, undoing a crossing, the bins against a scan of every triangle,
// and the mesh the wall loads give a condition, a crossing, a nearest triangle or a ray to.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

#include "mpm/wall_geometry.h"

using mpm::WallConstraint;
using mpm::WallGeometry;
using mpm::WallSpec;
using Tri = WallGeometry::Tri;

namespace {

Tri make_tri(const double a[3], const double b[3], const double c[3], int mesh = 0, long long key = 0,
             const double w[3] = nullptr) {
  Tri t;
  for (int d = 0; d < 3; ++d) {
    t.p[0][d] = a[d];
    t.p[1][d] = b[d];
    t.p[2][d] = c[d];
    for (int j = 0; j < 3; ++j) t.w[j][d] = w ? w[d] : 0.0;
  }
  t.mesh = mesh;
  t.key = key;
  EXPECT_TRUE(WallGeometry::finish_tri(t));
  return t;
}

// The plate z = z0 over [0,1]^2 as two triangles, normals +z, moving at w.
std::vector<Tri> plate(double z0, const double w[3], int mesh = 0) {
  const double p00[3] = {0, 0, z0}, p10[3] = {1, 0, z0}, p11[3] = {1, 1, z0}, p01[3] = {0, 1, z0};
  return {make_tri(p00, p10, p11, mesh, 0, w), make_tri(p00, p11, p01, mesh, 27, w)};
}

WallSpec wall(mpm::WallKind kind, double sticky = 1.0, int side = mpm::SIDE_NORMAL, double delta = 0.0) {
  WallSpec s;
  s.kind = kind;
  s.sticky = sticky;
  s.side = side;
  s.delta = delta;
  return s;
}

const double kBox[6] = {-0.5, -0.5, -0.5, 1.5, 1.5, 1.5};

WallGeometry plate_geometry(const WallSpec &s, const double w[3]) {
  WallGeometry g({s});
  g.set_triangles(plate(0.5, w), kBox, 0.1);
  return g;
}

void expect_v(const double *v, double a, double b, double c, double tol = 1e-14) {
  EXPECT_NEAR(v[0], a, tol);
  EXPECT_NEAR(v[1], b, tol);
  EXPECT_NEAR(v[2], c, tol);
}

}  // namespace

TEST(WallGeometry, ClosestPointRegions) {
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0};
  const Tri t = make_tri(a, b, c);
  expect_v(t.n, 0, 0, 1);
  WallGeometry::Hit h;
  // face
  const double xf[3] = {0.2, 0.3, 0.5};
  WallGeometry::closest_point(t, xf, h);
  EXPECT_TRUE(h.face);
  expect_v(h.p, 0.2, 0.3, 0.0);
  expect_v(h.b, 0.5, 0.2, 0.3);
  EXPECT_NEAR(h.dist2, 0.25, 1e-15);
  // edges ab and bc
  const double xe[3] = {0.5, -0.5, 0.2};
  WallGeometry::closest_point(t, xe, h);
  EXPECT_FALSE(h.face);
  expect_v(h.p, 0.5, 0.0, 0.0);
  expect_v(h.b, 0.5, 0.5, 0.0);
  EXPECT_NEAR(h.dist2, 0.29, 1e-15);
  const double xh[3] = {1, 1, 0};
  WallGeometry::closest_point(t, xh, h);
  EXPECT_FALSE(h.face);
  expect_v(h.p, 0.5, 0.5, 0.0);
  expect_v(h.b, 0.0, 0.5, 0.5);
  // vertices a and b
  const double xa[3] = {-1, -1, 0.3};
  WallGeometry::closest_point(t, xa, h);
  EXPECT_FALSE(h.face);
  expect_v(h.p, 0, 0, 0);
  expect_v(h.b, 1, 0, 0);
  const double xb[3] = {2, -0.5, 0};
  WallGeometry::closest_point(t, xb, h);
  EXPECT_FALSE(h.face);
  expect_v(h.p, 1, 0, 0);
  // a point above an edge (projection on the boundary) faces the triangle
  const double xo[3] = {0.5, 0, 0.4};
  WallGeometry::closest_point(t, xo, h);
  EXPECT_TRUE(h.face);
  expect_v(h.p, 0.5, 0, 0);
}

TEST(WallGeometry, ClosestPointIsNearestOfDenseSampling) {
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int ns = 200;  // samples per barycentric direction
  for (int trial = 0; trial < 50; ++trial) {
    double p[3][3], x[3];
    for (auto &q : p)
      for (double &v : q) v = u(gen);
    for (double &v : x) v = 2.0 * u(gen);
    const Tri t = make_tri(p[0], p[1], p[2]);
    WallGeometry::Hit h;
    WallGeometry::closest_point(t, x, h);
    // p is the point of the weights b, which are a convex combination
    EXPECT_NEAR(h.b[0] + h.b[1] + h.b[2], 1.0, 1e-14);
    for (int d = 0; d < 3; ++d) {
      EXPECT_GE(h.b[d], 0.0);
      EXPECT_NEAR(h.p[d], h.b[0] * p[0][d] + h.b[1] * p[1][d] + h.b[2] * p[2][d], 1e-14);
    }
    double best = 1e300;
    for (int i = 0; i <= ns; ++i)
      for (int j = 0; i + j <= ns; ++j) {
        const double bv = double(i) / ns, bw = double(j) / ns, bu = 1.0 - bv - bw;
        double d2 = 0.0;
        for (int d = 0; d < 3; ++d) {
          const double q = bu * p[0][d] + bv * p[1][d] + bw * p[2][d] - x[d];
          d2 += q * q;
        }
        best = std::min(best, d2);
      }
    // no sample is nearer; the nearest sample is within the sampling's spacing
    EXPECT_LE(h.dist2, best * (1 + 1e-12)) << trial;
    EXPECT_LE(std::sqrt(best) - std::sqrt(h.dist2), 2.0 * 2.0 * std::sqrt(3.0) / ns) << trial;
  }
}

TEST(WallGeometry, WallSpecsChecked) {
  WallSpec s = wall(mpm::WALL_NOSLIP, 0.3);
  EXPECT_EQ(mpm::check_wall(s), "");
  EXPECT_EQ(s.sticky, 1.0);
  s = wall(mpm::WALL_FREESLIP, 0.3);
  EXPECT_EQ(mpm::check_wall(s), "");
  EXPECT_EQ(s.sticky, 0.0);
  s = wall(mpm::WALL_PARTIAL, 1.5);
  EXPECT_NE(mpm::check_wall(s).find("[0,1]"), std::string::npos);
  s = wall(mpm::WALL_SHEAR, 0.5, mpm::SIDE_NORMAL, 0.0);
  EXPECT_NE(mpm::check_wall(s).find("positive"), std::string::npos);
  s = wall(static_cast<mpm::WallKind>(5));
  EXPECT_NE(mpm::check_wall(s).find("unknown wall kind"), std::string::npos);
  s = wall(mpm::WALL_NOSLIP, 1.0, 3);
  EXPECT_NE(mpm::check_wall(s).find("unknown fluid side"), std::string::npos);
  EXPECT_THROW(WallGeometry({wall(mpm::WALL_STICKY, -0.1)}), std::invalid_argument);
  // degenerate triangles are refused
  Tri t;
  const double a[3] = {0, 0, 0}, b[3] = {1, 1, 1};
  std::memcpy(t.p[0], a, sizeof a);
  std::memcpy(t.p[1], b, sizeof b);
  std::memcpy(t.p[2], b, sizeof b);
  EXPECT_FALSE(WallGeometry::finish_tri(t));
}

TEST(WallGeometry, PlateKinds) {
  const double still[3] = {0, 0, 0}, moving[3] = {0.4, -0.2, 0.0};
  const double x[3] = {0.3, 0.6, 0.55};  // 0.05 in front of the plate
  const double reach = 0.075;
  {
    const WallGeometry g = plate_geometry(wall(mpm::WALL_NOSLIP), still);
    double v[3] = {1, 2, -3}, u[3] = {1, 2, 3};
    EXPECT_TRUE(g.apply(x, v, reach));
    expect_v(v, 0, 0, 0);
    g.apply(x, u, reach);
    expect_v(u, 0, 0, 3);  // leaving the wall is free
    const double far[3] = {0.3, 0.6, 0.7};
    double q[3] = {1, 2, -3};
    EXPECT_FALSE(g.apply(far, q, reach));
    expect_v(q, 1, 2, -3);
  }
  {
    const WallGeometry g = plate_geometry(wall(mpm::WALL_FREESLIP), still);
    double v[3] = {1, 2, -3};
    g.apply(x, v, reach);
    expect_v(v, 1, 2, 0);
    // behind the one-sided plate: no normal motion either way
    const double xb[3] = {0.3, 0.6, 0.45};
    double a[3] = {1, 2, -3}, b[3] = {1, 2, 3};
    g.apply(xb, a, reach);
    g.apply(xb, b, reach);
    expect_v(a, 1, 2, 0);
    expect_v(b, 1, 2, 0);
  }
  {
    const WallGeometry g = plate_geometry(wall(mpm::WALL_PARTIAL, 0.25), moving);
    double v[3] = {1, 2, -3};
    g.apply(x, v, reach);
    // relative tangential velocity kept at 75 %
    expect_v(v, 0.4 + 0.75 * 0.6, -0.2 + 0.75 * 2.2, 0);
  }
  {
    const WallGeometry g = plate_geometry(wall(mpm::WALL_STICKY, 0.5), moving);
    for (double vx : {1.0, -7.0}) {
      double v[3] = {vx, 2, -3};
      g.apply(x, v, reach);
      expect_v(v, 0.2, -0.1, 0);  // half the wall's tangential velocity, whatever it was
    }
  }
  {
    const double nu = 1e-6, delta = 1e-3, f = 0.5, h = 2e-3;
    WallGeometry g = plate_geometry(wall(mpm::WALL_SHEAR, f, mpm::SIDE_NORMAL, delta), moving);
    g.set_kinematic_viscosity(nu);
    const double rate = nu / (delta * reach);
    EXPECT_EQ(mpm::wall_layer_rate(nu, delta, reach), rate);
    EXPECT_EQ(mpm::wall_slip_decay(rate, h), std::exp(-rate * h));
    WallConstraint c[WallGeometry::kMaxConstraints];
    const int nc = g.collect(x, reach, reach, c);
    ASSERT_EQ(nc, 1);
    EXPECT_EQ(c[0].rate, rate);
    EXPECT_FALSE(c[0].imposed);
    const double keep = std::exp(-rate * h);
    double v[3] = {1, 2, -3};
    WallGeometry::impose(c, nc, v, h);
    expect_v(v, f * 0.4 + keep * (1 - f * 0.4), f * -0.2 + keep * (2 + f * 0.2), 0);
    // two steps of h are one of 2h; h = 0 applies the normal condition only
    double a[3] = {1, 2, -3}, b[3] = {1, 2, -3}, z[3] = {1, 2, -3};
    WallGeometry::impose(c, nc, a, h);
    WallGeometry::impose(c, nc, a, h);
    WallGeometry::impose(c, nc, b, 2 * h);
    expect_v(a, b[0], b[1], b[2], 1e-14);
    WallGeometry::impose(c, nc, z, 0.0);
    expect_v(z, 1, 2, 0);
  }
}

TEST(WallGeometry, PushBackUndoesCrossing) {
  const double w[3] = {0.1, 0.0, 0.2};
  for (int side : {mpm::SIDE_NORMAL, mpm::SIDE_BOTH}) {
    const WallGeometry g = plate_geometry(wall(mpm::WALL_FREESLIP, 0, side), w);
    const double reach = 0.075;
    const double xo[3] = {0.3, 0.4, 0.6};
    double x[3] = {0.3, 0.4, 0.4}, v[3] = {0.5, 0.5, -2.0};
    EXPECT_TRUE(g.push_back(x, v, reach, xo)) << side;
    expect_v(x, 0.3, 0.4, 0.5 + 1e-3 * reach);
    expect_v(v, 0.5, 0.5, 0.2);  // normal velocity relative to the wall zeroed
    // a segment that stops short of the plate, and one beside it
    double y[3] = {0.3, 0.4, 0.52}, vy[3] = {0, 0, -1};
    EXPECT_FALSE(g.push_back(y, vy, reach, xo));
    expect_v(y, 0.3, 0.4, 0.52);
    const double xo2[3] = {1.5, 0.4, 0.6};
    double z[3] = {1.5, 0.4, 0.4}, vz[3] = {0, 0, -1};
    EXPECT_FALSE(g.push_back(z, vz, reach, xo2));
  }
  // one-sided: a point just behind the plate (no old position) goes back to the fluid side
  const WallGeometry g = plate_geometry(wall(mpm::WALL_NOSLIP), w);
  double p[3] = {0.3, 0.4, 0.47}, u[3] = {0, 0, -1};
  EXPECT_TRUE(g.push_back(p, u, 0.075));
  expect_v(p, 0.3, 0.4, 0.5 + 7.5e-5);
  expect_v(u, 0, 0, 0.2);
}

TEST(WallGeometry, NearestFace) {
  const double still[3] = {0, 0, 0};
  const WallGeometry g = plate_geometry(wall(mpm::WALL_NOSLIP), still);
  double q[3], n[3];
  const double x[3] = {0.3, 0.6, 0.55};
  ASSERT_TRUE(g.nearest_face(x, 0.075, q, n));
  expect_v(q, 0.3, 0.6, 0.5);
  expect_v(n, 0, 0, 1);
  const double xb[3] = {0.3, 0.6, 0.45};
  EXPECT_FALSE(g.nearest_face(xb, 0.075, q, n));  // behind a one-sided wall
  const double xf[3] = {0.3, 0.6, 0.6};
  EXPECT_FALSE(g.nearest_face(xf, 0.075, q, n));  // beyond reach
}

TEST(WallGeometry, TrianglesSortedByWallAndKey) {
  const double w[3] = {0, 0, 0};
  std::vector<Tri> t = plate(0.5, w, 1);
  std::vector<Tri> t0 = plate(0.2, w, 0);
  t[0].key = 5;
  t[1].key = 3;
  t.insert(t.end(), t0.begin(), t0.end());
  WallGeometry g({wall(mpm::WALL_NOSLIP), wall(mpm::WALL_FREESLIP)});
  g.set_triangles(t, kBox, 0.1);
  ASSERT_EQ(g.gathered(), 4);
  const auto &s = g.triangles();
  EXPECT_EQ(s[0].mesh, 0);
  EXPECT_EQ(s[1].mesh, 0);
  EXPECT_LT(s[0].key, s[1].key);
  EXPECT_EQ(s[2].key, 3);
  EXPECT_EQ(s[3].key, 5);
}

// The bins only choose which triangles a query looks at: the results must be those of a scan of
// all triangles, bit for bit.
TEST(WallGeometry, BinsMatchBruteForce) {
  std::mt19937 gen(12345);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Tri> tris;
  for (int i = 0; i < 300; ++i) {
    double c[3], p[3][3], w[3];
    for (double &v : c) v = u(gen);
    for (auto &q : p)
      for (int d = 0; d < 3; ++d) q[d] = c[d] + 0.3 * (u(gen) - 0.5);
    for (double &v : w) v = u(gen) - 0.5;
    Tri t = make_tri(p[0], p[1], p[2], i % 3, 27LL * i, w);
    tris.push_back(t);
  }
  const std::vector<WallSpec> walls = {wall(mpm::WALL_PARTIAL, 0.3, mpm::SIDE_NORMAL),
                                       wall(mpm::WALL_SHEAR, 0.5, mpm::SIDE_OPPOSITE, 1e-3),
                                       wall(mpm::WALL_FREESLIP, 0, mpm::SIDE_BOTH)};
  const double box[6] = {0.0, 0.0, 0.0, 1.0, 1.0, 1.0}, margin = 0.1;
  WallGeometry a(walls), b(walls);
  a.set_triangles(tris, box, margin);
  b.set_triangles(tris, box, margin);
  a.set_kinematic_viscosity(1e-6);
  b.set_kinematic_viscosity(1e-6);
  b.set_use_bins(false);
  int touched = 0, faces = 0, moved = 0;
  for (int i = 0; i < 2000; ++i) {
    const double x[3] = {u(gen), u(gen), u(gen)};
    WallConstraint ca[WallGeometry::kMaxConstraints], cb[WallGeometry::kMaxConstraints];
    const int na = a.collect(x, 0.05, 0.1, ca), nb = b.collect(x, 0.05, 0.1, cb);
    ASSERT_EQ(na, nb) << i;
    for (int k = 0; k < na; ++k) {
      EXPECT_EQ(0, std::memcmp(ca[k].w, cb[k].w, sizeof ca[k].w)) << i;
      EXPECT_EQ(0, std::memcmp(ca[k].n, cb[k].n, sizeof ca[k].n)) << i;
      EXPECT_EQ(ca[k].sticky, cb[k].sticky);
      EXPECT_EQ(ca[k].rate, cb[k].rate);
      EXPECT_EQ(ca[k].behind, cb[k].behind);
      EXPECT_EQ(ca[k].imposed, cb[k].imposed);
    }
    touched += na > 0;
    double qa[3], qb[3], na3[3], nb3[3];
    const bool fa = a.nearest_face(x, 0.1, qa, na3), fb = b.nearest_face(x, 0.1, qb, nb3);
    ASSERT_EQ(fa, fb) << i;
    if (fa) {
      EXPECT_EQ(0, std::memcmp(qa, qb, sizeof qa)) << i;
      EXPECT_EQ(0, std::memcmp(na3, nb3, sizeof na3)) << i;
      ++faces;
    }
    const double xo[3] = {x[0], x[1], x[2]};
    double xa[3], xb[3], va[3] = {0.1, 0.2, 0.3}, vb[3] = {0.1, 0.2, 0.3};
    for (int d = 0; d < 3; ++d) xa[d] = xb[d] = x[d] + 0.08 * (u(gen) - 0.5);
    const bool ma = a.push_back(xa, va, 0.05, xo), mb = b.push_back(xb, vb, 0.05, xo);
    ASSERT_EQ(ma, mb) << i;
    EXPECT_EQ(0, std::memcmp(xa, xb, sizeof xa)) << i;
    EXPECT_EQ(0, std::memcmp(va, vb, sizeof va)) << i;
    moved += ma;
  }
  // the comparison covered every kind of answer
  EXPECT_GT(touched, 200);
  EXPECT_GT(faces, 200);
  EXPECT_GT(moved, 50);
  std::printf("  %d of 2000 nodes constrained, %d nearest faces, %d points pushed back\n", touched, faces,
              moved);
}

// The projection's closed faces carry the wall's velocity along the wall normal only: a wall moving
// along itself (a jar turning about its axis) is no source or sink of fluid, whatever the grid
// face it cuts. Measured before: with the full wall velocity along the face, the staircase of the
// faces cut by the turning jar of docs/validation/jar.md made sources and sinks one cell apart, and the
// water's points collapsed into clumps (docs/theory/projection.md, "Mesh walls").
TEST(WallGeometry, CrossingCarriesTheNormalVelocityOnly) {
  const double sn = std::sin(M_PI / 6.0), cs = std::cos(M_PI / 6.0);
  const double n[3] = {sn, 0.0, cs}, t[3] = {cs, 0.0, -sn};
  const double a = 0.7, b = -0.3;  // tangential and normal speed of the wall
  double w[3], p[4][3];
  for (int d = 0; d < 3; ++d) w[d] = a * t[d] + b * n[d];
  const double y[3] = {0, 1, 0};
  for (int q = 0; q < 4; ++q) {
    const double u = (q == 1 || q == 2) ? 1.0 : -1.0, v = q >= 2 ? 1.0 : -1.0;
    for (int d = 0; d < 3; ++d) p[q][d] = 0.5 + 0.6 * (u * t[d] + v * y[d]);
  }
  WallGeometry g({wall(mpm::WALL_FREESLIP)});
  g.set_triangles({make_tri(p[0], p[1], p[2], 0, 0, w), make_tri(p[0], p[2], p[3], 0, 1, w)}, kBox, 0.1);
  for (int d : {0, 2}) {
    double x[3] = {0.5, 0.3, 0.5};
    x[d] -= 0.05;
    double wd = 99.0;
    ASSERT_TRUE(g.crosses(x, d, 0.1, &wd)) << d;
    EXPECT_NEAR(wd, b * n[d], 1e-14) << d;  // the full velocity would give w[d]
  }
  const double x[3] = {0.5, 0.25, 0.5};
  double wd = 99.0;
  EXPECT_FALSE(g.crosses(x, 1, 0.1, &wd));  // parallel to the wall
}

// set_triangles reports whether anything changed (the fix then keeps the nodes' wall constraints
// for walls at rest): the same triangles in another order, box and margin: no change; a node moved
// by one ulp, a node velocity, the box or the margin: a change.
TEST(WallGeometry, SetTrianglesReportsChange) {
  const double w0[3] = {0.0, 0.0, 0.0};
  WallGeometry g({wall(mpm::WALL_NOSLIP)});
  std::vector<Tri> t = plate(0.5, w0);
  EXPECT_TRUE(g.set_triangles(t, kBox, 0.1));  // the first set
  std::vector<Tri> r(t.rbegin(), t.rend());
  EXPECT_FALSE(g.set_triangles(r, kBox, 0.1));  // sorted, it is the same set
  std::vector<Tri> moved = t;
  moved[1].p[2][2] = std::nextafter(moved[1].p[2][2], 1.0);
  EXPECT_TRUE(g.set_triangles(moved, kBox, 0.1));
  EXPECT_FALSE(g.set_triangles(moved, kBox, 0.1));
  std::vector<Tri> faster = moved;
  faster[0].w[0][0] = 1e-12;
  EXPECT_TRUE(g.set_triangles(faster, kBox, 0.1));
  const double box2[6] = {-0.5, -0.5, -0.5, 1.5, 1.5, 1.25};
  EXPECT_TRUE(g.set_triangles(faster, box2, 0.1));
  EXPECT_TRUE(g.set_triangles(faster, box2, 0.2));
  EXPECT_FALSE(g.set_triangles(faster, box2, 0.2));
  EXPECT_TRUE(g.set_triangles({faster[0]}, box2, 0.2));  // a triangle fewer
  EXPECT_EQ(g.gathered(), 1);
}

// shear auto: the wall layer is the Stokes layer sqrt(2 nu / omega) of the mesh's rotation, omega
// fitted to its triangles' node velocities. A drum band (16 facets, axis along x through
// (0, 0.2, -0.1)) turning at 10.9 rad/s while it also translates: the fit returns |omega| to
// round-off, whatever the axis and the translation; a part of the band (one rank's triangles)
// gives the same; the same band at rest or only translating has no rotation, so no layer stress.
TEST(WallGeometry, ShearAutoTakesTheStokesLayerOfTheRotation) {
  const double om[3] = {10.9 * 0.6, 10.9 * 0.8, 0.0}, axis_pt[3] = {0.0, 0.2, -0.1}, v0[3] = {0.3, -0.1, 0.05};
  const double R = 0.08, len = 0.04;
  // unit axis e1 = omega / |omega| and two normals e2, e3
  const double e1[3] = {0.6, 0.8, 0.0}, e2[3] = {-0.8, 0.6, 0.0}, e3[3] = {0.0, 0.0, 1.0};
  auto point = [&](double s, double phi, double *x, double *w) {
    for (int d = 0; d < 3; ++d) x[d] = axis_pt[d] + s * e1[d] + R * (std::cos(phi) * e2[d] + std::sin(phi) * e3[d]);
    const double r[3] = {x[0] - axis_pt[0], x[1] - axis_pt[1], x[2] - axis_pt[2]};
    w[0] = v0[0] + om[1] * r[2] - om[2] * r[1];
    w[1] = v0[1] + om[2] * r[0] - om[0] * r[2];
    w[2] = v0[2] + om[0] * r[1] - om[1] * r[0];
  };
  auto band = [&](int first, int last, bool moving) {
    std::vector<Tri> tris;
    const int nf = 16;
    for (int f = first; f < last; ++f) {
      const double a0 = 2 * M_PI * f / nf, a1 = 2 * M_PI * (f + 1) / nf;
      double p[4][3], w[4][3];
      point(0.0, a0, p[0], w[0]);
      point(0.0, a1, p[1], w[1]);
      point(len, a1, p[2], w[2]);
      point(len, a0, p[3], w[3]);
      const int q[2][3] = {{0, 1, 2}, {0, 2, 3}};
      for (int h = 0; h < 2; ++h) {
        Tri t = make_tri(p[q[h][0]], p[q[h][1]], p[q[h][2]], 0, 2 * f + h);
        for (int j = 0; j < 3; ++j)
          for (int d = 0; d < 3; ++d) t.w[j][d] = moving ? w[q[h][j]][d] : v0[d];
        tris.push_back(t);
      }
    }
    return tris;
  };
  WallSpec s = wall(mpm::WALL_SHEAR, 1.0, mpm::SIDE_NORMAL, 0.0);
  s.delta_auto = true;
  EXPECT_EQ(mpm::check_wall(s), "");
  const double nu = 1e-6, box[6] = {-1, -1, -1, 1, 1, 1};
  WallGeometry g({s});
  g.set_kinematic_viscosity(nu);
  g.set_triangles(band(0, 16, true), box, 0.01);
  EXPECT_NEAR(g.rotation_rate(0), 10.9, 1e-12 * 10.9);
  EXPECT_NEAR(g.layer_thickness(0), std::sqrt(2 * nu / 10.9), 1e-12 * std::sqrt(2 * nu / 10.9));
  g.set_triangles(band(3, 6, true), box, 0.01);  // three facets only
  EXPECT_NEAR(g.rotation_rate(0), 10.9, 1e-10 * 10.9);
  g.set_triangles(band(0, 16, false), box, 0.01);  // translating only
  EXPECT_NEAR(g.rotation_rate(0), 0.0, 1e-12);
  EXPECT_TRUE(std::isinf(g.layer_thickness(0)));
  // a given delta is kept as it is
  WallGeometry fixed({wall(mpm::WALL_SHEAR, 1.0, mpm::SIDE_NORMAL, 2.5e-4)});
  fixed.set_triangles(band(0, 16, true), box, 0.01);
  EXPECT_EQ(fixed.layer_thickness(0), 2.5e-4);
}

// The wall loads' queries: which mesh a condition, a crossing undone, a nearest triangle and a ray
// belong to. Two plates, z = 0.5 (mesh 0) and z = 0.8 (mesh 1), both with normals +z.
TEST(WallGeometry, LoadQueriesNameTheMesh) {
  const double w0[3] = {0, 0, 0};
  WallGeometry g({wall(mpm::WALL_FREESLIP, 0.0, mpm::SIDE_BOTH), wall(mpm::WALL_FREESLIP, 0.0, mpm::SIDE_BOTH)});
  std::vector<Tri> t = plate(0.5, w0, 0), u = plate(0.8, w0, 1);
  t.insert(t.end(), u.begin(), u.end());
  g.set_triangles(t, kBox, 0.1);
  // conditions at a node between them, 0.05 from each: one per mesh, named
  const double x[3] = {0.3, 0.4, 0.65};
  WallConstraint c[WallGeometry::kMaxConstraints];
  const int nc = g.collect(x, 0.2, 0.2, c);
  ASSERT_EQ(nc, 2);
  EXPECT_NE(c[0].wall, c[1].wall);
  for (int k = 0; k < nc; ++k) EXPECT_EQ(c[k].wall, c[k].n[2] > 0.0 ? 0 : 1);  // above plate 0, below plate 1
  // nearest triangle and its distance
  double dist = 0.0;
  const double y[3] = {0.3, 0.4, 0.74};
  EXPECT_EQ(g.nearest_wall(y, 0.5, &dist), 1);
  EXPECT_NEAR(dist, 0.06, 1e-12);
  EXPECT_EQ(g.nearest_wall(y, 0.01, &dist), -1);
  // rays along z: up from 0.6 meets mesh 1 at 0.2, down mesh 0 at 0.1; along x none
  double t0 = 0.0;
  const double z[3] = {0.3, 0.4, 0.6};
  EXPECT_EQ(g.ray_wall(z, 2, 1, 1.0, &t0), 1);
  EXPECT_NEAR(t0, 0.2, 1e-12);
  EXPECT_EQ(g.ray_wall(z, 2, -1, 1.0, &t0), 0);
  EXPECT_NEAR(t0, 0.1, 1e-12);
  EXPECT_EQ(g.ray_wall(z, 2, -1, 0.05, &t0), -1);  // beyond the ray's length
  EXPECT_EQ(g.ray_wall(z, 0, 1, 1.0, &t0), -1);
  // a point that crossed plate 1 upwards is put back, and the crossing is mesh 1's
  double p[3] = {0.3, 0.4, 0.82}, v[3] = {0.0, 0.0, 1.0};
  const double pold[3] = {0.3, 0.4, 0.78};
  int which = -1;
  EXPECT_TRUE(g.push_back(p, v, 0.1, pold, &which));
  EXPECT_EQ(which, 1);
  EXPECT_LT(p[2], 0.8);
}

// node_side's dist_off: the distances to the walls of one-sided meshes, leaving out the triangles
// in the given planes (the box faces of the volume correction's expected fill). A floor plate in
// the plane z = 0.5 (fluid above) and a wall plate x = 0.8 (two triangles each); from x = (0.5,
// 0.5, 0.6) the floor is nearer (0.1) than the wall (0.3). With the wall's fluid side towards x <
// 0.8 the node is in the concave corner, in front of both faces: dist_off = {0.1, 0.3}; with the
// plane z = 0.5 left out, the wall's 0.3 alone; with x = 0.8 left out too, nothing within reach.
// With the wall's fluid side away from the node, the wall is no direction (the node is behind it).
// The nearest triangle and the side stay those of all triangles. A two-sided plate counts never.
TEST(WallGeometry, DistanceOffPlanesLeavesOutTheBoxFaces) {
  const double a[3] = {0.8, 0, 0}, b[3] = {0.8, 1, 0}, c[3] = {0.8, 1, 1}, e[3] = {0.8, 0, 1};
  const double x[3] = {0.5, 0.5, 0.6};
  constexpr int K = WallGeometry::kWallDirs;
  for (const bool facing : {true, false}) {  // the wall's normal towards the node (-x) or away (+x)
    std::vector<Tri> tris = plate(0.5, nullptr);
    if (facing) {
      tris.push_back(make_tri(a, c, b, 0, 54));
      tris.push_back(make_tri(a, e, c, 0, 81));
    } else {
      tris.push_back(make_tri(a, b, c, 0, 54));
      tris.push_back(make_tri(a, c, e, 0, 81));
    }
    for (const double margin : {0.1, 1.0}) {  // queries within the bins' margin, and scanning all
      WallGeometry g({wall(mpm::WALL_FREESLIP)});
      g.set_triangles(tris, kBox, margin);
      const double reach = 0.4 <= margin ? 0.4 : 0.09;
      const std::vector<std::pair<int, double>> none, floor{{2, 0.5}}, both{{2, 0.5}, {0, 0.8}};
      double dist, off[K];
      if (reach > 0.3) {
        EXPECT_EQ(g.node_side(x, reach, &dist, &none, off), 1);
        EXPECT_NEAR(dist, 0.1, 1e-14);
        EXPECT_NEAR(off[0], 0.1, 1e-14);
        EXPECT_NEAR(off[1], facing ? 0.3 : reach, 1e-14) << facing;
        EXPECT_EQ(off[2], reach);
        EXPECT_EQ(g.node_side(x, reach, &dist, &floor, off), 1);
        EXPECT_NEAR(dist, 0.1, 1e-14);
        EXPECT_NEAR(off[0], 0.3, 1e-14);  // behind the wall: the nearest distance alone
        EXPECT_EQ(off[1], reach);
        g.node_side(x, reach, &dist, &both, off);
        EXPECT_EQ(off[0], reach);
      } else {
        EXPECT_EQ(g.node_side(x, reach, &dist, &none, off), 0);
        EXPECT_EQ(off[0], reach);
      }
      WallGeometry two({wall(mpm::WALL_FREESLIP, 1.0, mpm::SIDE_BOTH)});
      two.set_triangles(tris, kBox, margin);
      two.node_side(x, reach, &dist, &none, off);
      for (int k = 0; k < K; ++k) EXPECT_EQ(off[k], reach);
    }
  }
}

namespace {
// A drum band: nf facets (two triangles each) of the cylinder of radius R about the axis along y
// through (xc, *, zc), from y = 0 to y = len, turning at omega about that axis; shared vertices
// are the same to the bit (the same expression); the normals point to the axis (the fluid inside).
std::vector<Tri> turning_band(int nf, double R, double len, double omega, int mesh = 0) {
  const double xc = 0.05, zc = 0.05;
  auto point = [&](double y, int f, double *x, double *w) {
    const double phi = 2.0 * M_PI * (f % nf) / nf;  // the last facet ends where the first begins
    x[0] = xc + R * std::cos(phi);
    x[1] = y;
    x[2] = zc + R * std::sin(phi);
    w[0] = omega * (x[2] - zc);  // omega e_y x r
    w[1] = 0.0;
    w[2] = -omega * (x[0] - xc);
  };
  std::vector<Tri> tris;
  for (int f = 0; f < nf; ++f) {
    double p[4][3], w[4][3];
    point(0.0, f, p[0], w[0]);
    point(len, f, p[1], w[1]);
    point(len, f + 1, p[2], w[2]);
    point(0.0, f + 1, p[3], w[3]);
    const int q[2][3] = {{0, 1, 2}, {0, 2, 3}};
    for (int h = 0; h < 2; ++h) {
      Tri t = make_tri(p[q[h][0]], p[q[h][1]], p[q[h][2]], mesh, 27LL * (2 * f + h));
      for (int j = 0; j < 3; ++j)
        for (int d = 0; d < 3; ++d) t.w[j][d] = w[q[h][j]][d];
      tris.push_back(t);
    }
  }
  return tris;
}

// normal speed of the raw facet velocity (the triangle's own normal) at barycentric weights b
double facet_normal_speed(const Tri &t, const double b[3]) {
  double s = 0.0;
  for (int d = 0; d < 3; ++d) s += (b[0] * t.w[0][d] + b[1] * t.w[1][d] + b[2] * t.w[2][d]) * t.n[d];
  return s;
}
}  // namespace

// A tessellated drum turning about its axis moves along itself: each flat facet has a normal
// speed omega times the distance from its centre line (up to omega R sin(pi / nf)), the smooth
// surface it stands for none. With the corner frames (set_corner_frames) the wall conditions and
// the projection's closed faces see the smooth surface's normal speed, 0 to round-off; without
// them the facets' own. The frames follow the mesh: set from the band at one angle, they serve
// the band turned by 0.3 rad. A flat plate has no frames (its triangles keep their own normal, bit
// for bit), and a box's 90-degree edges are real edges.
TEST(WallGeometry, TurningDrumMovesAlongItself) {
  const int nf = 72;
  const double R = 0.05, len = 0.1, omega = 10.9, wr = omega * R;
  const double box[6] = {-0.02, -0.02, -0.02, 0.12, 0.12, 0.12};
  WallGeometry raw({wall(mpm::WALL_FREESLIP, 0.0, mpm::SIDE_OPPOSITE)});
  WallGeometry smooth({wall(mpm::WALL_FREESLIP, 0.0, mpm::SIDE_OPPOSITE)});
  std::vector<Tri> band = turning_band(nf, R, len, omega);
  smooth.set_corner_frames(band);
  // the band turned by 0.3 rad (its triangles' IDs kept): the frames are in each triangle's own frame
  std::vector<Tri> turned = band;
  const double c = std::cos(0.3), s = std::sin(0.3);
  for (Tri &t : turned) {
    for (int j = 0; j < 3; ++j) {
      const double x = t.p[j][0] - 0.05, z = t.p[j][2] - 0.05;
      t.p[j][0] = 0.05 + c * x - s * z;
      t.p[j][2] = 0.05 + s * x + c * z;
      t.w[j][0] = omega * (t.p[j][2] - 0.05);
      t.w[j][2] = -omega * (t.p[j][0] - 0.05);
    }
    ASSERT_TRUE(WallGeometry::finish_tri(t));
  }
  raw.set_triangles(turned, box, 0.02);
  smooth.set_triangles(turned, box, 0.02);
  double raw_max = 0.0;
  for (const Tri &t : smooth.triangles()) {
    ASSERT_TRUE(t.smooth);
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(t.vn[j], 0.0, 1e-12 * wr);
    const double b[3] = {1.0, 0.0, 0.0};
    raw_max = std::max(raw_max, std::fabs(facet_normal_speed(t, b)));
  }
  EXPECT_NEAR(raw_max, wr * std::sin(M_PI / nf), 1e-9 * wr);  // what the facets alone would give
  // a node inside the drum near the wall, at angles across one facet: the wall condition
  // imposes the normal speed 0 (smooth) against up to omega R sin(pi / nf) (raw)
  double seen_raw = 0.0;
  for (int k = 0; k <= 10; ++k) {
    const double phi = 0.3 + 2.0 * M_PI * (7.0 + 0.1 * k) / nf, r = R - 0.002;
    const double x[3] = {0.05 + r * std::cos(phi), 0.04, 0.05 + r * std::sin(phi)};
    for (WallGeometry *g : {&raw, &smooth}) {
      WallConstraint con[WallGeometry::kMaxConstraints];
      const int nc = g->collect(x, 0.005, 0.01, con);
      ASSERT_EQ(nc, 1) << k;
      const double wn = con[0].w[0] * con[0].n[0] + con[0].w[1] * con[0].n[1] + con[0].w[2] * con[0].n[2];
      if (g == &smooth) EXPECT_NEAR(wn, 0.0, 1e-12 * wr) << k;
      else seen_raw = std::max(seen_raw, std::fabs(wn));
    }
    // the projection's closed face along the radius through x
    double a[3] = {x[0], x[1], x[2]}, wd_raw = 0.0, wd = 0.0;
    const int d = std::fabs(std::cos(phi)) > std::fabs(std::sin(phi)) ? 0 : 2;
    const double step = 0.004 * (d == 0 ? (std::cos(phi) > 0 ? 1.0 : -1.0) : (std::sin(phi) > 0 ? 1.0 : -1.0));
    if (step < 0) a[d] += step;
    ASSERT_TRUE(smooth.crosses(a, d, std::fabs(step), &wd)) << k;
    ASSERT_TRUE(raw.crosses(a, d, std::fabs(step), &wd_raw)) << k;
    EXPECT_NEAR(wd, 0.0, 1e-12 * wr) << k;
  }
  EXPECT_GT(seen_raw, 0.5 * wr * std::sin(M_PI / nf));
  // a flat plate: no frames, its triangles as they were
  WallGeometry flat({wall(mpm::WALL_FREESLIP)});
  const double w[3] = {0.1, 0.2, -0.3};
  std::vector<Tri> pl = plate(0.5, w);
  flat.set_corner_frames(pl);
  flat.set_triangles(pl, kBox, 0.1);
  for (const Tri &t : flat.triangles()) EXPECT_FALSE(t.smooth);
  // a cube's faces meet at 90 degrees: real edges, no frames either
  WallGeometry cube({wall(mpm::WALL_FREESLIP)});
  std::vector<Tri> ct;
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      double p[4][3];
      for (int q = 0; q < 4; ++q) {
        const int e = (d + 1) % 3, f = (d + 2) % 3;
        p[q][d] = side;
        p[q][e] = (q == 1 || q == 2) ? 1.0 : 0.0;
        p[q][f] = q >= 2 ? 1.0 : 0.0;
      }
      const long long key = 27LL * (4 * d + 2 * side);
      ct.push_back(make_tri(p[0], p[1], p[2], 0, key, w));
      ct.push_back(make_tri(p[0], p[2], p[3], 0, key + 27, w));
    }
  cube.set_corner_frames(ct);
  cube.set_triangles(ct, kBox, 0.1);
  for (const Tri &t : cube.triangles()) EXPECT_FALSE(t.smooth);
}

// Beyond the rim of a turning disk (a fan of 72 triangles in the plane z = 0.5 turning about its
// axis), a node in the disk's plane sees only edges and vertices of the rim, tens of degrees
// apart within its reach. Only the nearest acts: the node's velocity keeps the rim's normal
// speed, not the whole wall velocity that all of them together imposed (the corner node of a
// turning jar next to a face of the box).
TEST(WallGeometry, EdgeHitsActOnlyByTheNearest) {
  const int nf = 72;
  const double R = 0.05, omega = 10.9, wr = omega * R;
  std::vector<Tri> fan;
  const double o[3] = {0.5, 0.5, 0.5}, wo[3] = {0.0, 0.0, 0.0};
  for (int f = 0; f < nf; ++f) {
    double p[2][3], w[2][3];
    for (int q = 0; q < 2; ++q) {
      const double phi = 2.0 * M_PI * (f + q) / nf;
      p[q][0] = 0.5 + R * std::cos(phi);
      p[q][1] = 0.5 + R * std::sin(phi);
      p[q][2] = 0.5;
      w[q][0] = -omega * (p[q][1] - 0.5);
      w[q][1] = omega * (p[q][0] - 0.5);
      w[q][2] = 0.0;
    }
    Tri t = make_tri(o, p[0], p[1], 0, 27LL * f);
    for (int d = 0; d < 3; ++d) {
      t.w[0][d] = wo[d];
      t.w[1][d] = w[0][d];
      t.w[2][d] = w[1][d];
    }
    fan.push_back(t);
  }
  WallGeometry g({wall(mpm::WALL_FREESLIP, 0.0, mpm::SIDE_NORMAL)});
  g.set_triangles(fan, kBox, 0.02);
  const double dx = 0.1 / 18;
  const double x[3] = {0.5 + R + 0.3 * dx, 0.5 + 0.2 * dx, 0.5};
  WallConstraint con[WallGeometry::kMaxConstraints];
  const int nc = g.collect(x, dx, 2.0 * dx, con);
  ASSERT_EQ(nc, 1);
  double v[3] = {0.0, 0.0, 0.0};
  WallGeometry::impose(con, nc, v, 1e-3);
  EXPECT_LT(std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]), wr * std::sin(M_PI / nf) + 1e-12);
}
