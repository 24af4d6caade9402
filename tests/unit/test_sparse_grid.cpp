// The sparse grid (keyword sparse, mpm::ActiveBlocks): a column of fluid collapsing in a long box,
// stepped by two solvers side by side, one on the active blocks only and one on the dense grid.
// After every sub-step the points and all node arrays must be identical to the bit, every node
// value outside the active blocks zero (the invariant the sparse phases rely on), and the active
// blocks a small part of the grid. Serially and on 2 ranks (the exchanged nodes), for the shape
// functions, transfers and updates, a gate, a periodic dimension and the pressure projection.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "mpm/options.h"
#include "mpm/solver.h"

namespace {

// A fluid column 0.4 x 0.5 x 0.3 (2 x 2 x 2 points per cell of 0.05) in the corner of a box
// 2 x 0.5 x 0.5, moving towards +x at 0.5 m/s under gravity; this rank's points only.
struct Column {
  std::vector<std::string> words;
  mpm::Options opt;
  std::vector<double> xs, vs, fs, rows, rmass, radius;
  std::vector<double *> x, v, f, state;
  std::vector<int> mask, tag, type;
  std::unique_ptr<mpm::FluidSolver> solver;

  Column(const std::string &args, bool periodic_y) {
    const bool eos = args.find("projection") == std::string::npos;
    std::istringstream is("f all mpm/fluid cell 0.05 density 1000 viscosity 1e-3 sparse " + args + (eos ? " pressure eos bulk 1e5" : ""));
    for (std::string s; is >> s;) words.push_back(s);
    std::vector<char *> argv;
    for (auto &s : words) argv.push_back(&s[0]);
    mpm::ParseEnv env;
    const double hi[3] = {2.0, 0.5, 0.5};
    for (int d = 0; d < 3; ++d) env.boxhi[d] = hi[d];
    env.periodic[1] = periodic_y;
    opt = mpm::parse_options(static_cast<int>(argv.size()), argv.data(), env);
    int me = 0, np = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &me);
    MPI_Comm_size(MPI_COMM_WORLD, &np);
    // subdomains: slabs along x, the cut inside the column so that its points reach both ranks
    const double cut = 0.25;
    const double sublo[3] = {np == 1 ? 0.0 : (me == 0 ? 0.0 : cut), 0.0, 0.0};
    const double subhi[3] = {np == 1 ? 2.0 : (me == 0 ? cut : 2.0), 0.5, 0.5};
    const double h = 0.025;
    for (int k = 0; k < 12; ++k)
      for (int j = 0; j < 20; ++j)
        for (int i = 0; i < 16; ++i) {
          const double p[3] = {(i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h};
          if (p[0] < sublo[0] || p[0] >= subhi[0]) continue;
          for (int d = 0; d < 3; ++d) xs.push_back(p[d]);
          tag.push_back(1 + i + 16 * (j + 20 * k));
        }
    const int n = static_cast<int>(tag.size());
    vs.assign(3 * n, 0.0), fs.assign(3 * n, 0.0), rows.assign(n * mpm::NCOL, 0.0);
    solver.reset(new mpm::FluidSolver(opt, MPI_COMM_WORLD));
    for (int q = 0; q < n; ++q) {
      x.push_back(&xs[3 * q]), v.push_back(&vs[3 * q]), f.push_back(&fs[3 * q]), state.push_back(&rows[mpm::NCOL * q]);
      vs[3 * q] = 0.5;
      rmass.push_back(solver->init_point(x.back(), h * h * h, state.back()));
      radius.push_back(0.01), mask.push_back(1), type.push_back(1);
    }
    solver->state.point_mass_ref = 1000.0 * h * h * h;
    mpm::Points &pt = solver->pts;
    pt.nlocal = n, pt.x = x.data(), pt.v = v.data(), pt.f = f.data(), pt.rmass = rmass.data();
    pt.radius = radius.data(), pt.mask = mask.data(), pt.tag = tag.data(), pt.type = type.data();
    pt.state = state.data(), pt.point_bit = 1;
    // skin 4 cells: a halo of 6 nodes (stencil_reach), in which the points stay (they are not
    // migrated) and whose blocks the moving fluid leaves again
    solver->setup_grid(sublo, subhi, 0.2);
  }
  void substep(double h) {
    for (std::size_t q = 0; q < rmass.size(); ++q) fs[3 * q] = fs[3 * q + 1] = 0.0, fs[3 * q + 2] = -9.81 * rmass[q];
    solver->substep(h);
  }
};

bool same_bits(const std::vector<double> &a, const std::vector<double> &b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

// Steps both for 150 sub-steps of 1e-3 (the front runs ~0.1 m: blocks come and go).
// moving: the fluid leaves blocks within the run (blocks are cleared when they drop out);
// periodic_y: the periodic images in y are exchanged nodes, active throughout.
void check(const std::string &args, bool moving, bool periodic_y = false) {
  Column sparse("yes " + args, periodic_y), dense("no " + args, periodic_y);
  ASSERT_TRUE(sparse.solver->sparse());
  ASSERT_FALSE(dense.solver->sparse());
  long retired = 0;
  std::size_t active_max = 0;
  for (int s = 0; s < 150; ++s) {
    sparse.substep(1e-3);
    dense.substep(1e-3);
    const mpm::GridFields &a = sparse.solver->fields(), &b = dense.solver->fields();
    const long outside = sparse.solver->nonzero_outside_active();
    const bool same[8] = {same_bits(a.p2g, b.p2g), same_bits(a.vel, b.vel), same_bits(a.aux, b.aux),
                          same_bits(a.cell, b.cell), same_bits(sparse.xs, dense.xs), same_bits(sparse.vs, dense.vs),
                          same_bits(sparse.rows, dense.rows), outside == 0};
    int ok = 1, all = 0;
    for (bool q : same) ok = ok && q;
    MPI_Allreduce(&ok, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);  // every rank stops together
    if (!all) {
      const char *what[8] = {"p2g", "vel", "aux", "cell", "positions", "velocities", "point state",
                             "zero outside the active blocks"};
      for (int q = 0; q < 8; ++q) EXPECT_TRUE(same[q]) << what[q] << ", sub-step " << s << " (" << outside << " nonzero)";
      EXPECT_TRUE(ok) << "another rank differs";
      return;
    }
    retired += static_cast<long>(sparse.solver->active_blocks().retired().size());
    active_max = std::max(active_max, sparse.solver->active_blocks().boxes().size());
  }
  // the fluid moved (blocks dropped out and were cleared) and filled a small part of the grid
  double front = 0.0, gfront = 0.0;
  for (std::size_t q = 0; q < sparse.rmass.size(); ++q) front = std::max(front, sparse.xs[3 * q]);
  MPI_Allreduce(&front, &gfront, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  EXPECT_GT(gfront, 0.42);
  long gretired = 0;
  MPI_Allreduce(&retired, &gretired, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  if (moving) EXPECT_GT(gretired, 0);
  // on the rank that holds the empty end of the box
  const mpm::LocalGrid &g = sparse.solver->grid();
  if (!periodic_y && g.owned().hi[0] == g.spec().node_hi(0))
    EXPECT_LT(active_max, sparse.solver->active_blocks().total() / 2);
}

TEST(SparseGrid, BsplineFlipMuslEqualsDense) { check("shape bspline2 transfer flip", true); }
TEST(SparseGrid, BsplineApicUslEqualsDense) { check("transfer apic update usl", false); }
TEST(SparseGrid, LinearPicEqualsDense) { check("shape linear transfer pic", false); }
TEST(SparseGrid, GateAndFreeslipEqualDense) { check("gate x 0.6 lower never boundary all freeslip", true); }
TEST(SparseGrid, PeriodicYEqualsDense) { check("transfer apic", false, true); }
// pressure projection: the fluid's phases on the active blocks, the projection's sweeps on the work
// box around the fluid (retired as the column collapses), the hypre solve on the FLUID nodes' box
TEST(SparseGrid, ProjectionEqualsDense) { check("pressure projection", true); }
TEST(SparseGrid, ProjectionAveragedEqualsDense) {
  check("pressure projection transfer apic pressure_average 0.01 pressure_output acceleration "
        "volume_correction 10", false);
}

}  // namespace
