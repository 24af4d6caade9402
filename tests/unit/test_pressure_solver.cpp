// The pressure projection's operators (mpm/projection_ops.h) and hypre solve
// (mpm/pressure_solver.h) against exact solutions: second-order convergence
// with Dirichlet and wall boundaries, exact hydrostatics through a bed of
// varying fluid fraction, moving walls, periodicity, the projection itself,
// the checkerboard mode, 2 ranks against 1, and the failure path. Run with 1
// and 2 MPI ranks (figures printed on rank 0 are quoted in docs/theory/projection.md).
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "mpm/grid.h"
#include "mpm/pressure_solver.h"
#include "mpm/projection_ops.h"
#include "mpi_test_util.h"

namespace {

using mpm::kEmpty;
using mpm::kFluid;
using mpm::kSolid;

const double kPi = 3.14159265358979323846;

using mpm_test::rank_of;
using mpm_test::size_of;
bool root() { return rank_of(MPI_COMM_WORLD) == 0; }

// Deterministic value in [0, 1) of a global node (and a seed): the same on
// every rank and on every decomposition.
double hash01(int i, int j, int k, int seed) {
  std::uint64_t h = 1469598103934665603ull ^ std::uint64_t(seed) * 0x9E3779B97F4A7C15ull;
  for (int v : {i, j, k}) {
    h ^= std::uint64_t(std::int64_t(v) + 1000003);
    h *= 1099511628211ull;
    h ^= h >> 29;
  }
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 31;
  return double(h >> 11) * (1.0 / 9007199254740992.0);
}

// A grid on comm split into slabs along x (2 ranks: rank 0 up to split of the length).
struct Problem {
  mpm::GridSpec g;
  mpm::LocalGrid grid;
  mpm::ProjectionGeometry geo;
  mpm::NodeLabels lab;
  MPI_Comm comm;
  std::vector<double> beta, theta, rhs, p, pe, u;

  Problem(const mpm::GridSpec &spec, MPI_Comm c, double split = 0.5, bool half_cells = true) : g(spec), comm(c) {
    mpm_test::setup_slabs(grid, g, c, split, 2);
    geo.spec = g;
    geo.half_cells = half_cells;
    lab.reset(grid);
    const std::size_t n = grid.size();
    beta.assign(n, 1.0);
    theta.assign(n, 1.0);
    rhs.assign(n, 0.0);
    p.assign(n, 0.0);
    pe.assign(n, 0.0);
    u.assign(3 * n, 0.0);
  }
  int wrap(int d, int i) const {
    if (!g.periodic[d]) return i;
    const int n = g.ncell[d];
    return ((i % n) + n) % n;
  }
  double x(int d, int i) const { return g.origin[d] + i * g.dx; }
  // fn(i, j, k, n) over the whole patch (indices wrapped into the grid)
  void each_patch(const std::function<void(int, int, int, std::size_t)> &fn) const {
    const mpm::IndexBox &pb = grid.patch();
    for (int k = pb.lo[2]; k <= pb.hi[2]; ++k)
      for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
        for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) fn(wrap(0, i), wrap(1, j), wrap(2, k), grid.index(i, j, k));
  }
  double max_owned(const std::function<double(int, int, int, std::size_t)> &fn) const {
    double m = 0.0, all = 0.0;
    grid.for_owned([&](int i, int j, int k, std::size_t n) { m = std::max(m, fn(i, j, k, n)); });
    MPI_Allreduce(&m, &all, 1, MPI_DOUBLE, MPI_MAX, comm);
    return all;
  }
};

mpm::GridSpec cube(int nx, int ny, int nz, double dx) {
  mpm::GridSpec g;
  g.dx = dx;
  g.ncell[0] = nx;
  g.ncell[1] = ny;
  g.ncell[2] = nz;
  g.pad = 1;
  return g;
}

mpm::PressureSettings tight(double tol = 1e-11) {
  mpm::PressureSettings s;
  s.tolerance = tol;
  s.max_iterations = 500;
  return s;
}

// ---- 1. Manufactured solutions: second order ---------------------------------------------

// p = sin(pi x + .2) sin(pi y + .5) cos(pi z / 2 + c) / beta = theta / rho,
// theta = 0.7 + 0.3 sin(2 pi x) sin(2 pi y) sin(2 pi z) in [0.4, 1] (variable).
struct Exact {
  bool variable;
  bool neumann;  // p = cos(pi x) cos(pi y) cos(pi z / 2): zero normal gradient on x, y, z = 0 walls, 0 at z = 1
  double rho = 1000.0;
  double theta(double x, double y, double z) const {
    return variable ? 0.7 + 0.3 * std::sin(2 * kPi * x) * std::sin(2 * kPi * y) * std::sin(2 * kPi * z) : 1.0;
  }
  void dtheta(double x, double y, double z, double g[3]) const {
    const double a = 0.3 * 2 * kPi;
    g[0] = variable ? a * std::cos(2 * kPi * x) * std::sin(2 * kPi * y) * std::sin(2 * kPi * z) : 0.0;
    g[1] = variable ? a * std::sin(2 * kPi * x) * std::cos(2 * kPi * y) * std::sin(2 * kPi * z) : 0.0;
    g[2] = variable ? a * std::sin(2 * kPi * x) * std::sin(2 * kPi * y) * std::cos(2 * kPi * z) : 0.0;
  }
  // p, grad p, laplacian p
  double p(double x, double y, double z, double g[3], double *lap) const {
    if (neumann) {
      const double X = std::cos(kPi * x), Y = std::cos(kPi * y), Z = std::cos(kPi * z / 2);
      g[0] = -kPi * std::sin(kPi * x) * Y * Z;
      g[1] = -kPi * X * std::sin(kPi * y) * Z;
      g[2] = -kPi / 2 * X * Y * std::sin(kPi * z / 2);
      *lap = -(2.25 * kPi * kPi) * X * Y * Z;
      return X * Y * Z;
    }
    const double ax = kPi * x + 0.2, ay = kPi * y + 0.5, az = kPi * z + 0.7;
    const double v = std::sin(ax) * std::sin(ay) * std::sin(az);
    g[0] = kPi * std::cos(ax) * std::sin(ay) * std::sin(az);
    g[1] = kPi * std::sin(ax) * std::cos(ay) * std::sin(az);
    g[2] = kPi * std::sin(ax) * std::sin(ay) * std::cos(az);
    *lap = -3 * kPi * kPi * v;
    return v;
  }
  // div(beta grad p)
  double f(double x, double y, double z) const {
    double gp[3], gt[3], lap;
    p(x, y, z, gp, &lap);
    dtheta(x, y, z, gt);
    return (theta(x, y, z) * lap + gt[0] * gp[0] + gt[1] * gp[1] + gt[2] * gp[2]) / rho;
  }
};

// Max nodal error on the unit cube at N cells (Dirichlet: all six faces; Neumann:
// walls but the top). Optionally returns the iterations.
double manufactured_error(int N, const Exact &ex, bool half_cells, MPI_Comm comm, int *iters = nullptr) {
  Problem P(cube(N, N, N, 1.0 / N), comm, 0.5, half_cells);
  double gdum[3], lap;
  P.each_patch([&](int i, int j, int k, std::size_t n) {
    const double x = P.x(0, i), y = P.x(1, j), z = P.x(2, k);
    P.beta[n] = ex.theta(x, y, z) / ex.rho;
    if (P.lab.kind[n] == kSolid) return;
    const bool boundary = ex.neumann ? k == N : (i == 0 || i == N || j == 0 || j == N || k == 0 || k == N);
    if (boundary) {
      P.lab.kind[n] = kEmpty;
      P.pe[n] = ex.p(x, y, z, gdum, &lap);
    }
  });
  P.grid.for_owned([&](int i, int j, int k, std::size_t n) {
    P.rhs[n] = P.geo.volume(i, j, k) * ex.f(P.x(0, i), P.x(1, j), P.x(2, k));
  });
  mpm::PressureSolver solver(P.grid, comm, tight(), P.geo);
  const mpm::PressureResult r = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data(), P.pe.data());
  if (iters) *iters = r.iterations;
  return P.max_owned([&](int i, int j, int k, std::size_t n) {
    return P.lab.kind[n] == kFluid ? std::fabs(P.p[n] - ex.p(P.x(0, i), P.x(1, j), P.x(2, k), gdum, &lap)) : 0.0;
  });
}

void convergence(const Exact &ex, bool half_cells, const char *name, double min_rate) {
  const int Ns[3] = {8, 16, 32};
  double e[3];
  int it[3];
  for (int m = 0; m < 3; ++m) e[m] = manufactured_error(Ns[m], ex, half_cells, MPI_COMM_WORLD, &it[m]);
  const double r1 = std::log2(e[0] / e[1]), r2 = std::log2(e[1] / e[2]);
  if (root())
    std::printf("[ rates    ] %s: max error %.3e %.3e %.3e at 8^3 16^3 32^3 (PCG %d %d %d), rates %.3f %.3f\n", name,
                e[0], e[1], e[2], it[0], it[1], it[2], r1, r2);
  if (min_rate > 0) {
    EXPECT_GT(r1, min_rate) << name;
    EXPECT_GT(r2, min_rate) << name;
  }
}

TEST(PressureSolver, DirichletConstantBetaSecondOrder) { convergence({false, false}, true, "Dirichlet, beta constant", 1.8); }
TEST(PressureSolver, DirichletVariableBetaSecondOrder) { convergence({true, false}, true, "Dirichlet, theta in [0.4,1]", 1.8); }
TEST(PressureSolver, WallsHalfCellsSecondOrder) {
  convergence({true, true}, true, "walls (half cells) + top Dirichlet, theta in [0.4,1]", 1.8);
  // The alternative without half cells puts the walls half a cell behind the wall nodes.
  convergence({true, true}, false, "walls (full cells) + top Dirichlet, theta in [0.4,1]", 0.0);
}

// ---- 2. Hydrostatics through a bed, and a moving wall: exact -----------------------------

struct Column {
  Problem P;
  int top;  // last FLUID node layer
  Column(MPI_Comm comm, int top_layer) : P(cube(6, 5, 10, 0.1), comm, 0.37), top(top_layer) {
    P.each_patch([&](int i, int j, int k, std::size_t n) {
      P.theta[n] = 0.4 + 0.6 * hash01(i, j, k, 7);  // a random bed: theta in [0.4, 1]
      P.beta[n] = P.theta[n] / 1000.0;
      if (P.lab.kind[n] != kSolid && k > top) P.lab.kind[n] = kEmpty;
    });
  }
};

TEST(PressureSolver, HydrostaticBedExact) {
  Column C(MPI_COMM_WORLD, 6);
  Problem &P = C.P;
  const double rho = 1000.0, g = 9.81, dt = 1e-3;
  for (std::size_t n = 0; n < P.grid.size(); ++n) P.u[3 * n + 2] = -g * dt;
  mpm::pressure_rhs(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), nullptr, dt, P.rhs.data());
  mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(1e-12), P.geo);
  const mpm::PressureResult r = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
  const double zs = P.x(2, C.top + 1), pmax = rho * g * (zs - P.x(2, 0));
  const double err = P.max_owned([&](int, int, int k, std::size_t n) {
    return P.lab.kind[n] == kFluid ? std::fabs(P.p[n] - rho * g * (zs - P.x(2, k))) : 0.0;
  });
  // The rest state after the correction, on the nodes and on the faces.
  std::vector<double> grad(3 * P.grid.size()), inv_rho(P.grid.size(), 1.0 / rho), div(P.grid.size());
  mpm::pressure_gradient(P.grid, P.lab, P.p.data(), grad.data());
  mpm::correct_velocity(P.grid, P.lab, grad.data(), inv_rho.data(), dt, P.u.data());
  const double umax = P.max_owned([&](int, int, int, std::size_t n) {
    return P.lab.kind[n] == kFluid ? std::max({std::fabs(P.u[3 * n]), std::fabs(P.u[3 * n + 1]), std::fabs(P.u[3 * n + 2])}) : 0.0;
  });
  if (root())
    std::printf("[ hydro    ] random bed theta in [0.4,1], 6x5x10 cells: %d PCG iterations, max |p - rho g h| / p_floor = %.2e, "
                "max |u| / (g dt) after the correction = %.2e\n",
                r.iterations, err / pmax, umax / (g * dt));
  EXPECT_LT(err, 1e-9 * pmax);
  EXPECT_LT(umax, 1e-9 * g * dt);

  // The wiring's order matters: zeroing the wall nodes' normal velocity before the
  // projection (the wall condition of the eos model) breaks the rest state.
  std::fill(P.u.begin(), P.u.end(), 0.0);
  P.each_patch([&](int i, int j, int k, std::size_t n) {
    if (k > 0) P.u[3 * n + 2] = -g * dt;
  });
  std::vector<double> p0(P.grid.size(), 0.0);
  mpm::pressure_rhs(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), nullptr, dt, P.rhs.data());
  solver.solve(P.lab, P.beta.data(), P.rhs.data(), p0.data());
  mpm::pressure_gradient(P.grid, P.lab, p0.data(), grad.data());
  mpm::correct_velocity(P.grid, P.lab, grad.data(), inv_rho.data(), dt, P.u.data());
  const double ubad = P.max_owned([&](int, int, int k, std::size_t n) {
    return P.lab.kind[n] == kFluid && k > 0 ? std::fabs(P.u[3 * n + 2]) : 0.0;
  });
  if (root()) std::printf("[ hydro    ] floor nodes' w zeroed before the projection: max |u_z| / (g dt) above the floor = %.3f\n", ubad / (g * dt));
  EXPECT_GT(ubad, 0.1 * g * dt);
}

TEST(PressureSolver, WalledInFluidNodeIsLeftOut) {
  // A FLUID node whose six faces are all closed (in the rotating jar: box corner nodes outside
  // the jar mesh, docs/validation/jar.md "C4 with the projection") has a zero row. Before it was left out,
  // PFMG returned INF, PCG stopped at once with hypre's error flag and the old pressure (here 0)
  // stood as the answer. Now: p = 0 there, the rest of the bed hydrostatic (the node is an
  // obstacle; u* = -g dt is still exactly projected to rest), and enclosed = 1 on its rank.
  Column C(MPI_COMM_WORLD, 6);
  Problem &P = C.P;
  const double rho = 1000.0, g = 9.81, dt = 1e-3;
  const int c[3] = {4, 2, 3};
  P.grid.for_owned([&](int i, int j, int k, std::size_t) {
    const int q[3] = {i, j, k};
    for (int d = 0; d < 3; ++d) {
      int a[3] = {c[0], c[1], c[2]};
      a[d] -= 1;
      if (q[0] == c[0] && q[1] == c[1] && q[2] == c[2]) P.lab.close_face(P.grid, i, j, k, d);
      if (q[0] == a[0] && q[1] == a[1] && q[2] == a[2]) P.lab.close_face(P.grid, i, j, k, d);
    }
  });
  P.lab.exchange(P.grid, MPI_COMM_WORLD);
  for (std::size_t n = 0; n < P.grid.size(); ++n) P.u[3 * n + 2] = -g * dt;
  mpm::pressure_rhs(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), nullptr, dt, P.rhs.data());
  P.grid.for_owned([&](int i, int j, int k, std::size_t n) {
    if (i == c[0] && j == c[1] && k == c[2]) P.rhs[n] = 1e3;  // any value: the row has no coupling
  });
  mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(1e-12), P.geo);
  mpm::PressureResult r;
  ASSERT_NO_THROW(r = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data()));
  long enclosed = r.enclosed, genclosed = 0;
  MPI_Allreduce(&enclosed, &genclosed, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  const double zs = P.x(2, C.top + 1), pmax = rho * g * (zs - P.x(2, 0));
  const double err = P.max_owned([&](int i, int j, int k, std::size_t n) {
    if (P.lab.kind[n] != kFluid) return 0.0;
    if (i == c[0] && j == c[1] && k == c[2]) return std::fabs(P.p[n]);
    return std::fabs(P.p[n] - rho * g * (zs - P.x(2, k)));
  });
  if (root())
    std::printf("[ walled   ] one FLUID node walled in: %d PCG iterations, max |p - rho g h| / p_floor = %.2e, enclosed %ld\n",
                r.iterations, err / pmax, genclosed);
  EXPECT_EQ(genclosed, 1);
  EXPECT_LT(err, 1e-9 * pmax);
}

TEST(PressureSolver, SealedPocketIsMadeCompatible) {
  // A set of FLUID nodes that closed faces seal off from every EMPTY node (a pocket of water
  // between a lifter bar's faces and the drum: docs/theory/projection.md "Sealed pockets") has the
  // constants as null space. With a source that does not sum to zero over it (moving wall faces
  // around it) PCG diverged: the turning drum stopped with "did not converge". Now the pocket's
  // source is made compatible (its mean removed), one node held at 0 and p returned with zero
  // mean over the pocket; the rest of the bed, for which the pocket is an obstacle, is
  // hydrostatic. The 2 x 2 x 2 pocket straddles the ranks' cut in x (rank 0 up to x index 2).
  Column C(MPI_COMM_WORLD, 6);
  Problem &P = C.P;
  const double rho = 1000.0, g = 9.81, dt = 1e-3;
  auto pocket = [](int i, int j, int k) { return i >= 2 && i <= 3 && j >= 1 && j <= 2 && k >= 2 && k <= 3; };
  P.grid.for_owned([&](int i, int j, int k, std::size_t) {
    const int q[3] = {i, j, k};
    for (int d = 0; d < 3; ++d) {
      int a[3] = {i, j, k};
      a[d] += 1;
      if (pocket(q[0], q[1], q[2]) != pocket(a[0], a[1], a[2])) P.lab.close_face(P.grid, i, j, k, d);
    }
  });
  P.lab.exchange(P.grid, MPI_COMM_WORLD);
  for (std::size_t n = 0; n < P.grid.size(); ++n) P.u[3 * n + 2] = -g * dt;
  mpm::pressure_rhs(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), nullptr, dt, P.rhs.data());
  double vs[2] = {0, 0}, VS[2];
  P.grid.for_owned([&](int i, int j, int k, std::size_t n) {
    if (!pocket(i, j, k)) return;
    P.rhs[n] += 1e4 * hash01(i, j, k, 3);  // a source of nonzero sum: no solution as it stands
    vs[0] += P.rhs[n];
    vs[1] += 1.0;
  });
  MPI_Allreduce(vs, VS, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  const double mean = VS[0] / VS[1];
  mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(1e-12), P.geo);
  mpm::PressureResult r;
  ASSERT_NO_THROW(r = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data()));
  std::vector<double> Lp(P.grid.size());
  mpm::apply_laplacian(P.grid, P.lab, P.geo, P.beta.data(), P.p.data(), Lp.data());
  const double zs = P.x(2, C.top + 1), pmax = rho * g * (zs - P.x(2, 0));
  const double err_bed = P.max_owned([&](int i, int j, int k, std::size_t n) {
    if (P.lab.kind[n] != kFluid || pocket(i, j, k)) return 0.0;
    return std::fabs(P.p[n] - rho * g * (zs - P.x(2, k)));
  });
  const double err_pocket = P.max_owned([&](int i, int j, int k, std::size_t n) {
    return pocket(i, j, k) ? std::fabs(Lp[n] - (P.rhs[n] - mean)) : 0.0;
  });
  double ps = 0.0, PS = 0.0;
  P.grid.for_owned([&](int i, int j, int k, std::size_t n) { ps += pocket(i, j, k) ? P.p[n] : 0.0; });
  MPI_Allreduce(&ps, &PS, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  if (root())
    std::printf("[ pocket   ] sealed 2x2x2 pocket, source mean %.1f: %d PCG iterations, sealed %ld nodes in %ld set(s), "
                "max |p - rho g h| / p_floor = %.2e outside, max |L p - (rhs - mean)| / mean = %.2e inside, "
                "pocket mean p %.1e\n",
                mean, r.iterations, r.sealed, r.sealed_sets, err_bed / pmax, err_pocket / mean, PS / VS[1]);
  EXPECT_FALSE(r.singular);
  EXPECT_EQ(r.sealed, 8);
  EXPECT_EQ(r.sealed_sets, 1);
  EXPECT_LT(err_bed, 1e-9 * pmax);
  EXPECT_LT(err_pocket, 1e-8 * mean);
  EXPECT_LT(std::fabs(PS) / VS[1], 1e-9 * pmax);
}

TEST(PressureSolver, GhostSurfaceBetweenNodesExact) {
  // Ghost-fluid free surface (labels.level): the surface lies a fraction s of a cell above the
  // last FLUID layer (level +s / -(1 - s) on the two layers), for several s including the clamp.
  // The hydrostatic field with the surface at its place is then the exact discrete solution, and
  // the fluid is at rest after the correction, through a random bed.
  for (double s : {0.9, 0.5, 0.2, 0.01, 1e-4}) {
    Column C(MPI_COMM_WORLD, 6);
    Problem &P = C.P;
    const double rho = 1000.0, g = 9.81, dt = 1e-3;
    P.lab.level.assign(P.grid.size(), 0.0);
    P.each_patch([&](int, int, int k, std::size_t n) {
      P.lab.level[n] = (C.top + s - k) * 0.5;  // any positive multiple of the signed distance
      P.u[3 * n + 2] = -g * dt;
    });
    mpm::pressure_rhs(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), nullptr, dt, P.rhs.data());
    mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(1e-12), P.geo);
    const mpm::PressureResult r = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
    const double se = std::max(s, mpm::kMinSurfaceFraction);
    const double zs = P.x(2, C.top) + se * (P.x(2, 1) - P.x(2, 0)), pmax = rho * g * (zs - P.x(2, 0));
    const double err = P.max_owned([&](int, int, int k, std::size_t n) {
      return P.lab.kind[n] == kFluid ? std::fabs(P.p[n] - rho * g * (zs - P.x(2, k))) : 0.0;
    });
    std::vector<double> grad(3 * P.grid.size()), inv_rho(P.grid.size(), 1.0 / rho);
    mpm::pressure_gradient(P.grid, P.lab, P.p.data(), grad.data());
    mpm::correct_velocity(P.grid, P.lab, grad.data(), inv_rho.data(), dt, P.u.data());
    // FLUID nodes and the EMPTY layer above them (its velocity comes from the surface face)
    const double umax = P.max_owned([&](int, int, int k, std::size_t n) {
      return P.lab.kind[n] != kSolid && k <= C.top + 1 ? std::fabs(P.u[3 * n + 2]) : 0.0;
    });
    if (root())
      std::printf("[ ghost    ] surface %.4g cell above the last FLUID layer: %d PCG iterations, max |p - rho g h| / p_floor = "
                  "%.2e, max |u| / (g dt) = %.2e\n", s, r.iterations, err / pmax, umax / (g * dt));
    EXPECT_LT(err, 1e-9 * pmax);
    EXPECT_LT(umax, 1e-8 * g * dt);
  }
}

TEST(PressureSolver, GhostSurfaceOnANodePlaneIsWellConditioned) {
  // A surface a hair above the node layer top + 1 (levels +-1e-7, checkerwise, as grains
  // displacing a fluid filled up to a node plane leave them), its nodes labelled by the rule
  // make_labels applies (level_is_fluid). One surface node's level moved by delta moves the
  // surface there by 2 delta cells (level = half the signed distance here): the pressure may
  // change by at most about 2 rho g dx delta (bound: twice that). Measured: 0.45 rho g dx delta;
  // with 1e-9 as the FLUID bound instead of kLevelTie the +1e-7 nodes are FLUID with their surface
  // faces clamped, and the change is 11 rho g dx delta (docs/theory/projection.md, "np 2 against np 1
  // with grains and the ghost surface").
  const double rho = 1000.0, g = 9.81, dt = 1e-3, eps = 1e-7, delta = 1e-9;
  const int top = 6, ip = 2, jp = 3;  // a -eps node, between +eps ones
  std::vector<double> p0;
  double change = 0.0, pmax = 0.0, dx = 0.0;
  for (int run = 0; run < 2; ++run) {
    Column C(MPI_COMM_WORLD, top);
    Problem &P = C.P;
    dx = P.g.dx;
    P.lab.level.assign(P.grid.size(), 0.0);
    P.each_patch([&](int i, int j, int k, std::size_t n) {
      double lv = (top + 1 - k) * 0.5;
      if (k == top + 1) lv = ((i + j) % 2 ? -eps : eps) + (run == 1 && i == ip && j == jp ? delta : 0.0);
      P.lab.level[n] = lv;
      if (P.lab.kind[n] != kSolid) P.lab.kind[n] = mpm::level_is_fluid(lv) ? kFluid : kEmpty;
      P.u[3 * n + 2] = -g * dt;
    });
    mpm::pressure_rhs(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), nullptr, dt, P.rhs.data());
    mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(1e-13), P.geo);
    solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
    if (run == 0) {
      p0 = P.p;
      pmax = P.max_owned([&](int, int, int, std::size_t n) { return std::fabs(P.p[n]); });
    } else {
      change = P.max_owned([&](int, int, int, std::size_t n) {
        return P.lab.kind[n] == kFluid ? std::fabs(P.p[n] - p0[n]) : 0.0;
      });
    }
  }
  const double scale = rho * g * dx * delta;
  if (root())
    std::printf("[ ghost    ] surface levels +-%.0e on a node plane, one moved by %.0e: max |dp| = %.2e rho g dx delta "
                "(largest p %.3g Pa)\n", eps, delta, change / scale, pmax);
  EXPECT_GT(pmax, 0.5 * rho * g * top * dx);
  EXPECT_LT(change, 4.0 * scale);
}

TEST(PressureSolver, ActiveBoxGivesTheWholeBoxAnswer) {
  // Fluid in the lower 3, 8 and 2 of 11 node layers (random bed, random u*): hypre on the FLUID
  // nodes' bounding box (+ kActiveMargin) against hypre on the whole owned box. (A box that grows
  // with the fluid: the F2 dam break's front.csv is identical with and without it.)
  for (int top : {2, 7, 1}) {
    Column C(MPI_COMM_WORLD, top);
    Problem &P = C.P;
    P.each_patch([&](int i, int j, int k, std::size_t n) {
      for (int d = 0; d < 3; ++d) P.u[3 * n + d] = 1e-3 * (hash01(i, j, k, 11 + d) - 0.5);
    });
    mpm::pressure_rhs(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), nullptr, 1e-3, P.rhs.data());
    mpm::PressureSettings whole = tight(1e-12), act = tight(1e-12);
    whole.active_box = false;
    std::vector<double> pw(P.grid.size(), 0.0), pa(P.grid.size(), 0.0);
    mpm::PressureSolver sw(P.grid, MPI_COMM_WORLD, whole, P.geo), sa(P.grid, MPI_COMM_WORLD, act, P.geo);
    sw.solve(P.lab, P.beta.data(), P.rhs.data(), pw.data());
    sa.solve(P.lab, P.beta.data(), P.rhs.data(), pa.data());
    double pmax = 0.0;
    const double diff = P.max_owned([&](int, int, int, std::size_t n) {
      pmax = std::max(pmax, std::fabs(pw[n]));
      return std::fabs(pw[n] - pa[n]);
    });
    if (root()) std::printf("[ active   ] fluid up to layer %d: max |p_active - p_whole| = %.2e (max |p| %.2e)\n", top, diff, pmax);
    EXPECT_LT(diff, 1e-9 * pmax);
  }
}

TEST(PressureSolver, MovingFloorLiftsTheColumn) {
  // The floor (faces between the padding layer k = -1 and k = 0) rises at w; u* = 0.
  // theta uniform (0.6): through a bed of varying theta the fluid's speed would vary as 1 / theta.
  Column C(MPI_COMM_WORLD, 7);
  Problem &P = C.P;
  const double rho = 1000.0, dt = 1e-3, w = 0.05;
  for (std::size_t n = 0; n < P.grid.size(); ++n) {
    P.theta[n] = 0.6;
    P.beta[n] = 0.6 / rho;
  }
  const mpm::IndexBox &pb = P.grid.patch();
  if (pb.lo[2] <= -1)
    for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
      for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) P.lab.close_face(P.grid, i, j, -1, 2, w);
  P.lab.exchange(P.grid, MPI_COMM_WORLD);
  mpm::pressure_rhs(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), nullptr, dt, P.rhs.data());
  mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(1e-12), P.geo);
  solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
  std::vector<double> grad(3 * P.grid.size()), inv_rho(P.grid.size(), 1.0 / rho);
  mpm::pressure_gradient(P.grid, P.lab, P.p.data(), grad.data());
  mpm::correct_velocity(P.grid, P.lab, grad.data(), inv_rho.data(), dt, P.u.data());
  const double dev = P.max_owned([&](int, int, int, std::size_t n) {
    return P.lab.kind[n] == kFluid ? std::max({std::fabs(P.u[3 * n]), std::fabs(P.u[3 * n + 1]), std::fabs(P.u[3 * n + 2] - w)}) : 0.0;
  });
  if (root()) std::printf("[ piston   ] floor at w: max |u - w e_z| / w over the fluid = %.2e\n", dev / w);
  EXPECT_LT(dev, 1e-9 * w);
}

TEST(PressureSolver, FrontSourceIsThatOfTheRelaxedVelocity) {
  // relax_front_source (the film's front, docs/theory/projection.md "The step size") against an
  // independent form: the source of u* - (1 - f) u_old / s at the front nodes, that of u* elsewhere.
  // Random u*, u_old and theta, an EMPTY region (the upper third), a moving floor (its flux is the
  // wall's and stays in full) and a closed face inside the fluid.
  mpm::GridSpec g = cube(8, 6, 9, 0.1);
  Problem P(g, MPI_COMM_WORLD, 0.45);
  const double dt = 2e-3, f = 0.3, s = 1.04, c = (1.0 - f) / (s * dt);
  const std::size_t nn = P.grid.size();
  std::vector<double> uo(3 * nn), mix(3 * nn);
  std::vector<std::uint8_t> front(nn, 0);
  P.each_patch([&](int i, int j, int k, std::size_t n) {
    P.theta[n] = 0.5 + 0.5 * hash01(i, j, k, 7);
    for (int d = 0; d < 3; ++d) {
      P.u[3 * n + d] = hash01(i, j, k, 11 + d) - 0.5;
      uo[3 * n + d] = hash01(i, j, k, 21 + d) - 0.5;
      mix[3 * n + d] = P.u[3 * n + d] - (1.0 - f) * uo[3 * n + d] / s;
    }
    if (P.lab.kind[n] != kSolid && k >= 6) P.lab.kind[n] = kEmpty;
  });
  const mpm::IndexBox &pb = P.grid.patch();
  if (pb.lo[2] <= -1)
    for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
      for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) P.lab.close_face(P.grid, i, j, -1, 2, 0.07);
  P.grid.for_owned([&](int i, int j, int k, std::size_t) {
    if (i == 3 && j == 2 && k == 1) P.lab.close_face(P.grid, i, j, k, 0);
  });
  P.lab.exchange(P.grid, MPI_COMM_WORLD);
  // front: the top FLUID layer, every other node, and the nodes on the floor and beside the closed face
  P.grid.for_owned([&](int i, int j, int k, std::size_t n) {
    front[n] = P.lab.kind[n] == kFluid && ((k == 5 && (i + j) % 2 == 0) || k == 0 || (j == 2 && k == 1 && i >= 3));
  });
  std::vector<double> want(nn, 0.0);
  mpm::pressure_rhs(P.grid, P.lab, P.geo, mix.data(), P.theta.data(), nullptr, dt, want.data());
  std::vector<double> plain(nn, 0.0);
  mpm::pressure_rhs(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), nullptr, dt, plain.data());
  P.rhs = plain;
  mpm::relax_front_source(P.grid, P.lab, P.geo, front.data(), uo.data(), P.theta.data(), c, P.rhs.data());
  long fronts = 0, moved = 0;
  P.grid.for_owned([&](int, int, int, std::size_t n) {
    fronts += front[n];
    moved += std::fabs(P.rhs[n] - plain[n]) > 1e-9;
  });
  const double err = P.max_owned([&](int, int, int, std::size_t n) {
    return std::fabs(P.rhs[n] - (front[n] ? want[n] : plain[n])) / (std::fabs(plain[n]) + 1.0);
  });
  if (root()) std::printf("[ front    ] relaxed source against that of the mixed velocity: %.2e\n", err);
  EXPECT_LT(err, 1e-12);
  EXPECT_GT(fronts, 0);
  EXPECT_EQ(moved, fronts);  // (the front nodes only, each of them)
}

// ---- 3. Periodic dimension: an exact discrete eigenmode ------------------------------------

// beta3 (per direction, the same at every node; null: beta in all three): the coefficients of the
// faces along each direction (PressureSolver::solve's beta3, the projection's exact exchange)
void periodic_mode(int nx, double split, const double *beta3 = nullptr) {
  // x periodic (nx cells), y and z: p = 0 on the faces. p = sin(2 pi x / Lx + .3) sin(pi y) sin(pi z)
  // is an eigenvector of the 7-point operator: L p = -sum_d beta_d 4 sin^2(k_d dx / 2) / dx^2 p.
  const double dx = 1.0 / 8;
  mpm::GridSpec g = cube(nx, 8, 8, dx);
  g.periodic[0] = true;
  Problem P(g, MPI_COMM_WORLD, split);
  const double beta = 1e-3, Lx = nx * dx, k[3] = {2 * kPi / Lx, kPi, kPi};
  double lam = 0.0;
  for (int d = 0; d < 3; ++d) lam -= (beta3 ? beta3[d] : beta) * 4 * std::pow(std::sin(k[d] * dx / 2), 2) / (dx * dx);
  std::vector<double> b3;
  if (beta3)
    for (std::size_t n = 0; n < P.grid.size(); ++n) b3.insert(b3.end(), beta3, beta3 + 3);
  auto exact = [&](int i, int j, int kk) {
    return std::sin(k[0] * P.x(0, i) + 0.3) * std::sin(k[1] * P.x(1, j)) * std::sin(k[2] * P.x(2, kk));
  };
  P.each_patch([&](int i, int j, int kk, std::size_t n) {
    P.beta[n] = beta;
    if (P.lab.kind[n] != kSolid && (j == 0 || j == 8 || kk == 0 || kk == 8)) P.lab.kind[n] = kEmpty;
  });
  P.grid.for_owned([&](int i, int j, int kk, std::size_t n) { P.rhs[n] = lam * exact(i, j, kk); });
  mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(), P.geo);
  const mpm::PressureResult r =
      solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data(), nullptr, beta3 ? b3.data() : nullptr);
  const double err = P.max_owned([&](int i, int j, int kk, std::size_t n) {
    return P.lab.kind[n] == kFluid ? std::fabs(P.p[n] - exact(i, j, kk)) : 0.0;
  });
  // The halo images across the periodic face carry the wrapped values.
  double herr = 0.0;
  P.each_patch([&](int i, int j, int kk, std::size_t n) {
    if (P.lab.kind[n] == kFluid) herr = std::max(herr, std::fabs(P.p[n] - exact(i, j, kk)));
  });
  if (root())
    std::printf("[ periodic ] x periodic, %d cells%s: %d PCG iterations, max error %.2e (halo images %.2e)\n", nx,
                beta3 ? ", beta per direction" : "", r.iterations, err, herr);
  EXPECT_LT(err, 1e-8);
  EXPECT_LT(herr, 1e-8);
}

TEST(PressureSolver, PeriodicModeExactPowerOfTwo) { periodic_mode(16, 0.5); }
TEST(PressureSolver, PeriodicModeExactTwelveCells) { periodic_mode(12, 0.29); }
// the faces' coefficients per direction (beta3): the mode's eigenvalue with beta_d along d; with
// the scalar beta the same mode would leave an error of the order of the coefficients' spread
TEST(PressureSolver, PeriodicModeExactBetaPerDirection) {
  const double b3[3] = {2.5e-3, 1e-3, 0.6e-3};
  periodic_mode(12, 0.29, b3);
}

// ---- 4. The projection ----------------------------------------------------------------------

struct ProjectionRun {
  double face_ratio;    // max |D(faces after) + V dtheta/dt| / max |initial|
  double nodal_ratio;   // the same for the corrected nodal field (approximate projection)
  double nodal_inner;   // the same, nodes at least 3 cells from walls and free surface
  double second_change; // max |u2 - u1| / max |u1 - u*| (a second projection of the nodal field)
  double second_inner;  // the same, nodes at least 3 cells from walls and free surface
  double cb_content;    // |sum (-1)^(i+j+k) p| / sum |p| over FLUID nodes
  int iterations;
};

// Closed box of N^3 cells, free surface above 2/3 of the height, theta in [0.4,1]
// and a d(theta)/dt source; u* random (smooth = false) or a smooth field.
ProjectionRun project(int N, bool smooth, MPI_Comm comm, std::vector<double> *p_out = nullptr) {
  Problem P(cube(N, N, N, 1.0 / N), comm, 0.41);
  const double rho = 1000.0, dt = 1e-3;
  const int top = (2 * N) / 3;
  std::vector<double> theta_prev(P.grid.size());
  P.each_patch([&](int i, int j, int k, std::size_t n) {
    const double x = P.x(0, i), y = P.x(1, j), z = P.x(2, k);
    if (smooth) {
      P.theta[n] = 0.7 + 0.3 * std::sin(2 * kPi * x) * std::cos(2 * kPi * y) * std::sin(kPi * z);
      theta_prev[n] = P.theta[n] - 1e-4 * std::cos(kPi * x) * std::cos(kPi * y);
      P.u[3 * n] = std::sin(kPi * y) * std::cos(2 * kPi * z);
      P.u[3 * n + 1] = std::sin(2 * kPi * x) * std::sin(kPi * z);
      P.u[3 * n + 2] = std::cos(kPi * x) * std::sin(kPi * y) - 0.5;
    } else {
      P.theta[n] = 0.4 + 0.6 * hash01(i, j, k, 11);
      theta_prev[n] = P.theta[n] + 0.01 * (hash01(i, j, k, 12) - 0.5);
      for (int d = 0; d < 3; ++d) P.u[3 * n + d] = 2 * hash01(i, j, k, 13 + d) - 1;
    }
    P.beta[n] = P.theta[n] / rho;
    if (P.lab.kind[n] != kSolid && k > top) P.lab.kind[n] = kEmpty;
  });
  const std::size_t nn = P.grid.size();
  auto inner = [&](int i, int j, int k) {
    return std::min({i, j, k, N - i, N - j, top - k}) >= 3;
  };
  // max |D + V dtheta/dt| over FLUID nodes (only the inner ones)
  auto continuity = [&](const std::vector<double> &div, bool only_inner = false) {
    return P.max_owned([&](int i, int j, int k, std::size_t n) {
      if (P.lab.kind[n] != kFluid || (only_inner && !inner(i, j, k))) return 0.0;
      return std::fabs(div[n] + P.geo.volume(i, j, k) * (P.theta[n] - theta_prev[n]) / dt);
    });
  };
  std::vector<double> div(nn), grad(3 * nn), inv_rho(nn, 1.0 / rho);
  mpm::flux_divergence(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), div.data());
  const double c0 = continuity(div), c0_inner = continuity(div, true);

  mpm::PressureSolver solver(P.grid, comm, tight(1e-10), P.geo);
  auto project_once = [&](std::vector<double> &u, std::vector<double> &p) {
    mpm::pressure_rhs(P.grid, P.lab, P.geo, u.data(), P.theta.data(), theta_prev.data(), dt, P.rhs.data());
    const mpm::PressureResult r = solver.solve(P.lab, P.beta.data(), P.rhs.data(), p.data());
    mpm::corrected_flux_divergence(P.grid, P.lab, P.geo, u.data(), P.theta.data(), P.beta.data(), p.data(), dt, div.data());
    mpm::pressure_gradient(P.grid, P.lab, p.data(), grad.data());
    mpm::correct_velocity(P.grid, P.lab, grad.data(), inv_rho.data(), dt, u.data());
    P.grid.forward(u.data(), 3);
    return r.iterations;
  };
  ProjectionRun out;
  std::vector<double> u1 = P.u, p1(nn, 0.0);
  out.iterations = project_once(u1, p1);
  out.face_ratio = continuity(div) / c0;
  mpm::flux_divergence(P.grid, P.lab, P.geo, u1.data(), P.theta.data(), div.data());
  out.nodal_ratio = continuity(div) / c0;
  out.nodal_inner = continuity(div, true) / c0_inner;
  std::vector<double> u2 = u1, p2(nn, 0.0);
  project_once(u2, p2);
  auto change = [&](const std::vector<double> &a, const std::vector<double> &b, bool only_inner) {
    return P.max_owned([&](int i, int j, int k, std::size_t n) {
      if (P.lab.kind[n] != kFluid || (only_inner && !inner(i, j, k))) return 0.0;
      double m = 0;
      for (int d = 0; d < 3; ++d) m = std::max(m, std::fabs(a[3 * n + d] - b[3 * n + d]));
      return m;
    });
  };
  const double d21 = change(u2, u1, false), d10 = change(u1, P.u, false);
  out.second_inner = change(u2, u1, true) / change(u1, P.u, true);
  out.second_change = d21 / d10;
  double s[2] = {0, 0}, S[2];
  P.grid.for_owned([&](int i, int j, int k, std::size_t n) {
    if (P.lab.kind[n] != kFluid) return;
    s[0] += ((i + j + k) % 2 ? -1.0 : 1.0) * p1[n];
    s[1] += std::fabs(p1[n]);
  });
  MPI_Allreduce(s, S, 2, MPI_DOUBLE, MPI_SUM, comm);
  out.cb_content = std::fabs(S[0]) / S[1];
  if (p_out) {
    // gathered owned values by global index, for the comparison of decompositions
    const int M = N + 3;
    std::vector<double> mine(std::size_t(M) * M * M, 0.0);
    P.grid.for_owned([&](int i, int j, int k, std::size_t n) {
      mine[(std::size_t(k + 1) * M + (j + 1)) * M + (i + 1)] = p1[n];
    });
    p_out->assign(mine.size(), 0.0);
    MPI_Allreduce(mine.data(), p_out->data(), int(mine.size()), MPI_DOUBLE, MPI_SUM, comm);
  }
  return out;
}

TEST(PressureSolver, ProjectionRandomField) {
  const ProjectionRun r = project(16, false, MPI_COMM_WORLD);
  if (root())
    std::printf("[ project  ] random u*, 16^3, bed + free surface + dtheta/dt: %d PCG iterations; continuity residual / initial: "
                "faces %.2e, nodes %.3f (inner %.3f); 2nd projection changes u by %.3f (inner %.3f) of the 1st; checkerboard content of p %.2e\n",
                r.iterations, r.face_ratio, r.nodal_ratio, r.nodal_inner, r.second_change, r.second_inner, r.cb_content);
  EXPECT_LT(r.face_ratio, 1e-8);
  // Measured 0.3 to 0.5 here: the nodal field of an approximate projection is not
  // discretely divergence free, only the face field is.
  EXPECT_LT(r.nodal_ratio, 1.0);
}

TEST(PressureSolver, ProjectionSmoothFieldConverges) {
  // For a smooth field the nodal field's defect and the change by a second
  // projection fall with the cell away from the boundaries (measured about 3x per
  // halving at 3 cells from them: the approximation error of the projection). The
  // largest defect sits on the last FLUID layer under the free surface, where p has
  // a kink (p = 0 above it); it does not fall with the cell (docs/theory/projection.md).
  ProjectionRun r[2] = {project(12, true, MPI_COMM_WORLD), project(24, true, MPI_COMM_WORLD)};
  if (root())
    for (int m = 0; m < 2; ++m)
      std::printf("[ project  ] smooth u*, %d^3: faces %.2e, nodes %.3e (inner %.3e), 2nd projection change %.3e (inner %.3e), PCG %d\n",
                  12 * (m + 1), r[m].face_ratio, r[m].nodal_ratio, r[m].nodal_inner, r[m].second_change, r[m].second_inner,
                  r[m].iterations);
  for (int m = 0; m < 2; ++m) EXPECT_LT(r[m].face_ratio, 1e-8);
  EXPECT_LT(r[1].nodal_inner, r[0].nodal_inner / 2.5);
  EXPECT_LT(r[1].second_inner, r[0].second_inner / 2.5);
}

// ---- 5. Checkerboard ----------------------------------------------------------------------------

TEST(PressureSolver, CheckerboardIsTheStiffestModeNotANullMode) {
  // Fully periodic, all FLUID (singular: constants only). A checkerboard source
  // (-1)^(i+j+k) is an eigenvector of the compact operator with the largest
  // eigenvalue 12 beta / dx^2: the answer is p = -dx^2 / (12 beta) times the source,
  // bounded by the source and not amplified (a collocated central-difference
  // Laplacian would have the checkerboard in its null space: no solution).
  mpm::GridSpec g = cube(8, 8, 8, 0.1);
  for (int d = 0; d < 3; ++d) g.periodic[d] = true;
  Problem P(g, MPI_COMM_WORLD);
  const double beta = 2e-3;
  auto cb = [](int i, int j, int k) { return (i + j + k) % 2 ? -1.0 : 1.0; };
  P.each_patch([&](int, int, int, std::size_t n) { P.beta[n] = beta; });
  P.grid.for_owned([&](int i, int j, int k, std::size_t n) { P.rhs[n] = cb(i, j, k); });
  mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(), P.geo);
  const mpm::PressureResult r = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
  const double amp = g.dx * g.dx / (12 * beta);
  const double err = P.max_owned([&](int i, int j, int k, std::size_t n) { return std::fabs(P.p[n] + amp * cb(i, j, k)); });
  if (root())
    std::printf("[ checker  ] periodic 8^3: singular %d, %d PCG iterations, max |p + dx^2/(12 beta) cb| / amplitude = %.2e\n",
                int(r.singular), r.iterations, err / amp);
  EXPECT_TRUE(r.singular);
  EXPECT_LT(err, 1e-8 * amp);

  // The nodal gradient of the checkerboard is zero (a mean of two face gradients
  // of opposite sign), and a nodal velocity checkerboard has zero face flux:
  // both odd-even modes are invisible to the nodal operators, which is why the
  // pressure must come from the compact face operator above (docs/theory/projection.md).
  std::vector<double> grad(3 * P.grid.size()), div(P.grid.size());
  P.each_patch([&](int i, int j, int k, std::size_t n) {
    P.p[n] = cb(i, j, k);
    P.u[3 * n] = cb(i, j, k);
    P.theta[n] = 1.0;
  });
  mpm::pressure_gradient(P.grid, P.lab, P.p.data(), grad.data());
  mpm::flux_divergence(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), div.data());
  const double gmax = P.max_owned([&](int, int, int, std::size_t n) {
    return std::max({std::fabs(grad[3 * n]), std::fabs(grad[3 * n + 1]), std::fabs(grad[3 * n + 2])});
  });
  const double dmax = P.max_owned([&](int, int, int, std::size_t n) { return std::fabs(div[n]); });
  EXPECT_EQ(gmax, 0.0);
  EXPECT_EQ(dmax, 0.0);
}

// With no EMPTY node the solve answers the compatible source (the FLUID nodes' source less its
// mean): the largest |L p - compatible source| over the owned FLUID nodes; the mean and the number
// of FLUID nodes (all ranks) through the pointers.
double compatible_source_error(Problem &P, double *mean_out, double *count_out = nullptr) {
  double loc[2] = {0.0, 0.0}, glob[2];
  P.grid.for_owned([&](int, int, int, std::size_t n) {
    if (P.lab.kind[n] != kFluid) return;
    loc[0] += P.rhs[n];
    loc[1] += 1.0;
  });
  MPI_Allreduce(loc, glob, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  const double mean = glob[0] / glob[1];
  std::vector<double> Lp(P.grid.size());
  mpm::apply_laplacian(P.grid, P.lab, P.geo, P.beta.data(), P.p.data(), Lp.data());
  *mean_out = mean;
  if (count_out) *count_out = glob[1];
  return P.max_owned([&](int, int, int, std::size_t n) {
    return P.lab.kind[n] == kFluid ? std::fabs(Lp[n] - (P.rhs[n] - mean)) : 0.0;
  });
}

TEST(PressureSolver, ClosedBoxFullOfFluid) {
  // No EMPTY node: the constants are the null space. A random source is made
  // compatible (its mean removed) and the answer has zero mean; L p then equals
  // the compatible source.
  Problem P(cube(10, 7, 9, 0.1), MPI_COMM_WORLD, 0.45);
  P.each_patch([&](int i, int j, int k, std::size_t n) { P.beta[n] = (0.4 + 0.6 * hash01(i, j, k, 8)) / 1000.0; });
  P.grid.for_owned([&](int i, int j, int k, std::size_t n) {
    if (P.lab.kind[n] == kFluid) P.rhs[n] = hash01(i, j, k, 9) - 0.3;
  });
  mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(1e-10), P.geo);
  const mpm::PressureResult r = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
  double mean = 0.0, count = 0.0;
  const double err = compatible_source_error(P, &mean, &count);
  double ps = 0, PS;
  P.grid.for_owned([&](int, int, int, std::size_t n) { ps += P.lab.kind[n] == kFluid ? P.p[n] : 0.0; });
  MPI_Allreduce(&ps, &PS, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  if (root())
    std::printf("[ neumann  ] closed box full of fluid, random beta and source: %d PCG iterations, mean removed %.4f "
                "(expected %.4f), max |L p - compatible source| %.1e\n",
                r.iterations, r.rhs_mean_removed, mean, err);
  EXPECT_TRUE(r.singular);
  EXPECT_NEAR(r.rhs_mean_removed, mean, 1e-12);
  EXPECT_LT(err, 1e-7);
  EXPECT_LT(std::fabs(PS) / count, 1e-12);
}

// A box periodic along all three directions, full of fluid with a fluid fraction that varies over
// two decades and a random source, for 40 seeds: every solve converges to L p = the compatible
// source. Returns the number of solves that did not converge.
int periodic_random_fields(int nx, int ny, int nz) {
  mpm::GridSpec g = cube(nx, ny, nz, 0.0045);
  for (int d = 0; d < 3; ++d) g.periodic[d] = true;
  int worst_iterations = 0, failed = 0;
  double worst = 0.0;
  for (int seed = 0; seed < 40; ++seed) {
    Problem P(g, MPI_COMM_WORLD, 0.5);
    P.each_patch([&](int i, int j, int k, std::size_t n) { P.beta[n] = std::pow(10.0, -2.0 * hash01(i, j, k, 100 + seed)) / 1000.0; });
    P.grid.for_owned([&](int i, int j, int k, std::size_t n) { P.rhs[n] = hash01(i, j, k, 200 + seed) - 0.5; });
    mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(1e-10), P.geo);
    try {
      const mpm::PressureResult r = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
      worst_iterations = std::max(worst_iterations, r.iterations);
      double mean = 0.0;
      worst = std::max(worst, compatible_source_error(P, &mean));
    } catch (const mpm::PressureSolveError &e) {
      ++failed;
      if (root()) std::printf("[ periodic ] %d x %d x %d, seed %d: %s\n", nx, ny, nz, seed, e.what());
    }
  }
  if (root())
    std::printf("[ periodic ] %d x %d x %d fully periodic, 40 random fields: %d did not converge, at most %d PCG "
                "iterations, max |L p - compatible source| %.1e\n", nx, ny, nz, failed, worst_iterations, worst);
  EXPECT_LT(worst, 1e-6);
  return failed;
}

TEST(PressureSolver, PeriodicBoxOfOddLengthConverges) {
  // The coarsening of PFMG stops at a periodic direction of odd length (the fluidized bed's
  // 4 x 4 x 19 cells at 2 x 2 x 19). With Galerkin coarse operators and weighted Jacobi, PCG broke
  // down on 23 / 32 / 16 / 2 of the 40 fields of these boxes (a few iterations, then a residual of
  // order 0.1); not on 4 x 4 x 20, 8 x 8 x 8 or 6 x 6 x 6.
  EXPECT_EQ(periodic_random_fields(4, 4, 19), 0);
  EXPECT_EQ(periodic_random_fields(2, 2, 19), 0);
  EXPECT_EQ(periodic_random_fields(8, 8, 19), 0);
  EXPECT_EQ(periodic_random_fields(4, 4, 9), 0);
  EXPECT_EQ(periodic_random_fields(8, 8, 8), 0);
}

// ---- 6. Two ranks against one --------------------------------------------------------------------

TEST(PressureSolver, TwoRanksMatchOne) {
  std::vector<double> pd, ps;
  project(16, false, MPI_COMM_WORLD, &pd);
  project(16, false, MPI_COMM_SELF, &ps);  // every rank alone
  double diff = 0.0, pmax = 0.0;
  for (std::size_t n = 0; n < pd.size(); ++n) {
    diff = std::max(diff, std::fabs(pd[n] - ps[n]));
    pmax = std::max(pmax, std::fabs(ps[n]));
  }
  if (root())
    std::printf("[ ranks    ] %d ranks against 1: max |p difference| / max |p| = %.2e\n", size_of(MPI_COMM_WORLD),
                diff / pmax);
  EXPECT_LT(diff, 1e-8 * pmax);
}

// ---- 7. Failure, warm start, reuse -------------------------------------------------------------

TEST(PressureSolver, NoConvergenceThrowsWithIterationsAndResidual) {
  Column C(MPI_COMM_WORLD, 6);
  Problem &P = C.P;
  P.grid.for_owned([&](int i, int j, int k, std::size_t n) { P.rhs[n] = P.lab.kind[n] == kFluid ? hash01(i, j, k, 3) - 0.5 : 0.0; });
  mpm::PressureSettings s;
  s.tolerance = 1e-12;
  s.max_iterations = 1;
  mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, s, P.geo);
  try {
    solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
    FAIL() << "no exception";
  } catch (const mpm::PressureSolveError &e) {
    const std::string m = e.what();
    if (root()) std::printf("[ failure  ] %s\n", e.what());
    EXPECT_EQ(e.iterations, 1);
    EXPECT_GT(e.residual, 1e-12);
    EXPECT_NE(m.find("1 PCG iterations"), std::string::npos) << m;
    EXPECT_NE(m.find("relative residual"), std::string::npos) << m;
  }
  EXPECT_THROW(mpm::PressureSolver(P.grid, MPI_COMM_WORLD, mpm::PressureSettings{0.0, 10}, P.geo), std::invalid_argument);
  EXPECT_THROW(mpm::PressureSolver(P.grid, MPI_COMM_WORLD, mpm::PressureSettings{1e-8, 0}, P.geo), std::invalid_argument);
}

TEST(PressureSolver, WarmStartAndReuse) {
  Column C(MPI_COMM_WORLD, 6);
  Problem &P = C.P;
  P.grid.for_owned([&](int i, int j, int k, std::size_t n) { P.rhs[n] = P.lab.kind[n] == kFluid ? hash01(i, j, k, 3) - 0.5 : 0.0; });
  mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, tight(1e-9), P.geo);
  const mpm::PressureResult cold = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
  const mpm::PressureResult warm = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
  if (root())
    std::printf("[ warm     ] cold start %d PCG iterations (rebuilt %d), warm start from the solution %d (rebuilt %d, residual %.1e)\n",
                cold.iterations, int(cold.rebuilt), warm.iterations, int(warm.rebuilt), warm.relative_residual);
  EXPECT_TRUE(cold.rebuilt);
  EXPECT_FALSE(warm.rebuilt);
  EXPECT_LE(warm.iterations, 1);

  // New coefficients on the same solver give the fresh solver's answer.
  std::vector<double> beta2 = P.beta, p_reused(P.p), p_fresh(P.p.size(), 0.0);
  for (double &b : beta2) b *= 1.5;
  const mpm::PressureResult again = solver.solve(P.lab, beta2.data(), P.rhs.data(), p_reused.data());
  mpm::PressureSolver fresh(P.grid, MPI_COMM_WORLD, tight(1e-9), P.geo);
  fresh.solve(P.lab, beta2.data(), P.rhs.data(), p_fresh.data());
  const double diff = P.max_owned([&](int, int, int, std::size_t n) { return std::fabs(p_reused[n] - p_fresh[n]); });
  const double pm = P.max_owned([&](int, int, int, std::size_t n) { return std::fabs(p_fresh[n]); });
  EXPECT_TRUE(again.rebuilt);
  EXPECT_LT(diff, 1e-7 * pm);
  // and the first answer scaled: beta x 1.5 -> p / 1.5
  const double scale = P.max_owned([&](int, int, int, std::size_t n) { return std::fabs(1.5 * p_fresh[n] - P.p[n]); });
  EXPECT_LT(scale, 1e-7 * pm * 1.5);
}

// ---- Timing (not run by CTest: --gtest_also_run_disabled_tests) -------------------------------

TEST(PressureSolver, DISABLED_Timing) {
  for (int N : {32, 64}) {
    Problem P(cube(N, N, N, 1.0 / N), MPI_COMM_WORLD, 0.5);
    const int top = (2 * N) / 3;
    const double rho = 1000.0, dt = 1e-3;
    std::vector<double> theta_prev(P.grid.size());
    P.each_patch([&](int i, int j, int k, std::size_t n) {
      // a bed (theta 0.4 .. 0.6) in the lower third, water above, free surface at 2/3
      P.theta[n] = k < N / 3 ? 0.4 + 0.2 * hash01(i, j, k, 5) : 1.0;
      theta_prev[n] = P.theta[n];
      P.beta[n] = P.theta[n] / rho;
      P.u[3 * n + 2] = -9.81 * dt;
      for (int d = 0; d < 3; ++d) P.u[3 * n + d] += 0.1 * (hash01(i, j, k, 20 + d) - 0.5);
      if (P.lab.kind[n] != kSolid && k > top) P.lab.kind[n] = kEmpty;
    });
    mpm::pressure_rhs(P.grid, P.lab, P.geo, P.u.data(), P.theta.data(), theta_prev.data(), dt, P.rhs.data());
    for (auto pc : {mpm::PressureSettings::Preconditioner::PFMG, mpm::PressureSettings::Preconditioner::SMG}) {
      mpm::PressureSettings s;
      s.tolerance = 1e-8;
      s.preconditioner = pc;
      std::fill(P.p.begin(), P.p.end(), 0.0);
      mpm::PressureSolver solver(P.grid, MPI_COMM_WORLD, s, P.geo);
      const mpm::PressureResult a = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
      // next step: a slightly different rhs, warm start, same matrix
      for (double &r : P.rhs) r *= 1.01;
      const mpm::PressureResult b = solver.solve(P.lab, P.beta.data(), P.rhs.data(), P.p.data());
      for (double &r : P.rhs) r /= 1.01;
      // a new matrix (grains moved: beta changed by 1 %), warm start
      std::vector<double> beta2(P.beta);
      for (double &x : beta2) x *= 1.0 + 0.01 * double((&x - beta2.data()) % 3);
      const mpm::PressureResult c = solver.solve(P.lab, beta2.data(), P.rhs.data(), P.p.data());
      if (root())
        std::printf("[ timing   ] %d^3 cells, %d ranks, %s: cold %d it (setup %.3f s + solve %.3f s); warm, same matrix %d it "
                    "%.3f s; warm, new matrix %d it (setup %.3f + solve %.3f s)\n",
                    N, size_of(MPI_COMM_WORLD), pc == mpm::PressureSettings::Preconditioner::PFMG ? "PFMG" : "SMG",
                    a.iterations, a.setup_seconds, a.solve_seconds, b.iterations, b.solve_seconds, c.iterations,
                    c.setup_seconds, c.solve_seconds);
    }
  }
}

}  // namespace

// The level (projection_ops.h, surface_distance): the nodes below and above a plane surface with
// the fluid's points on the fill's lattice (np per cell, the top layer half a spacing below the
// surface) read the signed distance to the plane, whether the plane lies on a node plane, mid-cell
// or in between, with 1, 2 or 3 points per cell, for both shape functions. The fill is summed
// here from the points themselves (the node mass over a full cell's), independently of
// lattice_fill. The continuous fill's inverse, the level before, read -1.046 at the EMPTY node
// above a node-plane surface with 2 points per cell.
TEST(PressureSolver, SurfaceLevelOfAPointLatticeIsTheDistance) {
  auto bspline = [](double x) {
    x = std::fabs(x);
    return x < 0.5 ? 0.75 - x * x : (x < 1.5 ? 0.5 * (1.5 - x) * (1.5 - x) : 0.0);
  };
  auto hat = [](double x) { return std::max(0.0, 1.0 - std::fabs(x)); };
  int checked = 0;  // nodes with 0 < fill < 1
  for (const mpm::ShapeKind shape : {mpm::ShapeKind::QuadraticBSpline, mpm::ShapeKind::Linear}) {
    for (int np = 1; np <= 3; ++np) {
      for (const double zs : {0.0, 0.5, 0.3, 0.77, 0.05}) {  // the plane, in cells above node 0
        for (int node = -3; node <= 3; ++node) {
          double fill = 0.0;  // points at zs - (j + 1/2) / np, each 1 / np of a cell
          for (int j = 0; j < 20 * np; ++j) {
            const double x = zs - (j + 0.5) / np - node;
            fill += (shape == mpm::ShapeKind::Linear ? hat(x) : bspline(x)) / np;
          }
          if (fill <= 1e-12 || fill >= 1.0 - 1e-12) continue;  // beyond the points' reach
          EXPECT_NEAR(mpm::surface_distance(fill, shape, np), zs - node, 1e-10)
              << mpm::shape_name(shape) << ", " << np << " points per cell, plane at " << zs << ", node " << node;
          ++checked;
        }
      }
    }
  }
  printf("  %d nodes between the empty and the full ones\n", checked);
  EXPECT_GE(checked, 50);
  // the continuous fill's inverse at that node: F(-1) = 1/48 against the lattice's 1/64
  EXPECT_NEAR(mpm::lattice_fill(-1.0, mpm::ShapeKind::QuadraticBSpline, 2), 1.0 / 64.0, 1e-15);
  // a fill of 0 reads the end of the lattice's reach (the level continuous in the fill)
  EXPECT_NEAR(mpm::surface_distance(0.0, mpm::ShapeKind::QuadraticBSpline, 2), -1.25, 1e-15);
  EXPECT_NEAR(mpm::surface_distance(1e-12, mpm::ShapeKind::QuadraticBSpline, 2), -1.25, 1e-5);
}

// continuum_fill (projection_ops.h): the share of a node's shape function on the fluid side of a
// plane s cells away, against the integral of the shape function by the midpoint rule (4e5
// intervals), the limit of the lattice's fill G as the points per cell grow (np = 400), and
// F(s) + F(-s) = 1; the two ends: 1/2 on the plane, 1 beyond the reach.
TEST(PressureSolver, ContinuumFillIsTheShareOfTheShapeFunction) {
  auto bspline = [](double x) {
    x = std::fabs(x);
    return x < 0.5 ? 0.75 - x * x : (x < 1.5 ? 0.5 * (1.5 - x) * (1.5 - x) : 0.0);
  };
  auto hat = [](double x) { return std::max(0.0, 1.0 - std::fabs(x)); };
  for (const mpm::ShapeKind shape : {mpm::ShapeKind::QuadraticBSpline, mpm::ShapeKind::Linear}) {
    for (const double s : {-1.7, -1.2, -0.6, -0.25, 0.0, 0.1, 0.5, 0.73, 1.0, 1.4, 2.0}) {
      const int n = 400000;
      const double lo = -s, hi = 2.0, du = (hi - lo) / n;
      double share = 0.0;
      for (int q = 0; q < n; ++q) {
        const double u = lo + (q + 0.5) * du;
        share += (shape == mpm::ShapeKind::Linear ? hat(u) : bspline(u)) * du;
      }
      if (lo >= hi) share = 0.0;
      const double f = mpm::continuum_fill(s, shape);
      EXPECT_NEAR(f, share, 1e-9) << mpm::shape_name(shape) << ", s = " << s;
      EXPECT_NEAR(f, mpm::lattice_fill(s, shape, 400), 2e-5) << mpm::shape_name(shape) << ", s = " << s;
      EXPECT_NEAR(f + mpm::continuum_fill(-s, shape), 1.0, 1e-15);
    }
    EXPECT_EQ(mpm::continuum_fill(0.0, shape), 0.5);
    EXPECT_EQ(mpm::continuum_fill(1.5, shape), 1.0);
  }
}
