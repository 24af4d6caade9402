// The solver's optimized transfer kernels (mpm/transfer.cpp: stencil loops, 4-wide rows, policy
// types) against a plain serial reference written from the equations: P2G (8-10), (8-19), (8-24)
// with the APIC affine momentum, and G2P (8-37)-(8-40) with PIC, FLIP, APIC and the velocity
// gradient, for the quadratic B-spline and linear shape functions, at random points.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "mpm/error.h"
#include "mpm/options.h"
#include "mpm/solver.h"
#include "mpm/transfer.h"

namespace {

// ---- the reference: one point at a time, every node of a 5^3 box around it, plain loops ----
double N(bool quad, double r, double &dN) {  // 1-D shape function of the offset r (cells) and dN/dr
  const double a = std::fabs(r), s = r < 0 ? -1.0 : 1.0;
  if (quad) {
    if (a < 0.5) return dN = -2.0 * r, 0.75 - r * r;
    if (a < 1.5) return dN = -s * (1.5 - a), 0.5 * (1.5 - a) * (1.5 - a);
  } else if (a < 1.0) {
    return dN = -s, 1.0 - a;
  }
  return dN = 0.0, 0.0;
}

struct RefNode { long i, j, k; double w, g[3], o[3]; };  // weight, gradient, x_i - x_p

std::vector<RefNode> ref_nodes(bool quad, const mpm::GridSpec &gs, const double *x) {
  std::vector<RefNode> out;
  double xi[3];
  for (int d = 0; d < 3; ++d) xi[d] = (x[d] - gs.origin[d]) / gs.dx;
  for (long k = std::lround(xi[2]) - 2; k <= std::lround(xi[2]) + 2; ++k)
    for (long j = std::lround(xi[1]) - 2; j <= std::lround(xi[1]) + 2; ++j)
      for (long i = std::lround(xi[0]) - 2; i <= std::lround(xi[0]) + 2; ++i) {
        const long idx[3] = {i, j, k};
        double n[3], dn[3];
        for (int d = 0; d < 3; ++d) n[d] = N(quad, xi[d] - idx[d], dn[d]);
        RefNode r{i, j, k, n[0] * n[1] * n[2], {}, {}};
        r.g[0] = dn[0] * n[1] * n[2] / gs.dx;
        r.g[1] = n[0] * dn[1] * n[2] / gs.dx;
        r.g[2] = n[0] * n[1] * dn[2] / gs.dx;
        for (int d = 0; d < 3; ++d) r.o[d] = gs.origin[d] + idx[d] * gs.dx - x[d];
        out.push_back(r);
      }
  return out;
}

// ---- the host's arrays (what LIGGGHTS hands the fix) and the solver on them ----
struct Host {
  std::vector<std::string> words;
  mpm::Options opt;
  std::vector<double> xs, vs, fs, rows;
  std::vector<double *> x, v, f, state;
  std::vector<double> rmass, radius;
  std::vector<int> mask, tag, type;
  std::unique_ptr<mpm::FluidSolver> solver;
  // the fix's arguments (after "f all mpm/fluid"), parsed as the fix does
  void parse(const std::string &args, const mpm::ParseEnv &env) {
    std::istringstream is("f all mpm/fluid " + args);
    for (std::string w; is >> w;) words.push_back(w);
    std::vector<char *> argv;
    for (auto &w : words) argv.push_back(&w[0]);
    opt = mpm::parse_options(static_cast<int>(argv.size()), argv.data(), env);
  }
};

// ---- the set-up: random points in the middle of a 10^3 grid (no wall is within reach) ----
struct Scene : Host {
  explicit Scene(const std::string &args, int n = 40, bool periodic = false) {
    mpm::ParseEnv env;
    for (int d = 0; d < 3; ++d) env.periodic[d] = periodic;
    parse("cell 0.1 density 1000 pressure eos bulk 1e5 viscosity 1e-3 " + args, env);
    std::mt19937_64 gen(7);
    std::uniform_real_distribution<double> pos(0.25, 0.75), val(-1.0, 1.0), pos1(0.5, 1.5);
    xs.resize(3 * n), vs.resize(3 * n), fs.resize(3 * n), rows.assign(n * mpm::NCOL, 0.0);
    for (int i = 0; i < 3 * n; ++i) xs[i] = pos(gen), vs[i] = val(gen), fs[i] = val(gen);
    for (int i = 0; i < n; ++i) {
      x.push_back(&xs[3 * i]), v.push_back(&vs[3 * i]), f.push_back(&fs[3 * i]), state.push_back(&rows[mpm::NCOL * i]);
      rmass.push_back(pos1(gen)), radius.push_back(0.01), mask.push_back(1), tag.push_back(i + 1), type.push_back(1);
      double *s = state.back();
      s[mpm::C_VOL] = 1e-3 * pos1(gen);
      s[mpm::C_P] = 1e3 * val(gen);
      for (int c = 0; c < 6; ++c) s[mpm::C_TAU + c] = 10.0 * val(gen);
      for (int c = 0; c < 9; ++c) s[mpm::C_AFF + c] = val(gen);
      s[mpm::C_THETA] = 1.0;
    }
    solver.reset(new mpm::FluidSolver(opt, MPI_COMM_WORLD));
    mpm::Points &p = solver->pts;
    p.nlocal = n, p.x = x.data(), p.v = v.data(), p.f = f.data(), p.rmass = rmass.data(), p.radius = radius.data();
    p.mask = mask.data(), p.tag = tag.data(), p.type = type.data(), p.state = state.data(), p.point_bit = 1;
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    solver->setup_grid(lo, hi, 0.0);
    solver->compute_shapes();
  }
  bool quad() const { return opt.shape == mpm::ShapeKind::QuadraticBSpline; }
  std::size_t node(const RefNode &r) const { return solver->grid().index(r.i, r.j, r.k); }
};

void expect_close(const std::vector<double> &a, const std::vector<double> &b, const char *what) {
  double scale = 0.0, err = 0.0;
  for (std::size_t q = 0; q < a.size(); ++q) scale = std::max(scale, std::fabs(b[q]));
  for (std::size_t q = 0; q < a.size(); ++q) err = std::max(err, std::fabs(a[q] - b[q]));
  EXPECT_GT(scale, 0.0) << what;
  EXPECT_LE(err, 1e-13 * scale) << what << ": largest difference " << err << " of " << scale;
}

void check_p2g(const std::string &args) {
  Scene sc(args);
  sc.solver->particles_to_grid();
  const bool apic = sc.opt.transfer == mpm::Transfer::Apic;
  const std::size_t nn = sc.solver->grid().size();
  std::vector<double> ref(nn * 7, 0.0), got(nn * 7, 0.0);
  for (std::size_t p = 0; p < sc.x.size(); ++p) {
    const double *s = sc.state[p], m = sc.rmass[p], V = s[mpm::C_VOL], P = s[mpm::C_P], *t = s + mpm::C_TAU;
    const double sig[3][3] = {{t[0] - P, t[5], t[4]}, {t[5], t[1] - P, t[3]}, {t[4], t[3], t[2] - P}};
    for (const RefNode &r : ref_nodes(sc.quad(), sc.opt.grid, sc.x[p])) {
      double *g = &ref[7 * sc.node(r)];
      g[0] += r.w * m;
      for (int a = 0; a < 3; ++a) {
        double mv = m * sc.v[p][a];
        if (apic)
          for (int b = 0; b < 3; ++b) mv += m * s[mpm::C_AFF + 3 * a + b] * r.o[b];
        g[1 + a] += r.w * mv;
        double fa = r.w * sc.f[p][a];
        for (int b = 0; b < 3; ++b) fa -= V * sig[a][b] * r.g[b];
        g[4 + a] += fa;
      }
    }
  }
  const std::vector<double> &rec = sc.solver->fields().p2g;
  for (std::size_t n = 0; n < nn; ++n)
    for (int c = 0; c < 7; ++c) got[7 * n + c] = rec[mpm::P2gRec::N * n + (c < 4 ? mpm::P2gRec::M + c : mpm::P2gRec::F + c - 4)];
  expect_close(got, ref, ("P2G " + args).c_str());
}

void check_g2p(const std::string &args) {
  Scene sc(args);
  std::vector<double> &vel = sc.solver->fields().vel;
  std::mt19937_64 gen(11);
  std::uniform_real_distribution<double> val(-1.0, 1.0);
  for (std::size_t n = 0; n < sc.solver->grid().size(); ++n)
    for (int d = 0; d < 3; ++d) {
      vel[mpm::VelRec::N * n + mpm::VelRec::V_NEW + d] = val(gen);
      vel[mpm::VelRec::N * n + mpm::VelRec::V_OLD + d] = val(gen);
    }
  const std::vector<double> v0 = sc.vs;
  sc.solver->grid_to_particles();
  const bool apic = sc.opt.transfer == mpm::Transfer::Apic, flip = sc.opt.transfer == mpm::Transfer::Flip;
  const double alpha = sc.opt.flip_alpha, dx = sc.opt.grid.dx;
  std::vector<double> vref, vgot, cref, cgot;
  for (std::size_t p = 0; p < sc.x.size(); ++p) {
    double vp[3] = {0, 0, 0}, dv[3] = {0, 0, 0}, L[9] = {0}, B[9] = {0};
    for (const RefNode &r : ref_nodes(sc.quad(), sc.opt.grid, sc.x[p])) {
      const double *u = &vel[mpm::VelRec::N * sc.node(r)];
      for (int a = 0; a < 3; ++a) {
        vp[a] += r.w * u[mpm::VelRec::V_NEW + a];
        dv[a] += r.w * (u[mpm::VelRec::V_NEW + a] - u[mpm::VelRec::V_OLD + a]);
        for (int b = 0; b < 3; ++b) {
          L[3 * a + b] += u[mpm::VelRec::V_NEW + a] * r.g[b];
          B[3 * a + b] += r.w * u[mpm::VelRec::V_NEW + a] * r.o[b];
        }
      }
    }
    for (int a = 0; a < 3; ++a) {
      vref.push_back(flip ? alpha * (v0[3 * p + a] + dv[a]) + (1.0 - alpha) * vp[a] : vp[a]);
      vgot.push_back(sc.v[p][a]);
    }
    // the affine field: APIC's B D^-1 (bspline2, D = dx^2/4) or the velocity gradient
    for (int c = 0; c < 9; ++c) {
      cref.push_back(apic && sc.quad() ? 4.0 * B[c] / (dx * dx) : L[c]);
      cgot.push_back(sc.state[p][mpm::C_AFF + c]);
    }
  }
  expect_close(vgot, vref, ("G2P velocity " + args).c_str());
  expect_close(cgot, cref, ("G2P affine field " + args).c_str());
}

// A whole sub-step in a periodic box (no wall, no external force): P2G, grid update, G2P (APIC
// or FLIP), MUSL, stress and advection keep the points' total momentum, since the internal forces
// of the nodes sum to zero; no node is dropped (mass_threshold 0).
void check_momentum(const std::string &args) {
  Scene sc(args + " mass_threshold 0", 60, true);
  std::fill(sc.fs.begin(), sc.fs.end(), 0.0);
  auto momentum = [&](int d) {
    double s = 0.0;
    for (std::size_t p = 0; p < sc.x.size(); ++p) s += sc.rmass[p] * sc.v[p][d];
    return s;
  };
  double before[3], scale = 0.0;
  for (int d = 0; d < 3; ++d) before[d] = momentum(d);
  for (std::size_t p = 0; p < sc.x.size(); ++p) scale += sc.rmass[p] * std::fabs(sc.v[p][0]);
  const std::vector<double> v0 = sc.vs;
  sc.solver->substep(1e-4);
  double change = 0.0;  // the sub-step does change the velocities (pressure, stress, transfer)
  for (std::size_t q = 0; q < v0.size(); ++q) change = std::max(change, std::fabs(sc.vs[q] - v0[q]));
  EXPECT_GT(change, 1e-3) << args;
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(momentum(d), before[d], 1e-13 * scale) << args << ", direction " << d;
}

TEST(SubstepConservation, MomentumApicBSpline) { check_momentum("shape bspline2 transfer apic"); }
TEST(SubstepConservation, MomentumFlipLinear) { check_momentum("shape linear transfer flip update usl"); }

TEST(TransferReference, P2gBSplineApic) { check_p2g("shape bspline2 transfer apic"); }
TEST(TransferReference, P2gBSplineFlip) { check_p2g("shape bspline2 transfer flip"); }
TEST(TransferReference, P2gLinearApic) { check_p2g("shape linear transfer apic"); }
TEST(TransferReference, P2gLinearFlip) { check_p2g("shape linear transfer flip 0.9"); }
// G2P with USL (the affine field is then the velocity gradient for FLIP/PIC) and APIC with MUSL
TEST(TransferReference, G2pBSplineApic) { check_g2p("shape bspline2 transfer apic"); }
TEST(TransferReference, G2pBSplineFlip) { check_g2p("shape bspline2 transfer flip 0.9 update usl"); }
TEST(TransferReference, G2pLinearApic) { check_g2p("shape linear transfer apic"); }
TEST(TransferReference, G2pLinearPic) { check_g2p("shape linear transfer pic update usl"); }

// The halo (docs/design.md, "The halo"): a rank with the subdomain [0.3, 0.6)^3 of the 10^3 grid
// (owned nodes 3..5) and a skin of 0.2 cells has 2 node layers on each side (3 with mesh walls);
// a point 0.199 cells outside the subdomain is stepped, one whose stencil leaves the patch (or,
// with mesh walls, would leave it if grown by the layer the wall traction reads) stops the run
// with the error that names the skin and the subdomain.
void check_halo(bool mesh_walls, int layers) {
  Scene sc("shape bspline2 transfer apic", 1);
  const double lo[3] = {0.3, 0.3, 0.3}, hi[3] = {0.6, 0.6, 0.6};
  sc.solver->setup_grid(lo, hi, 0.02, mesh_walls);
  const mpm::IndexBox &ob = sc.solver->grid().owned(), &pb = sc.solver->grid().patch();
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(ob.lo[d], 3);
    EXPECT_EQ(ob.hi[d], 5);
    EXPECT_EQ(pb.lo[d], ob.lo[d] - layers) << d;
    EXPECT_EQ(pb.hi[d], ob.hi[d] + layers) << d;
  }
  for (const double x : {0.3 - 0.0199, 0.6 + 0.0199}) {
    sc.xs = {x, x, x};
    EXPECT_NO_THROW(sc.solver->compute_shapes()) << x;
  }
  for (const double x : {0.1499, 0.6501}) {  // the stencils 0..2 and 6..8
    sc.xs = {x, 0.45, 0.45};
    try {
      sc.solver->compute_shapes();
      ADD_FAILURE() << "no error for a point at x = " << x;
    } catch (const mpm::LocalError &e) {
      EXPECT_NE(std::string(e.what()).find("farther than the neighbor skin (0.02) outside the subdomain [0.3, 0.6]"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(Halo, PatchAndGuard) { check_halo(false, 2); }
TEST(Halo, PatchAndGuardMeshWalls) { check_halo(true, 3); }

// The scalar form the kernels had before the 4-wide rows: d[r] = sum_e mC[3 r + e] o[e][.].
void affine_momentum(const double mC[9], const double o[3][3], int a, int b, int c, double d[3]) {
  const double ox = o[0][a], oy = o[1][b], oz = o[2][c];
  for (int r = 0; r < 3; ++r) d[r] = mC[3 * r] * ox + mC[3 * r + 1] * oy + mC[3 * r + 2] * oz;
}

// The 4-wide affine momentum of P2G and the MUSL remap (affine_row, in lanes 1..3 and 0..2) holds
// in each lane the scalar sum of affine_momentum, bit for bit (the kernels' outputs did not change
// when the rows replaced the scalar form); the unused lane is 0.
TEST(TransferReference, AffineRowIsTheScalarSum) {
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    double mC[9], o[3][3];
    for (double &c : mC) c = 1e3 * u(gen);
    for (auto &row : o)
      for (double &x : row) x = 0.01 * u(gen);
    for (int lane0 = 0; lane0 <= 1; ++lane0) {
      mpm::Row4 col[3];
      mpm::affine_columns(mC, lane0, col);
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          for (int c = 0; c < 3; ++c) {
            double d[3];
            affine_momentum(mC, o, a, b, c, d);
            const mpm::Row4 r = mpm::affine_row(col, o, a, b, c);
            for (int q = 0; q < 3; ++q) EXPECT_EQ(r[lane0 + q], d[q]);
            EXPECT_EQ(r[lane0 == 0 ? 3 : 0], 0.0);
          }
    }
  }
}

// ---- the coupling's node scratch (coupling.cpp) ----
// couple_kernel keeps pfit and dr at 0 between calls and clears only the nodes it wrote (the
// stencils of the points and grains), and sets the grains' node records (st) only around the
// grains: a step whose grains lie elsewhere than in the step before must give, bit for bit, what a
// fresh solver gives for it (a value left over from the first step would change the pressure fit,
// the drag or the grains' records). Points fill the lower middle of a 1 m box of cells 0.1, grains
// sit among them, left in the first step and right in the second; both coupled steps run whole.
struct CoupledScene : Host {
  int npts = 0;

  CoupledScene(const std::string &args, double grain_x) {
    mpm::ParseEnv env;
    env.group_exists = [](const char *g) { return std::string(g) == "beads"; };
    parse("cell 0.1 density 1000 pressure eos bulk 1e5 viscosity 1e-3 couple beads " + args, env);
    std::mt19937_64 gen(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int k = 0; k < 8; ++k)  // points 2 x 2 x 2 per cell in [0.2, 0.8] x [0.2, 0.8] x [0, 0.5]
      for (int j = 0; j < 12; ++j)
        for (int i = 0; i < 12; ++i) add(0.2 + 0.05 * (i + 0.5), 0.2 + 0.05 * (j + 0.5), 0.05 * (k + 0.5), 1, 1e3 * 1.25e-4, 0.0, gen, u);
    npts = static_cast<int>(xs.size() / 3);
    for (int g = 0; g < 30; ++g)  // grains (radius 0.02, glass) near the floor around x = grain_x
      add(grain_x + 0.1 * (u(gen) - 0.5), 0.3 + 0.4 * u(gen), 0.05 + 0.15 * u(gen), 2, 2500 * 4.0 / 3.0 * M_PI * 8e-6, 0.02, gen, u);
    for (std::size_t i = 0; i < rmass.size(); ++i) {
      x.push_back(&xs[3 * i]), v.push_back(&vs[3 * i]), f.push_back(&fs[3 * i]), state.push_back(&rows[mpm::NCOL * i]);
    }
    solver.reset(new mpm::FluidSolver(opt, MPI_COMM_WORLD));
    point_views();
    for (int i = 0; i < npts; ++i) rmass[i] = solver->init_point(x[i], 1.25e-4, state[i]);
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    solver->setup_grid(lo, hi, 0.0);
    solver->clock.dt = 1e-4;
  }
  void add(double a, double b, double c, int m, double mass, double r, std::mt19937_64 &gen,
           std::uniform_real_distribution<double> &u) {
    xs.insert(xs.end(), {a, b, c});
    vs.insert(vs.end(), {0.1 * (u(gen) - 0.5), 0.1 * (u(gen) - 0.5), 0.1 * (u(gen) - 0.5)});
    fs.insert(fs.end(), {0.0, 0.0, -9.81 * mass});
    rows.resize(rows.size() + mpm::NCOL, 0.0);
    rmass.push_back(mass), radius.push_back(r), mask.push_back(m);
    tag.push_back(static_cast<int>(tag.size()) + 1), type.push_back(1);
  }
  void point_views() {
    mpm::Points &p = solver->pts;
    p.nlocal = static_cast<int>(rmass.size()), p.x = x.data(), p.v = v.data(), p.f = f.data();
    p.rmass = rmass.data(), p.radius = radius.data(), p.mask = mask.data(), p.tag = tag.data(), p.type = type.data();
    p.state = state.data(), p.point_bit = 1, p.grain_bit = 2, p.integrated_bits = 2;
  }
  // the whole state a step changes or reads (host arrays)
  std::vector<double> snapshot() const {
    std::vector<double> a = xs;
    a.insert(a.end(), vs.begin(), vs.end());
    a.insert(a.end(), fs.begin(), fs.end());
    a.insert(a.end(), rows.begin(), rows.end());
    a.insert(a.end(), rmass.begin(), rmass.end());
    return a;
  }
  void restore(const std::vector<double> &a) {
    std::size_t o = 0;
    for (auto *w : {&xs, &vs, &fs, &rows, &rmass}) {
      std::copy(a.begin() + o, a.begin() + o + w->size(), w->begin());
      o += w->size();
    }
  }
  void move_grains(const CoupledScene &from) {  // the grains' rows of another scene
    for (std::size_t i = npts; i < rmass.size(); ++i)
      for (int d = 0; d < 3; ++d) xs[3 * i + d] = from.xs[3 * i + d], vs[3 * i + d] = from.vs[3 * i + d], fs[3 * i + d] = from.fs[3 * i + d];
  }
};

void check_coupling_scratch(const std::string &args) {
  CoupledScene a(args, 0.3), b(args, 0.7);  // (no setup_coupling: it would scale the points' masses by theta)
  const std::vector<double> a0 = a.snapshot(), b0 = b.snapshot();
  a.solver->step();  // grains left
  const std::vector<double> a1 = a.snapshot();
  a.restore(a0);
  a.move_grains(b);  // now the scene of b (points as at the start, grains right)
  ASSERT_EQ(a.snapshot(), b0);
  a.solver->step();
  b.solver->step();
  EXPECT_NE(a1, b.snapshot()) << "the two steps should differ (grains elsewhere)";
  EXPECT_TRUE(a.snapshot() == b.snapshot()) << args << ": the step after one with the grains elsewhere differs from a fresh solver's";
  EXPECT_EQ(a.solver->grain_force(), b.solver->grain_force()) << args;
  double fmax = 0.0;  // the fluid does push the grains
  for (double q : b.solver->grain_force()) fmax = std::max(fmax, std::fabs(q));
  EXPECT_GT(fmax, 0.0) << args;
  for (const auto *s : {&a, &b}) {  // the scratch is 0 after the step
    const mpm::GridFields &g = s->solver->fields();
    EXPECT_EQ(std::count(g.pfit.begin(), g.pfit.end(), 0.0), static_cast<long>(g.pfit.size())) << args;
    EXPECT_EQ(std::count(g.dr.begin(), g.dr.end(), 0.0), static_cast<long>(g.dr.size())) << args;
  }
}

TEST(CouplingScratch, Yang2016Smoothed) { check_coupling_scratch("model yang2016 theta_smooth 0.1"); }
TEST(CouplingScratch, Standard) { check_coupling_scratch(""); }

}  // namespace

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  const int rc = RUN_ALL_TESTS();
  MPI_Finalize();
  return rc;
}
