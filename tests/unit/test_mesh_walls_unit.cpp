// Unit tests of mpm::MeshWalls (liggghts_mpm/mesh_walls.h) on real LIGGGHTS meshes: an in-process
// LAMMPS instance reads STL files written by the test into a temporary directory (fix mesh/surface,
// optionally fix move/mesh), runs one step, and MeshWalls is checked on hand-placed grid nodes and
// material points. Runs on 1 or 2 MPI ranks (the 2-rank run checks the triangle gathering across
// ranks and periodic images).
//
// Build by hand from the repository root (CTest builds it: tests/unit/CMakeLists.txt):
//   mpicxx -std=c++17 -O2 -Iliggghts_mpm -I/usr/include/liggghts tests/unit/test_mesh_walls_unit.cpp liggghts_mpm/mesh_walls.cpp -o build/test_mesh_walls_unit -lliggghts -lgtest -pthread
//   build/test_mesh_walls_unit
//   mpirun --allow-run-as-root --oversubscribe -np 2 build/test_mesh_walls_unit
// (own main(): MPI_Init before GoogleTest; do not link gtest_main.)
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "fix_mesh_surface.h"
#include "input.h"
#include "lammps.h"
#include "modify.h"
#include "tri_mesh.h"
#include "mesh_walls.h"

using mpm::MeshWalls;
using mpm::MeshWallSpec;

namespace {

using V3 = std::array<double, 3>;
using Tri = std::array<V3, 3>;

std::string g_dir;  // temporary directory (same path on all ranks)

void write_stl(const std::string &name, const std::vector<Tri> &tris) {
  int me = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  if (me == 0) {
    std::ofstream f(g_dir + "/" + name);
    f << "solid t\n";
    for (const Tri &t : tris) {
      f << " facet normal 0 0 0\n  outer loop\n";
      for (const V3 &p : t) f << "   vertex " << p[0] << " " << p[1] << " " << p[2] << "\n";
      f << "  endloop\n endfacet\n";
    }
    f << "endsolid t\n";
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

// Horizontal square plate z = z0 over [x0,x1] x [y0,y1], counter-clockwise seen from +z (normal +z).
std::vector<Tri> plate_z(double x0, double x1, double y0, double y1, double z0) {
  return {Tri{V3{x0, y0, z0}, V3{x1, y0, z0}, V3{x1, y1, z0}},
          Tri{V3{x0, y0, z0}, V3{x1, y1, z0}, V3{x0, y1, z0}}};
}

// Closed box [lo,hi]^3 with 12 triangles, normals pointing out (the usual STL convention).
std::vector<Tri> box_out(double lo, double hi) {
  std::vector<Tri> t;
  auto P = [&](int i, int j, int k) { return V3{i ? hi : lo, j ? hi : lo, k ? hi : lo}; };
  auto quad = [&](V3 a, V3 b, V3 c, V3 d) {  // a b c d counter-clockwise seen from outside
    t.push_back(Tri{a, b, c});
    t.push_back(Tri{a, c, d});
  };
  quad(P(0, 0, 0), P(0, 1, 0), P(1, 1, 0), P(1, 0, 0));  // z = lo, normal -z
  quad(P(0, 0, 1), P(1, 0, 1), P(1, 1, 1), P(0, 1, 1));  // z = hi, normal +z
  quad(P(0, 0, 0), P(1, 0, 0), P(1, 0, 1), P(0, 0, 1));  // y = lo, normal -y
  quad(P(0, 1, 0), P(0, 1, 1), P(1, 1, 1), P(1, 1, 0));  // y = hi, normal +y
  quad(P(0, 0, 0), P(0, 0, 1), P(0, 1, 1), P(0, 1, 0));  // x = lo, normal -x
  quad(P(1, 0, 0), P(1, 1, 0), P(1, 1, 1), P(1, 0, 1));  // x = hi, normal +x
  return t;
}

class MeshWallsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const char *args[] = {"test_mesh_walls", "-screen", "/dev/null", "-log", "none"};
    // LIGGGHTS 3.8 prints the STL import to 'screen' unconditionally: '-screen none' crashes
    lmp.reset(new LAMMPS_NS::LAMMPS(5, const_cast<char **>(args), MPI_COMM_WORLD));
  }
  void TearDown() override { lmp.reset(); }
  void cmd(const std::string &c) { lmp->input->one(c.c_str()); }
  // Box [-0.5,1.5]^3 (x optionally periodic), split along z over the ranks.
  void make_box(const char *bnd = "f f f") {
    cmd("atom_style sphere");
    cmd("atom_modify map array sort 0 0");
    cmd(std::string("boundary ") + bnd);
    cmd("processors 1 1 *");
    cmd("units si");
    cmd("region box block -0.5 1.5 -0.5 1.5 -0.5 1.5 units box");
    cmd("create_box 1 box");
    cmd("neighbor 0.01 bin");
    cmd("timestep 0.001");
  }
  void mesh(const std::string &id, const std::string &stl) {
    cmd("fix " + id + " all mesh/surface file " + g_dir + "/" + stl + " type 1");
  }
  std::unique_ptr<LAMMPS_NS::LAMMPS> lmp;
};

const double kAll[2][3] = {{-0.5, -0.5, -0.5}, {1.5, 1.5, 1.5}};

MeshWallSpec spec(const char *id, mpm::WallKind kind, double sticky = 1.0, int side = mpm::SIDE_NORMAL) {
  MeshWallSpec s;
  s.fix_id = id;
  s.kind = kind;
  s.sticky = sticky;
  s.side = side;
  return s;
}

void expect_v(const double *v, double a, double b, double c, double tol = 1e-12) {
  EXPECT_NEAR(v[0], a, tol);
  EXPECT_NEAR(v[1], b, tol);
  EXPECT_NEAR(v[2], c, tol);
}

}  // namespace

TEST_F(MeshWallsTest, BadSpecsNameTheFix) {
  write_stl("plate.stl", plate_z(0, 1, 0, 1, 0.5));
  make_box();
  mesh("plate", "plate.stl");
  cmd("fix grav all gravity 9.81 vector 0 0 -1");
  auto msg = [&](std::vector<MeshWallSpec> s) -> std::string {
    try {
      MeshWalls w(lmp.get(), s);
    } catch (const std::runtime_error &e) {
      return e.what();
    }
    return "";
  };
  std::string m = msg({spec("nosuch", mpm::WALL_NOSLIP)});
  EXPECT_NE(m.find("'nosuch'"), std::string::npos) << m;
  EXPECT_NE(m.find("no such fix"), std::string::npos) << m;
  m = msg({spec("grav", mpm::WALL_NOSLIP)});
  EXPECT_NE(m.find("'grav'"), std::string::npos) << m;
  EXPECT_NE(m.find("not a fix mesh/surface"), std::string::npos) << m;
  m = msg({spec("plate", mpm::WALL_PARTIAL, 1.5)});
  EXPECT_NE(m.find("'plate'"), std::string::npos) << m;
  EXPECT_NE(m.find("[0,1]"), std::string::npos) << m;
  m = msg({spec("plate", static_cast<mpm::WallKind>(7))});
  EXPECT_NE(m.find("unknown wall kind"), std::string::npos) << m;
  m = msg({spec("plate", mpm::WALL_NOSLIP), spec("plate", mpm::WALL_FREESLIP)});
  EXPECT_NE(m.find("given twice"), std::string::npos) << m;
  EXPECT_EQ(msg({spec("plate", mpm::WALL_PARTIAL, 0.5)}), "");
}

TEST_F(MeshWallsTest, StaticPlateNoslipFreeslipPartial) {
  write_stl("plate.stl", plate_z(0, 1, 0, 1, 0.5));
  make_box();
  mesh("plate", "plate.stl");
  cmd("run 1");
  MeshWalls noslip(lmp.get(), {spec("plate", mpm::WALL_NOSLIP)});
  MeshWalls freeslip(lmp.get(), {spec("plate", mpm::WALL_FREESLIP)});
  MeshWalls partial(lmp.get(), {spec("plate", mpm::WALL_PARTIAL, 0.25)});
  for (MeshWalls *w : {&noslip, &freeslip, &partial}) w->refresh(kAll[0], kAll[1], 0.1);
  EXPECT_EQ(noslip.global_triangles(), 2);
  EXPECT_EQ(noslip.gathered(), 2);  // every rank's patch covers the plate

  const double x[3] = {0.3, 0.6, 0.55};
  double v[3] = {1, 2, -3};
  EXPECT_TRUE(noslip.apply(x, v, 0.075));
  expect_v(v, 0, 0, 0);
  double f[3] = {1, 2, -3};
  EXPECT_TRUE(freeslip.apply(x, f, 0.075));
  expect_v(f, 1, 2, 0);  // approach removed, tangential kept
  double g[3] = {1, 2, 3};
  freeslip.apply(x, g, 0.075);
  expect_v(g, 1, 2, 3);  // leaving the wall: untouched
  double p[3] = {1, 2, -3};
  partial.apply(x, p, 0.075);
  expect_v(p, 0.75, 1.5, 0);
  // out of reach
  double q[3] = {1, 2, -3};
  const double far[3] = {0.3, 0.6, 0.6};
  EXPECT_FALSE(noslip.apply(far, q, 0.075));
  expect_v(q, 1, 2, -3);
  // behind a one-sided wall: normal relative velocity zeroed in both directions
  const double behind[3] = {0.3, 0.6, 0.47};
  double b1[3] = {1, 0, 3}, b2[3] = {1, 0, -3};
  freeslip.apply(behind, b1, 0.075);
  freeslip.apply(behind, b2, 0.075);
  expect_v(b1, 1, 0, 0);
  expect_v(b2, 1, 0, 0);
  // separate reaches: nodes behind the wall are constrained farther out than those in front
  const double front9[3] = {0.3, 0.6, 0.59}, back9[3] = {0.3, 0.6, 0.41};
  double h1[3] = {0, 0, -1}, h2[3] = {0, 0, 1};
  EXPECT_FALSE(freeslip.apply(front9, h1, 0.05, 0.1));
  EXPECT_TRUE(freeslip.apply(back9, h2, 0.05, 0.1));
  expect_v(h1, 0, 0, -1);
  expect_v(h2, 0, 0, 0);
  // beyond the plate's edge: rounded edge, normal from the edge to the node
  const double edge[3] = {1.05, 0.5, 0.5};
  double e[3] = {-2, 1, 0};
  EXPECT_TRUE(freeslip.apply(edge, e, 0.075));
  expect_v(e, 0, 1, 0);
}

TEST_F(MeshWallsTest, TwoSidedAndOppositeSides) {
  write_stl("plate.stl", plate_z(0, 1, 0, 1, 0.5));
  make_box();
  mesh("plate", "plate.stl");
  cmd("run 1");
  MeshWalls both(lmp.get(), {spec("plate", mpm::WALL_FREESLIP, 0, mpm::SIDE_BOTH)});
  MeshWalls opp(lmp.get(), {spec("plate", mpm::WALL_FREESLIP, 0, mpm::SIDE_OPPOSITE)});
  both.refresh(kAll[0], kAll[1], 0.1);
  opp.refresh(kAll[0], kAll[1], 0.1);
  const double below[3] = {0.3, 0.6, 0.46}, above[3] = {0.3, 0.6, 0.54};
  double a[3] = {0, 0, 3}, b[3] = {0, 0, -3}, c[3] = {0, 0, -3}, d[3] = {0, 0, 3};
  both.apply(below, a, 0.075);  // towards the plate from below: stopped
  both.apply(below, b, 0.075);  // away: kept
  both.apply(above, c, 0.075);  // towards from above: stopped
  both.apply(above, d, 0.075);
  expect_v(a, 0, 0, 0);
  expect_v(b, 0, 0, -3);
  expect_v(c, 0, 0, 0);
  expect_v(d, 0, 0, 3);
  // a node in the plane of a two-sided wall cannot leave it either way
  const double in[3] = {0.3, 0.6, 0.5};
  double u1[3] = {1, 0, 3}, u2[3] = {1, 0, -3};
  both.apply(in, u1, 0.075);
  both.apply(in, u2, 0.075);
  expect_v(u1, 1, 0, 0);
  expect_v(u2, 1, 0, 0);
  // opposite: the fluid is below; above is behind
  double e[3] = {0, 0, -3}, g[3] = {0, 0, 3};
  opp.apply(below, e, 0.075);
  opp.apply(above, g, 0.075);
  expect_v(e, 0, 0, -3);
  expect_v(g, 0, 0, 0);
}

TEST_F(MeshWallsTest, MovingWallImposesItsVelocity) {
  write_stl("plate.stl", plate_z(0, 1, 0, 1, 0.5));
  make_box();
  mesh("plate", "plate.stl");
  cmd("fix lift all move/mesh mesh plate linear 0.5 0 2.0");
  cmd("run 1");  // plate at z = 0.502, wall velocity (0.5, 0, 2)
  MeshWalls noslip(lmp.get(), {spec("plate", mpm::WALL_NOSLIP)});
  MeshWalls freeslip(lmp.get(), {spec("plate", mpm::WALL_FREESLIP)});
  noslip.refresh(kAll[0], kAll[1], 0.1);
  freeslip.refresh(kAll[0], kAll[1], 0.1);
  const double x[3] = {0.3, 0.6, 0.55};
  double v[3] = {0, 0, 0};
  EXPECT_TRUE(noslip.apply(x, v, 0.075));
  expect_v(v, 0.5, 0, 2);
  double f[3] = {1, 0, 0};  // relative normal velocity -2: the rising plate pushes the node
  freeslip.apply(x, f, 0.075);
  expect_v(f, 1, 0, 2);
  double g[3] = {1, 0, 3};  // faster than the plate: untouched
  freeslip.apply(x, g, 0.075);
  expect_v(g, 1, 0, 3);

  // a material point left behind the rising plate goes back to the fluid side
  double p[3] = {0.3, 0.6, 0.49}, u[3] = {0.2, 0.1, 0.0};
  EXPECT_TRUE(noslip.push_back(p, u, 0.075));
  EXPECT_NEAR(p[2], 0.502 + 1e-3 * 0.075, 1e-12);
  EXPECT_NEAR(p[0], 0.3, 1e-12);
  expect_v(u, 0.2, 0.1, 2.0);  // normal relative velocity zeroed, tangential kept
  // a point on the fluid side is left alone
  double q[3] = {0.3, 0.6, 0.53}, uq[3] = {0, 0, -1};
  EXPECT_FALSE(noslip.push_back(q, uq, 0.075));
}

// shear delta f: the tangential velocity relaxes towards f times the wall's over h with the exact
// exponential of dv_t/dt = -nu/(delta reach) (v_t - f w_t); the normal condition is the free-slip
// one; h = 0 (a second pass) leaves the tangential velocity alone.
TEST_F(MeshWallsTest, ShearWallRelaxesTowardsAFractionOfTheWallVelocity) {
  write_stl("plate.stl", plate_z(0, 1, 0, 1, 0.5));
  make_box();
  mesh("plate", "plate.stl");
  cmd("fix slide all move/mesh mesh plate linear 0.5 0 2.0");
  cmd("run 1");  // wall velocity (0.5, 0, 2)
  MeshWallSpec s = spec("plate", mpm::WALL_SHEAR, 0.5);
  s.delta = 1e-3;
  MeshWalls shear(lmp.get(), {s});
  const double nu = 1e-6, reach = 0.075, h = 2e-3;
  shear.set_kinematic_viscosity(nu);
  shear.refresh(kAll[0], kAll[1], 0.1);
  const double x[3] = {0.3, 0.6, 0.55};
  const double keep = std::exp(-nu / (1e-3 * reach) * h);
  double v[3] = {1.0, -0.4, 0.0};  // approaching the rising plate: normal part becomes 2
  EXPECT_TRUE(shear.apply(x, v, reach, -1.0, h));
  expect_v(v, 0.25 + keep * (1.0 - 0.25), keep * -0.4, 2.0);
  // two steps of h equal one of 2h (the exponential is exact)
  double a[3] = {1.0, -0.4, 3.0}, b[3] = {1.0, -0.4, 3.0};
  shear.apply(x, a, reach, -1.0, h);
  shear.apply(x, a, reach, -1.0, h);
  shear.apply(x, b, reach, -1.0, 2 * h);
  expect_v(a, b[0], b[1], b[2]);
  // h = 0: only the normal condition
  double c[3] = {1.0, -0.4, 0.0};
  shear.apply(x, c, reach, -1.0, 0.0);
  expect_v(c, 1.0, -0.4, 2.0);
  // a long time: the tangential velocity is f times the wall's
  double d[3] = {1.0, -0.4, 3.0};
  shear.apply(x, d, reach, -1.0, 1e6);
  expect_v(d, 0.25, 0.0, 3.0);
  // a non-positive layer thickness is refused, naming the fix
  s.delta = 0.0;
  try {
    MeshWalls bad(lmp.get(), {s});
    ADD_FAILURE() << "no error for delta = 0";
  } catch (const std::runtime_error &e) {
    EXPECT_NE(std::string(e.what()).find("'plate'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("must be positive"), std::string::npos) << e.what();
  }
}

TEST_F(MeshWallsTest, CrossingOfTwoSidedWallIsUndone) {
  write_stl("plate.stl", plate_z(0, 1, 0, 1, 0.5));
  make_box();
  mesh("plate", "plate.stl");
  cmd("run 1");
  MeshWalls w(lmp.get(), {spec("plate", mpm::WALL_FREESLIP, 0, mpm::SIDE_BOTH)});
  w.refresh(kAll[0], kAll[1], 0.1);
  const double xo[3] = {0.4, 0.4, 0.52};
  double x[3] = {0.42, 0.4, 0.48}, v[3] = {1, 0, -2};
  EXPECT_TRUE(w.push_back(x, v, 0.075, xo));
  EXPECT_GT(x[2], 0.5);
  EXPECT_LT(x[2], 0.52);
  EXPECT_NEAR(x[0], 0.41, 1e-9);  // at the crossing point
  expect_v(v, 1, 0, 0);
  // no x_old: a two-sided wall has no 'behind'
  double y[3] = {0.42, 0.4, 0.48}, u[3] = {1, 0, -2};
  EXPECT_FALSE(w.push_back(y, u, 0.075));
  // a crossing beside the plate is not one
  const double xo2[3] = {1.2, 0.4, 0.52};
  double z[3] = {1.2, 0.4, 0.48}, uz[3] = {0, 0, -2};
  EXPECT_FALSE(w.push_back(z, uz, 0.075, xo2));
}

TEST_F(MeshWallsTest, ClosedBoxCornersAndInferredSide) {
  write_stl("box.stl", box_out(0.0, 1.0));
  make_box();
  mesh("walls", "box.stl");
  cmd("run 1");
  MeshWalls w(lmp.get(), {spec("walls", mpm::WALL_FREESLIP, 0, mpm::SIDE_AUTO)});
  w.refresh(kAll[0], kAll[1], 0.1);
  EXPECT_EQ(w.global_triangles(), 12);
  EXPECT_EQ(w.gathered(), 12);
  // fluid points inside the box (a lattice; those near the faces vote)
  std::vector<std::array<double, 3>> pts;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j)
      for (int k = 0; k < 10; ++k) pts.push_back({0.05 + 0.1 * i, 0.05 + 0.1 * j, 0.05 + 0.1 * k});
  std::vector<const double *> ptr;
  // every rank holds a share of the points
  int me = 0, np = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  MPI_Comm_size(MPI_COMM_WORLD, &np);
  for (size_t i = me; i < pts.size(); i += np) ptr.push_back(pts[i].data());
  const std::string log = w.infer_sides(ptr.data(), static_cast<int>(ptr.size()), 0.075);
  EXPECT_EQ(w.side(0), mpm::SIDE_OPPOSITE) << log;
  EXPECT_NE(log.find("opposite"), std::string::npos) << log;

  // inner corner (x = 0, y = 0, z = 0): approach removed on all three faces
  const double c[3] = {0.03, 0.04, 0.02};
  double v[3] = {-1, -2, 0.5};
  EXPECT_TRUE(w.apply(c, v, 0.075));
  expect_v(v, 0, 0, 0.5);
  // inner edge region of a face split along its diagonal: flow along the face is not slowed
  const double f[3] = {0.5, 0.5, 0.03};
  double u[3] = {1, -1, 0};
  w.apply(f, u, 0.075);
  expect_v(u, 1, -1, 0);
  // nodes exactly on a face's diagonal (the edge between its two triangles) and on a box edge
  // are on the wall: the approach is removed
  const double diag[3] = {0.0, 0.4, 0.4}, bedge[3] = {0.0, 0.3, 0.0};
  double dv[3] = {-1, 1, 1}, bv[3] = {-1, 1, -1};
  EXPECT_TRUE(w.apply(diag, dv, 0.075));
  EXPECT_TRUE(w.apply(bedge, bv, 0.075));
  expect_v(dv, 0, 1, 1);
  expect_v(bv, 0, 1, 0);
  // a node outside the box behind the face z = 0: normal velocity zeroed
  const double out[3] = {0.5, 0.4, -0.04};
  double o[3] = {1, 0, -1};
  w.apply(out, o, 0.075);
  expect_v(o, 1, 0, 0);
  // a point that leaked out through z = 0 comes back in
  double p[3] = {0.5, 0.4, -0.02}, pv[3] = {0, 0, -1};
  EXPECT_TRUE(w.push_back(p, pv, 0.075));
  EXPECT_GT(p[2], 0.0);
  EXPECT_LT(p[2], 1e-3);
  expect_v(pv, 0, 0, 0);
  // outside the box's edge x = 0, y = 0 (behind both faces, near neither face): the node's
  // velocity along the diagonal is zeroed both ways, the point comes back in across the edge
  const double oc[3] = {-0.03, -0.03, 0.5};
  double ov1[3] = {-1, -1, 0.3}, ov2[3] = {1, 1, 0.3};
  EXPECT_TRUE(w.apply(oc, ov1, 0.075));
  EXPECT_TRUE(w.apply(oc, ov2, 0.075));
  expect_v(ov1, 0, 0, 0.3);
  expect_v(ov2, 0, 0, 0.3);
  double pc[3] = {-0.02, -0.02, 0.5}, pcv[3] = {-1, -1, 0};
  EXPECT_TRUE(w.push_back(pc, pcv, 0.075));
  const double off = 1e-3 * 0.075 / std::sqrt(2.0);
  EXPECT_NEAR(pc[0], off, 1e-12);
  EXPECT_NEAR(pc[1], off, 1e-12);
  expect_v(pcv, 0, 0, 0);
  // a point lying exactly on a face that steps out is caught by the crossing test
  const double on[3] = {0.0, 0.5, 0.5};
  double step[3] = {-0.001, 0.5, 0.5}, sv[3] = {-1, 0, 0};
  EXPECT_TRUE(w.push_back(step, sv, 0.075, on));
  EXPECT_NEAR(step[0], 1e-3 * 0.075, 1e-12);
}

TEST_F(MeshWallsTest, NoAutoVoteIsAnError) {
  write_stl("plate.stl", plate_z(0, 1, 0, 1, 0.5));
  make_box();
  mesh("plate", "plate.stl");
  cmd("run 1");
  MeshWalls w(lmp.get(), {spec("plate", mpm::WALL_NOSLIP, 1, mpm::SIDE_AUTO)});
  w.refresh(kAll[0], kAll[1], 0.1);
  const double far[3] = {0.5, 0.5, 1.2};
  const double *ptr[1] = {far};
  EXPECT_THROW(w.infer_sides(ptr, 1, 0.075), std::runtime_error);
}

TEST_F(MeshWallsTest, BinsAgreeWithBruteForce) {
  write_stl("box.stl", box_out(0.1, 0.9));
  write_stl("plate.stl", {Tri{V3{0.2, 0.1, 0.3}, V3{0.8, 0.3, 0.7}, V3{0.3, 0.85, 0.45}}});
  make_box();
  mesh("walls", "box.stl");
  mesh("tilt", "plate.stl");
  cmd("fix spin all move/mesh mesh walls rotate origin 0.5 0.5 0.5 axis 0 0 1 period 2.0");
  cmd("run 1");
  std::vector<MeshWallSpec> s = {spec("walls", mpm::WALL_PARTIAL, 0.3, mpm::SIDE_OPPOSITE), spec("tilt", mpm::WALL_FREESLIP, 0, mpm::SIDE_BOTH)};
  MeshWalls a(lmp.get(), s), b(lmp.get(), s);
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  a.refresh(lo, hi, 0.08);
  b.refresh(lo, hi, 0.08);
  b.set_use_bins(false);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0.0, 1.0), V(-1.0, 1.0);
  int touched = 0;
  for (int i = 0; i < 20000; ++i) {
    const double x[3] = {U(rng), U(rng), U(rng)};
    double va[3] = {V(rng), V(rng), V(rng)}, vb[3] = {va[0], va[1], va[2]};
    const bool ta = a.apply(x, va, 0.06), tb = b.apply(x, vb, 0.06);
    ASSERT_EQ(ta, tb);
    touched += ta;
    for (int d = 0; d < 3; ++d) ASSERT_DOUBLE_EQ(va[d], vb[d]);
  }
  EXPECT_GT(touched, 1000);
  // the rotating box's wall velocity is omega x r: at the centre of the face x = 0.9 (r = 0.4),
  // |w| = 0.4 * pi; noslip on a node there gives it that velocity
  MeshWalls ns(lmp.get(), {spec("walls", mpm::WALL_NOSLIP, 1, mpm::SIDE_OPPOSITE)});
  ns.refresh(lo, hi, 0.08);
  double x[3] = {0.85, 0.5, 0.5}, v[3] = {0, 0, 0};
  // the box turned by 2 pi dt / T = pi/1000: find the node on the same radius as the face centre
  const double phi = M_PI * 1e-3;
  x[0] = 0.5 + 0.35 * std::cos(phi);
  x[1] = 0.5 + 0.35 * std::sin(phi);
  EXPECT_TRUE(ns.apply(x, v, 0.06));
  EXPECT_NEAR(v[0], -0.4 * M_PI * std::sin(phi), 1e-9);
  EXPECT_NEAR(v[1], 0.4 * M_PI * std::cos(phi), 1e-9);
  EXPECT_NEAR(v[2], 0.0, 1e-12);
}

TEST_F(MeshWallsTest, PatchesAwayFromTheMeshOwnerAndPeriodicImages) {
  // a plate near z = 0.6: with 2 ranks split along z at 0.5 it belongs to the upper rank; the
  // lower rank's patch reaches it only through the margin
  write_stl("plate.stl", plate_z(0, 1, 0, 1, 0.6));
  // a vertical plate x = 1.45 near the periodic face x = 1.5 (normal -x)
  write_stl("side.stl", {Tri{V3{1.45, 0, 0}, V3{1.45, 0, 1}, V3{1.45, 1, 0}}});
  make_box("p f f");
  mesh("plate", "plate.stl");
  mesh("side", "side.stl");
  cmd("run 1");
  MeshWalls w(lmp.get(), {spec("plate", mpm::WALL_NOSLIP), spec("side", mpm::WALL_NOSLIP, 1, mpm::SIDE_BOTH)});
  int me = 0, np = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  MPI_Comm_size(MPI_COMM_WORLD, &np);
  if (np == 2) {
    // the test is meaningful: the lower rank owns none of the plate's triangles
    auto *fm = dynamic_cast<LAMMPS_NS::FixMeshSurface *>(lmp->modify->fix[lmp->modify->find_fix("plate")]);
    ASSERT_NE(fm, nullptr);
    EXPECT_EQ(fm->triMesh()->sizeLocal(), me == 0 ? 0 : 2);
  }
  // patch below the plate (like a lower rank's patch + halo)
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 0.55};
  w.refresh(lo, hi, 0.1);
  const double x[3] = {0.5, 0.5, 0.55};  // 0.05 below the plate, behind it
  double v[3] = {1, 1, 1};
  EXPECT_TRUE(w.apply(x, v, 0.075));
  expect_v(v, 0, 0, 0);
  // a patch that extends past x = -0.5 (periodic images of the nodes near x = 1.5) sees the image
  // of the side plate at x = -0.55
  const double lo2[3] = {-0.7, 0, 0}, hi2[3] = {-0.5, 1, 0.5};
  w.refresh(lo2, hi2, 0.1);
  EXPECT_EQ(w.gathered(), 1);
  const double xi[3] = {-0.6, 0.2, 0.2};
  double vi[3] = {1, 1, 1};
  EXPECT_TRUE(w.apply(xi, vi, 0.075));
  expect_v(vi, 0, 0, 0);
  // an empty patch gets nothing and takes part in the collective calls
  const double e0[3] = {1, 1, 1}, e1[3] = {0, 0, 0};
  w.refresh(e0, e1, 0.1);
  EXPECT_EQ(w.gathered(), 0);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  int me = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  char name[256] = {0};
  if (me == 0) {
    char tmpl[] = "/tmp/mesh_walls_test_XXXXXX";
    if (!mkdtemp(tmpl)) return 2;
    snprintf(name, sizeof name, "%s", tmpl);
  }
  MPI_Bcast(name, sizeof name, MPI_CHAR, 0, MPI_COMM_WORLD);
  g_dir = name;
  if (me != 0) ::testing::GTEST_FLAG(print_time) = false;
  const int rc = RUN_ALL_TESTS();
  int all = 0;
  MPI_Allreduce(&rc, &all, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (me == 0) {
    const std::string rm = "rm -rf '" + g_dir + "'";
    if (std::system(rm.c_str()) != 0) std::fprintf(stderr, "could not remove %s\n", g_dir.c_str());
  }
  MPI_Finalize();
  return all;
}
