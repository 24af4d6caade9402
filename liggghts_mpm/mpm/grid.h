// The background grid as one MPI rank sees it: a patch of nodes covering the
// rank's subdomain plus a halo wide enough for every node its material points
// can touch. Each node of the global grid is owned by exactly one rank (the
// one whose subdomain contains the node, positions clamped into the grid);
// the halo holds partial sums (particles-to-grid) that reverse_sum() adds
// into the owners, and copies of owned values that forward() refreshes.
#pragma once
#include <mpi.h>
#include <algorithm>
#include <array>
#include <cstddef>
#include <initializer_list>
#include <vector>

namespace mpm {

struct IndexBox {
  int lo[3] = {0, 0, 0};
  int hi[3] = {-1, -1, -1};  // inclusive; empty if any hi < lo
  bool empty() const { return hi[0] < lo[0] || hi[1] < lo[1] || hi[2] < lo[2]; }
  long count() const {
    return empty() ? 0 : long(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
  }
  // the nodes of both boxes
  IndexBox cut(const IndexBox &b) const {
    IndexBox r;
    for (int d = 0; d < 3; ++d) {
      r.lo[d] = std::max(lo[d], b.lo[d]);
      r.hi[d] = std::min(hi[d], b.hi[d]);
    }
    return r;
  }
  // the smallest box that holds both (an empty box adds nothing)
  IndexBox hull(const IndexBox &b) const {
    if (b.empty()) return *this;
    if (empty()) return b;
    IndexBox r;
    for (int d = 0; d < 3; ++d) {
      r.lo[d] = std::min(lo[d], b.lo[d]);
      r.hi[d] = std::max(hi[d], b.hi[d]);
    }
    return r;
  }
  bool contains(int i, int j, int k) const {
    return i >= lo[0] && i <= hi[0] && j >= lo[1] && j <= hi[1] && k >= lo[2] && k <= hi[2];
  }
  // the nodes of this box outside b, as up to six disjoint slabs
  std::vector<IndexBox> minus(const IndexBox &b) const {
    std::vector<IndexBox> out;
    if (empty()) return out;
    const IndexBox c = cut(b);
    if (c.empty()) return {*this};
    IndexBox rest = *this;
    for (int d = 2; d >= 0; --d) {
      IndexBox l = rest, h = rest;
      l.hi[d] = c.lo[d] - 1;
      h.lo[d] = c.hi[d] + 1;
      if (!l.empty()) out.push_back(l);
      if (!h.empty()) out.push_back(h);
      rest.lo[d] = c.lo[d];
      rest.hi[d] = c.hi[d];
    }
    return out;
  }
};

struct GridSpec {
  double origin[3] = {0, 0, 0};
  double dx = 1.0;
  int ncell[3] = {1, 1, 1};
  bool periodic[3] = {false, false, false};
  int pad = 1;  // node layers outside a non-periodic face (support of the shape function)
  double upper(int d) const { return origin[d] + ncell[d] * dx; }
  // Global node index range: non-periodic 0-pad .. ncell+pad, periodic 0 .. ncell-1.
  int node_lo(int d) const { return periodic[d] ? 0 : -pad; }
  int node_hi(int d) const { return periodic[d] ? ncell[d] - 1 : ncell[d] + pad; }
  // Index c along d reflected at the wall it lies behind (-c, or 2 ncell - c); c itself inside the
  // box or along a periodic d.
  int mirror(int c, int d) const {
    if (periodic[d]) return c;
    return c < 0 ? -c : (c > ncell[d] ? 2 * ncell[d] - c : c);
  }
  // The nodes of b that are not padding: b cut to 0..ncell along every non-periodic dimension.
  IndexBox interior(const IndexBox &b) const {
    IndexBox in = b;
    for (int d = 0; d < 3; ++d)
      if (!periodic[d]) {
        in.lo[d] = std::max(in.lo[d], 0);
        in.hi[d] = std::min(in.hi[d], ncell[d]);
      }
    return in;
  }
  // The padding layers of b along a non-periodic d: its nodes below 0 and above ncell (either
  // box empty when b has none there).
  std::array<IndexBox, 2> padding_layers(const IndexBox &b, int d) const {
    std::array<IndexBox, 2> out = {b, b};
    out[0].hi[d] = std::min(b.hi[d], -1);
    out[1].lo[d] = std::max(b.lo[d], ncell[d] + 1);
    return out;
  }
};

// Owned node index range along one dimension of the subdomain [sublo, subhi).
// Shared by all ranks so that neighbouring ranges tile the grid exactly.
IndexBox owned_box(const GridSpec &g, const double sublo[3], const double subhi[3]);

class LocalGrid {
 public:
  // Collective over comm. halo: node layers added below (halo[0]) and above (halo[1]) the owned
  // box along every dimension.
  void setup(const GridSpec &spec, MPI_Comm comm, const double sublo[3], const double subhi[3],
             const int halo[2]);
  void setup(const GridSpec &spec, MPI_Comm comm, const double sublo[3], const double subhi[3], int halo) {
    const int h[2] = {halo, halo};
    setup(spec, comm, sublo, subhi, h);
  }

  const GridSpec &spec() const { return spec_; }
  const IndexBox &patch() const { return patch_; }
  const IndexBox &owned() const { return owned_; }
  std::size_t size() const { return nnodes_; }
  int extent(int d) const { return n_[d]; }
  // Flat-index strides of one node step in y and in z.
  std::size_t stride_y() const { return std::size_t(n_[0]); }
  std::size_t stride_z() const { return std::size_t(n_[0]) * n_[1]; }
  // Flat patch index of global (unwrapped) node indices; i fastest.
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(k - patch_.lo[2]) * n_[1] + (j - patch_.lo[1])) * n_[0] + (i - patch_.lo[0]);
  }
  bool in_patch(int i, int j, int k) const {
    return i >= patch_.lo[0] && i <= patch_.hi[0] && j >= patch_.lo[1] && j <= patch_.hi[1] &&
           k >= patch_.lo[2] && k <= patch_.hi[2];
  }

  // Calls fn(i, j, k, n) for every node of box b (in the patch; global indices, flat patch index).
  template <class Fn>
  void for_box(const IndexBox &b, Fn &&fn) const {
    for (int k = b.lo[2]; k <= b.hi[2]; ++k)
      for (int j = b.lo[1]; j <= b.hi[1]; ++j)
        for (int i = b.lo[0]; i <= b.hi[0]; ++i) fn(i, j, k, index(i, j, k));
  }
  // Calls fn(i, j, k, n) for every owned node (of the work box only, while one is set).
  template <class Fn>
  void for_owned(Fn &&fn) const {
    for_box(restricted_ ? owned_.cut(work_) : owned_, fn);
  }
  // Calls fn(i, j, k, n) for every owned node, work box or not.
  template <class Fn>
  void for_owned_all(Fn &&fn) const {
    for_box(owned_, fn);
  }
  // The work box (the projection's sparse sweeps, docs/validation/performance.md "Sparse grid"): while set,
  // for_owned visits only the owned nodes inside it; null: every owned node again. WorkScope
  // sets it for a scope.
  void set_work(const IndexBox *b) {
    restricted_ = b != nullptr;
    if (b) work_ = *b;
  }
  bool restricted() const { return restricted_; }
  const IndexBox &work() const { return work_; }
  class WorkScope {
   public:
    WorkScope(LocalGrid &g, const IndexBox *b) : g_(g), was_(g.restricted_), old_(g.work_) { g.set_work(b); }
    ~WorkScope() { g_.set_work(was_ ? &old_ : nullptr); }
    WorkScope(const WorkScope &) = delete;
    WorkScope &operator=(const WorkScope &) = delete;

   private:
    LocalGrid &g_;
    bool was_;
    IndexBox old_;
  };

  // The nodes of the boxes (in the patch) set to 0 in a (stride doubles per node; nothing if a is
  // not in use), row by row along x.
  void zero_boxes(std::vector<double> &a, int stride, const std::vector<IndexBox> &boxes) const {
    if (a.empty()) return;
    for (const IndexBox &b : boxes) {
      if (b.empty()) continue;
      for (int k = b.lo[2]; k <= b.hi[2]; ++k)
        for (int j = b.lo[1]; j <= b.hi[1]; ++j)
          std::fill(a.begin() + stride * index(b.lo[0], j, k), a.begin() + stride * (index(b.hi[0], j, k) + 1), 0.0);
    }
  }

  // Adds the halo partial sums of data (stride doubles per node) into their owners.
  void reverse_sum(double *data, int stride);
  // Copies owned values into every rank's halo images.
  void forward(double *data, int stride);
  // One array of an exchange of several (stride doubles per node; data null: left out, on every
  // rank alike).
  struct Field {
    double *data;
    int stride;
  };
  // reverse_sum() and forward() of several arrays at once: one message per peer carries them all
  // (the same sums, each node's in the same order, and the same copies as one call per array)
  void reverse_sum(std::initializer_list<Field> fields);
  void forward(std::initializer_list<Field> fields);
  // The boxes of patch nodes that reverse_sum() and forward() read or write (halo and owner side,
  // all peers, periodic self images included).
  std::vector<IndexBox> exchanged_boxes() const;
  // wall time this rank waited for its peers' halo messages (MPI_Waitall of the exchanges), summed
  // since construction (fix balance/mpm measured: the work is the time minus the waits)
  double wait_seconds() const { return wait_seconds_; }
  // What the exchanges moved on this rank since construction (tools/scaling.py, docs/scaling.md):
  // calls of reverse_sum() and forward() (one exchange each, counted on one rank too), messages
  // and bytes to and from other ranks (periodic self images are copies, not messages).
  struct ExchangeCounts {
    long exchanges = 0, msgs_sent = 0, msgs_recv = 0;
    long long bytes_sent = 0, bytes_recv = 0;
  };
  const ExchangeCounts &exchange_counts() const { return counts_; }

 private:
  struct Transfer {      // one box of nodes exchanged with one peer
    int peer;
    IndexBox mine;       // node indices in my patch (halo side) or my owned box (owner side)
    int shift[3];        // peer index = my index - shift (halo side)
  };
  // setup()'s parts: the patch around the owned box; who exchanges which boxes with whom
  void place_patch(const double sublo[3], const int halo[2]);
  void find_transfers();
  bool nothing_to_move(const Field *fields, int nfields);
  void exchange(const Field *fields, int nfields, bool reverse);
  template <class BoxOf, class Pack, class Unpack>
  void exchange_peers(const std::vector<Transfer> &send, const std::vector<Transfer> &recv, int stride,
                      BoxOf &&box_of, Pack &&pack, Unpack &&unpack);

  GridSpec spec_;
  MPI_Comm comm_ = MPI_COMM_NULL;
  int me_ = 0, nprocs_ = 1;
  IndexBox patch_, owned_;
  int n_[3] = {0, 0, 0};
  std::size_t nnodes_ = 0;
  std::vector<Transfer> halo_side_;   // my halo nodes -> owner (reverse sends, forward receives)
  std::vector<Transfer> owner_side_;  // my owned nodes <- peer halos (reverse receives, forward sends)
  bool self_ = false;                 // some transfer is with this rank (periodic images)
  // exchange()'s buffers and scratch, kept from call to call (grown, never shrunk)
  std::vector<double> sendbuf_, recvbuf_, selfbuf_;
  std::vector<int> xcount_, xoff_, xpos_;
  std::vector<MPI_Request> req_;
  IndexBox work_;
  bool restricted_ = false;
  double wait_seconds_ = 0.0;
  ExchangeCounts counts_;
};

// The sparse grid (keyword sparse, docs/validation/performance.md): blocks of kSize^3 nodes of a rank's patch
// that hold values this sub-step, the blocks the material points' stencils reach plus, for good,
// the blocks of the nodes the halo exchange moves (so that the exchange stays as it is). The solver
// clears, updates and sweeps only active blocks; every node of an inactive block is zero, since
// a block that drops out of the set is cleared once (retired()).
class ActiveBlocks {
 public:
  static constexpr int kSize = 4;
  // all blocks inactive except those of the exchanged nodes (the node arrays are all zero)
  void setup(const LocalGrid &g);
  // starts the next set: only the exchanged nodes' blocks
  void begin();
  // nodes lo..hi (global indices, cut to the patch) are active
  void mark(const int lo[3], const int hi[3]) {
    int bl[3], bh[3];
    for (int d = 0; d < 3; ++d) {
      bl[d] = (std::max(lo[d], patch_.lo[d]) - patch_.lo[d]) / kSize;
      bh[d] = (std::min(hi[d], patch_.hi[d]) - patch_.lo[d]) / kSize;
    }
    for (int c = bl[2]; c <= bh[2]; ++c)
      for (int b = bl[1]; b <= bh[1]; ++b)
        for (int a = bl[0]; a <= bh[0]; ++a) on_[(std::size_t(c) * nb_[1] + b) * nb_[0] + a] = 1;
  }
  // the 2 x 2 x 2 blocks from the one that holds node (i, j, k) (global, in the patch) upward are
  // active: they cover any box of kSize + 1 nodes per direction from there. One store per call;
  // finish() spreads it.
  void mark_from(int i, int j, int k) {
    corner_[(std::size_t((k - patch_.lo[2]) / kSize) * nb_[1] + (j - patch_.lo[1]) / kSize) * nb_[0] +
            (i - patch_.lo[0]) / kSize] = 1;
  }
  // ends the set: boxes(), owned_boxes() and retired() (the blocks of the last set that are not
  // in this one)
  void finish();
  // node boxes (in the patch) of the active blocks, of their owned nodes, of the retired blocks
  const std::vector<IndexBox> &boxes() const { return boxes_; }
  const std::vector<IndexBox> &owned_boxes() const { return owned_boxes_; }
  const std::vector<IndexBox> &retired() const { return retired_; }
  bool active(int i, int j, int k) const {
    const std::size_t q = (std::size_t((k - patch_.lo[2]) / kSize) * nb_[1] + (j - patch_.lo[1]) / kSize) * nb_[0] +
                          (i - patch_.lo[0]) / kSize;
    return on_[q] != 0;
  }
  std::size_t total() const { return on_.size(); }

 private:
  IndexBox box_of(std::size_t q) const;
  IndexBox patch_, owned_;
  int nb_[3] = {0, 0, 0};
  std::vector<unsigned char> on_, fixed_, corner_;
  std::vector<std::size_t> list_;
  std::vector<IndexBox> boxes_, owned_boxes_, retired_;
};

}  // namespace mpm
