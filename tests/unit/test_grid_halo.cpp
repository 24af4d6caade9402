// Distributed grid: every node of the global grid has exactly one owner, and
// halo exchanges neither lose nor duplicate anything, for uneven subdomains,
// walls with padding nodes and periodic images; and the reverse sum adds the
// images in a fixed order (bit for bit, the results do not depend on how the
// exchange packs its messages); the exchange counters match the nodes counted from the boxes, for
// halo widths 1 to 5. Run with 1 and 2 MPI ranks.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "mpm/grid.h"
#include "mpm/shape_functions.h"

namespace {

struct Case {
  int ncell[3];
  bool periodic[3];
  int pad;
  int halo;
  double split;      // where rank 0's subdomain ends, fraction of x (2 ranks)
  int halo_hi = -1;  // node layers above the owned box when they differ from those below (halo)
};

int wrap(int i, int n) { return ((i % n) + n) % n; }

// The grid of case c over MPI_COMM_WORLD (2 ranks: split along x at c.split).
void setup_case(const Case &c, mpm::GridSpec &g, mpm::LocalGrid &grid) {
  int me, np;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  MPI_Comm_size(MPI_COMM_WORLD, &np);
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
  const int halo[2] = {c.halo, c.halo_hi < 0 ? c.halo : c.halo_hi};
  grid.setup(g, MPI_COMM_WORLD, sublo, subhi, halo);
}

void run_case(const Case &c) {
  mpm::GridSpec g;
  mpm::LocalGrid grid;
  setup_case(c, g, grid);
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
TEST(GridHalo, UnequalSides) { run_case({{12, 5, 4}, {false, false, false}, 1, 1, 0.3717, 3}); }
TEST(GridHalo, UnequalSidesPeriodic) { run_case({{9, 4, 3}, {true, false, true}, 1, 3, 0.61, 2}); }

// Every rank's owned and patch box and its patch values (stride per node), gathered.
struct AllPatches {
  std::vector<mpm::IndexBox> owned, patch;
  std::vector<std::vector<double>> data;
  // the value c of global node (i, j, k) in rank q's patch, or nullptr if not in it
  const double *at(const mpm::GridSpec &g, int q, int i, int j, int k, int stride) const {
    const mpm::IndexBox &b = patch[q];
    const int idx[3] = {i, j, k};
    for (int d = 0; d < 3; ++d)
      if (idx[d] < b.lo[d] || idx[d] > b.hi[d]) return nullptr;
    const long nx = b.hi[0] - b.lo[0] + 1, ny = b.hi[1] - b.lo[1] + 1;
    const long n = ((long(k - b.lo[2]) * ny) + (j - b.lo[1])) * nx + (i - b.lo[0]);
    return data[q].data() + n * stride;
  }
};

AllPatches gather(const mpm::LocalGrid &grid, const std::vector<double> &a, int stride) {
  int np;
  MPI_Comm_size(MPI_COMM_WORLD, &np);
  const mpm::IndexBox &pb = grid.patch(), &ob = grid.owned();
  int mine[12];
  for (int d = 0; d < 3; ++d) {
    mine[d] = ob.lo[d];
    mine[3 + d] = ob.hi[d];
    mine[6 + d] = pb.lo[d];
    mine[9 + d] = pb.hi[d];
  }
  std::vector<int> all(12 * np);
  MPI_Allgather(mine, 12, MPI_INT, all.data(), 12, MPI_INT, MPI_COMM_WORLD);
  AllPatches r;
  r.owned.resize(np);
  r.patch.resize(np);
  r.data.resize(np);
  std::vector<int> count(np), off(np + 1, 0);
  for (int q = 0; q < np; ++q) {
    for (int d = 0; d < 3; ++d) {
      r.owned[q].lo[d] = all[12 * q + d];
      r.owned[q].hi[d] = all[12 * q + 3 + d];
      r.patch[q].lo[d] = all[12 * q + 6 + d];
      r.patch[q].hi[d] = all[12 * q + 9 + d];
    }
    count[q] = int(r.patch[q].count()) * stride;
    off[q + 1] = off[q] + count[q];
  }
  std::vector<double> flat(off[np]);
  MPI_Allgatherv(a.data(), int(a.size()), MPI_DOUBLE, flat.data(), count.data(), off.data(), MPI_DOUBLE,
                 MPI_COMM_WORLD);
  for (int q = 0; q < np; ++q) r.data[q].assign(flat.begin() + off[q], flat.begin() + off[q + 1]);
  return r;
}

bool same_bits(double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; }

// Reverse sum of values whose sum depends on the order of the additions: each owned value must be
// its own plus its images' in the exchange's order (this rank's periodic images first, then the
// other ranks in rank order; images in the order of their shifts, z outermost), bit for bit.
// The same sums in another order (ranks and shifts reversed) must differ somewhere when some node
// has three or more terms, so that the check can tell orders apart. Forward: every patch node
// holds its owner's value, bit for bit.
void run_order_case(const Case &c, int stride) {
  int me, np;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  MPI_Comm_size(MPI_COMM_WORLD, &np);
  mpm::GridSpec g;
  mpm::LocalGrid grid;
  setup_case(c, g, grid);
  const mpm::IndexBox &pb = grid.patch(), &ob = grid.owned();
  std::mt19937_64 rng(12345 + 977 * me);
  std::uniform_real_distribution<double> mant(1.0, 2.0);
  std::uniform_int_distribution<int> expo(-20, 20);
  std::vector<double> a(grid.size() * stride);
  for (double &v : a) v = (rng() & 1 ? -1.0 : 1.0) * std::ldexp(mant(rng), expo(rng));
  const AllPatches before = gather(grid, a, stride);
  grid.reverse_sum(a.data(), stride);

  // shifts of whole periods that can bring a patch node onto an owned one (the patches are at
  // most ncell + 2 halo + 2 pad wide)
  int kmax[3];
  for (int d = 0; d < 3; ++d) kmax[d] = g.periodic[d] ? (2 * c.halo + 2) / g.ncell[d] + 2 : 0;
  std::vector<int> order{me};
  for (int q = 0; q < np; ++q)
    if (q != me) order.push_back(q);
  long checked = 0, multi = 0, differs = 0;
  for (int k = ob.lo[2]; k <= ob.hi[2]; ++k)
    for (int j = ob.lo[1]; j <= ob.hi[1]; ++j)
      for (int i = ob.lo[0]; i <= ob.hi[0]; ++i) {
        std::vector<const double *> terms;  // in the exchange's order
        for (const int q : order)
          for (int kz = -kmax[2]; kz <= kmax[2]; ++kz)
            for (int ky = -kmax[1]; ky <= kmax[1]; ++ky)
              for (int kx = -kmax[0]; kx <= kmax[0]; ++kx) {
                if (q == me && kx == 0 && ky == 0 && kz == 0) continue;
                const double *v = before.at(g, q, i + kx * g.ncell[0], j + ky * g.ncell[1], k + kz * g.ncell[2], stride);
                if (v) terms.push_back(v);
              }
        const double *own = before.at(g, me, i, j, k, stride);
        const std::size_t n = grid.index(i, j, k);
        for (int s = 0; s < stride; ++s) {
          double sum = own[s], other = own[s];
          for (const double *t : terms) sum += t[s];
          for (auto t = terms.rbegin(); t != terms.rend(); ++t) other += (*t)[s];
          ASSERT_TRUE(same_bits(a[n * stride + s], sum))
              << "node " << i << " " << j << " " << k << " value " << s << ": " << a[n * stride + s] << " vs " << sum;
          ++checked;
          differs += !same_bits(sum, other);
        }
        multi += terms.size() >= 2;
      }
  EXPECT_GT(checked, 0);
  if (multi > 0) EXPECT_GT(differs, 0) << "no node's sum depends on the order: the case cannot tell orders apart";

  // forward: owners hold fresh values, the halo copies them
  for (std::size_t n = 0; n < a.size(); ++n) a[n] = std::ldexp(mant(rng), expo(rng));
  const AllPatches owners = gather(grid, a, stride);
  grid.forward(a.data(), stride);
  auto wrap_to = [&](int i, int d) { return g.periodic[d] ? wrap(i, g.ncell[d]) : i; };
  for (int k = pb.lo[2]; k <= pb.hi[2]; ++k)
    for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
      for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) {
        const int w[3] = {wrap_to(i, 0), wrap_to(j, 1), wrap_to(k, 2)};
        int owner = -1;
        for (int q = 0; q < np; ++q) {
          const mpm::IndexBox &o = owners.owned[q];
          if (w[0] >= o.lo[0] && w[0] <= o.hi[0] && w[1] >= o.lo[1] && w[1] <= o.hi[1] && w[2] >= o.lo[2] &&
              w[2] <= o.hi[2])
            owner = q;
        }
        ASSERT_GE(owner, 0);
        const double *v = owners.at(g, owner, w[0], w[1], w[2], stride);
        ASSERT_NE(v, nullptr);
        for (int s = 0; s < stride; ++s)
          ASSERT_TRUE(same_bits(a[grid.index(i, j, k) * stride + s], v[s])) << "node " << i << " " << j << " " << k;
      }
}

TEST(GridHaloOrder, WallsUnevenSplit) { run_order_case({{12, 5, 4}, {false, false, false}, 1, 5, 0.3717}, 3); }
TEST(GridHaloOrder, PeriodicThinSlabManyImages) { run_order_case({{10, 1, 6}, {false, true, false}, 1, 4, 0.45}, 4); }
TEST(GridHaloOrder, PeriodicAcrossRanks) { run_order_case({{9, 4, 3}, {true, false, true}, 1, 3, 0.61}, 5); }
TEST(GridHaloOrder, PeriodicAllStride1) { run_order_case({{5, 3, 2}, {true, true, true}, 1, 3, 0.5}, 1); }
TEST(GridHaloOrder, UnequalSidesPeriodic) { run_order_case({{9, 4, 3}, {true, false, true}, 1, 2, 0.61, 3}, 4); }

// stencil_reach (the halo, docs/design.md "The halo") against every point of a fine sweep: for
// subdomains [a, b) anywhere between the nodes (also on a node and half-way) and points in
// [a - delta, b + delta), the stencil's nodes lie within the reach below and above the owned
// nodes (owned_box), and some point needs all of it (the halo is no wider than it must be).
void check_reach(mpm::ShapeKind kind, double delta) {
  int reach[2];
  mpm::stencil_reach(kind, delta, reach);
  mpm::GridSpec g;
  g.dx = 1.0;
  g.ncell[0] = g.ncell[1] = g.ncell[2] = 64;
  g.pad = mpm::support(kind) - 2;
  int need[2] = {0, 0};
  const int ns = mpm::support(kind);
  // the faces' places between two nodes: on a node and half-way, within owned_box's rounding
  // (1e-9 cells) and a little farther on either side of them, and a sweep
  std::vector<double> off = {0.0, 1e-10, -1e-10, 1e-7, -1e-7, 0.5, 0.5 + 1e-10, 0.5 - 1e-10, 0.5 + 1e-7, 0.5 - 1e-7};
  for (int q = 1; q < 40; ++q) off.push_back(q / 40.0);
  for (const double fa : off)
    for (const double fb : off) {
      const double sublo[3] = {20.0 + fa, 20.0, 20.0}, subhi[3] = {30.0 + fb, 30.0, 30.0};
      const mpm::IndexBox ob = mpm::owned_box(g, sublo, subhi);
      const int m = 400;
      for (int q = 0; q <= m; ++q) {
        // from a - delta to just below b + delta
        double x = (sublo[0] - delta) + (subhi[0] - sublo[0] + 2.0 * delta) * q / m;
        if (q == m) x = std::nextafter(subhi[0] + delta, 0.0);
        mpm::Shape1D s;
        mpm::shape_eval(kind, x, s);
        need[0] = std::max(need[0], ob.lo[0] - s.base);
        need[1] = std::max(need[1], s.base + ns - 1 - ob.hi[0]);
      }
    }
  for (int side = 0; side < 2; ++side) {
    EXPECT_LE(need[side], reach[side]) << mpm::shape_name(kind) << " delta " << delta << " side " << side;
    EXPECT_EQ(need[side], reach[side]) << mpm::shape_name(kind) << " delta " << delta << " side " << side;
  }
}

TEST(HaloReach, BSpline) {
  for (double delta : {0.0, 0.1, 0.2, 0.45, 0.5, 0.55, 0.9, 1.0, 1.2, 1.5, 1.7, 2.3}) check_reach(mpm::ShapeKind::QuadraticBSpline, delta);
}
TEST(HaloReach, Linear) {
  for (double delta : {0.0, 0.1, 0.2, 0.45, 0.5, 0.55, 0.9, 1.0, 1.2, 1.5, 1.7, 2.3}) check_reach(mpm::ShapeKind::Linear, delta);
}

}  // namespace

namespace {

// The exchange counters (LocalGrid::exchange_counts) against the nodes counted from the boxes
// alone: in a reverse sum each rank sends every node of its patch (each periodic image apart)
// that the other rank owns, stride doubles per node, in one message to that rank; a forward moves
// the same nodes back. Periodic images on the same rank are copies: no message, no byte. The count
// follows the patch, so it holds for every halo width.
void run_count_case(const Case &c, int stride) {
  mpm::GridSpec g;
  mpm::LocalGrid grid;
  setup_case(c, g, grid);
  int me, np;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  MPI_Comm_size(MPI_COMM_WORLD, &np);
  const mpm::IndexBox &ob = grid.owned(), &pb = grid.patch();
  int mine[6] = {ob.lo[0], ob.lo[1], ob.lo[2], ob.hi[0], ob.hi[1], ob.hi[2]}, all[12] = {};
  MPI_Allgather(mine, 6, MPI_INT, all, 6, MPI_INT, MPI_COMM_WORLD);
  long long halo = 0;  // my patch nodes that the other rank owns
  if (np == 2) {
    const int *o = all + 6 * (1 - me);
    for (int k = pb.lo[2]; k <= pb.hi[2]; ++k)
      for (int j = pb.lo[1]; j <= pb.hi[1]; ++j)
        for (int i = pb.lo[0]; i <= pb.hi[0]; ++i) {
          int idx[3] = {i, j, k};
          bool in = true;
          for (int d = 0; d < 3; ++d) {
            if (g.periodic[d]) idx[d] = wrap(idx[d], g.ncell[d]);
            in = in && idx[d] >= o[d] && idx[d] <= o[3 + d];
          }
          halo += in ? 1 : 0;
        }
  }
  std::vector<double> a(grid.size() * stride, 1.0);
  const mpm::LocalGrid::ExchangeCounts c0 = grid.exchange_counts();
  grid.reverse_sum(a.data(), stride);
  const mpm::LocalGrid::ExchangeCounts c1 = grid.exchange_counts();
  grid.forward(a.data(), stride);
  const mpm::LocalGrid::ExchangeCounts c2 = grid.exchange_counts();
  const long long bytes = 8LL * stride * halo;
  EXPECT_EQ(c1.exchanges - c0.exchanges, 1);
  EXPECT_EQ(c2.exchanges - c1.exchanges, 1);
  EXPECT_EQ(c1.bytes_sent - c0.bytes_sent, bytes);
  EXPECT_EQ(c1.msgs_sent - c0.msgs_sent, halo > 0 ? 1 : 0);
  EXPECT_EQ(c2.bytes_recv - c1.bytes_recv, bytes);
  EXPECT_EQ(c2.msgs_recv - c1.msgs_recv, halo > 0 ? 1 : 0);
  if (np == 2) EXPECT_GT(halo, 0);
  long long sr[4] = {c2.bytes_sent - c0.bytes_sent, c2.bytes_recv - c0.bytes_recv, c2.msgs_sent - c0.msgs_sent,
                     c2.msgs_recv - c0.msgs_recv},
            tot[4];
  MPI_Allreduce(sr, tot, 4, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(tot[0], tot[1]);
  EXPECT_EQ(tot[2], tot[3]);
}

}  // namespace

TEST(GridHaloCounts, WallsHalo1) { run_count_case({{12, 5, 4}, {false, false, false}, 1, 1, 0.5}, 3); }
TEST(GridHaloCounts, WallsUnevenHalo2) { run_count_case({{12, 5, 4}, {false, false, false}, 1, 2, 0.3717}, 1); }
TEST(GridHaloCounts, WallsHalo5) { run_count_case({{16, 5, 4}, {false, false, false}, 1, 5, 0.5}, 4); }
TEST(GridHaloCounts, PeriodicThinSlabHalo4) { run_count_case({{10, 1, 6}, {false, true, false}, 1, 4, 0.45}, 2); }
TEST(GridHaloCounts, PeriodicAcrossRanksHalo3) { run_count_case({{9, 4, 3}, {true, false, true}, 1, 3, 0.61}, 5); }
