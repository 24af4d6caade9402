#include "mpm/grid.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace mpm {

namespace {

// First node index whose position is >= x (positions i*dx from the origin).
int first_node_at_or_above(const GridSpec &g, int d, double x) {
  const double xi = (x - g.origin[d]) / g.dx;
  return static_cast<int>(std::ceil(xi - 1e-9));
}

IndexBox shifted(const IndexBox &a, const int s[3]) {
  IndexBox r = a;
  for (int d = 0; d < 3; ++d) {
    r.lo[d] += s[d];
    r.hi[d] += s[d];
  }
  return r;
}

// Periodic images k*ncell (k in a range) that can bring box b over box a.
void image_range(const GridSpec &g, const IndexBox &a, const IndexBox &b, int kmin[3], int kmax[3]) {
  for (int d = 0; d < 3; ++d) {
    if (!g.periodic[d]) {
      kmin[d] = kmax[d] = 0;
      continue;
    }
    const int n = g.ncell[d];
    kmin[d] = static_cast<int>(std::floor(double(a.lo[d] - b.hi[d]) / n));
    kmax[d] = static_cast<int>(std::ceil(double(a.hi[d] - b.lo[d]) / n));
  }
}

// Some transfer of the list is with rank me.
template <class List>
bool any_with(const List &list, int me) {
  return std::any_of(list.begin(), list.end(), [me](const auto &t) { return t.peer == me; });
}

}  // namespace

IndexBox owned_box(const GridSpec &g, const double sublo[3], const double subhi[3]) {
  IndexBox b;
  for (int d = 0; d < 3; ++d) {
    const double glo = g.origin[d], ghi = g.upper(d);
    const double tol = 1e-9 * g.dx;
    b.lo[d] = (sublo[d] <= glo + tol) ? g.node_lo(d) : first_node_at_or_above(g, d, sublo[d]);
    b.hi[d] = (subhi[d] >= ghi - tol) ? g.node_hi(d) : first_node_at_or_above(g, d, subhi[d]) - 1;
    if (subhi[d] <= glo + tol || sublo[d] >= ghi - tol) b.hi[d] = b.lo[d] - 1;  // no overlap
    if (g.periodic[d]) {
      b.lo[d] = std::max(b.lo[d], 0);
      b.hi[d] = std::min(b.hi[d], g.ncell[d] - 1);
    }
  }
  return b;
}

void LocalGrid::setup(const GridSpec &spec, MPI_Comm comm, const double sublo[3],
                      const double subhi[3], const int halo[2]) {
  spec_ = spec;
  comm_ = comm;
  MPI_Comm_rank(comm, &me_);
  MPI_Comm_size(comm, &nprocs_);

  owned_ = owned_box(spec, sublo, subhi);
  place_patch(sublo, halo);
  find_transfers();
}

void LocalGrid::place_patch(const double sublo[3], const int halo[2]) {
  const GridSpec &spec = spec_;
  // The patch: owned nodes (or, for a rank without any, the nodes nearest its
  // subdomain) widened by the halo, clipped to the grid in non-periodic dims.
  for (int d = 0; d < 3; ++d) {
    int lo = owned_.lo[d], hi = owned_.hi[d];
    if (hi < lo) {
      lo = first_node_at_or_above(spec, d, sublo[d]);
      hi = lo - 1;
    }
    patch_.lo[d] = lo - halo[0];
    patch_.hi[d] = hi + halo[1];
    if (!spec.periodic[d]) {
      patch_.lo[d] = std::max(patch_.lo[d], spec.node_lo(d));
      patch_.hi[d] = std::min(patch_.hi[d], spec.node_hi(d));
    }
    n_[d] = std::max(0, patch_.hi[d] - patch_.lo[d] + 1);
  }
  nnodes_ = std::size_t(n_[0]) * n_[1] * n_[2];
}

void LocalGrid::find_transfers() {
  const GridSpec &spec = spec_;
  // Everybody's owned and patch boxes, to find who exchanges what with whom.
  std::vector<int> boxes(12 * nprocs_);
  int mine[12];
  for (int d = 0; d < 3; ++d) {
    mine[d] = owned_.lo[d];
    mine[3 + d] = owned_.hi[d];
    mine[6 + d] = patch_.lo[d];
    mine[9 + d] = patch_.hi[d];
  }
  MPI_Allgather(mine, 12, MPI_INT, boxes.data(), 12, MPI_INT, comm_);
  auto box_of = [&](int r, int off) {
    IndexBox b;
    for (int d = 0; d < 3; ++d) {
      b.lo[d] = boxes[12 * r + off + d];
      b.hi[d] = boxes[12 * r + off + 3 + d];
    }
    return b;
  };

  halo_side_.clear(), owner_side_.clear();
  for (int q = 0; q < nprocs_; ++q) {
    // My halo nodes that are images of nodes q owns.
    const IndexBox oq = box_of(q, 0);
    if (!oq.empty() && !patch_.empty()) {
      int kmin[3], kmax[3];
      image_range(spec, patch_, oq, kmin, kmax);
      for (int kz = kmin[2]; kz <= kmax[2]; ++kz)
        for (int ky = kmin[1]; ky <= kmax[1]; ++ky)
          for (int kx = kmin[0]; kx <= kmax[0]; ++kx) {
            int s[3] = {kx * spec.ncell[0], ky * spec.ncell[1], kz * spec.ncell[2]};
            if (q == me_ && s[0] == 0 && s[1] == 0 && s[2] == 0) continue;
            IndexBox b = patch_.cut(shifted(oq, s));
            if (!b.empty()) halo_side_.push_back({q, b, {s[0], s[1], s[2]}});
          }
    }
    // Nodes I own that are images of halo nodes of q (same enumeration order as q uses).
    const IndexBox pq = box_of(q, 6);
    if (!owned_.empty() && !pq.empty()) {
      int kmin[3], kmax[3];
      image_range(spec, pq, owned_, kmin, kmax);
      for (int kz = kmin[2]; kz <= kmax[2]; ++kz)
        for (int ky = kmin[1]; ky <= kmax[1]; ++ky)
          for (int kx = kmin[0]; kx <= kmax[0]; ++kx) {
            int s[3] = {kx * spec.ncell[0], ky * spec.ncell[1], kz * spec.ncell[2]};
            if (q == me_ && s[0] == 0 && s[1] == 0 && s[2] == 0) continue;
            IndexBox b = pq.cut(shifted(owned_, s));  // q's halo indices
            if (b.empty()) continue;
            int ms[3] = {-s[0], -s[1], -s[2]};
            owner_side_.push_back({q, shifted(b, ms), {s[0], s[1], s[2]}});
          }
    }
  }
  self_ = any_with(halo_side_, me_) || any_with(owner_side_, me_);  // transfers with myself
}

bool LocalGrid::nothing_to_move(const Field *fields, int nfields) {
  if (nprocs_ > 1 || self_) return false;
  // one rank, no periodic images: no copy to make; counted as exchange() counts it (an exchange
  // with at least one array), so that the exchanges per step read the same on any number of ranks
  for (int q = 0; q < nfields; ++q)
    if (fields[q].data) {
      ++counts_.exchanges;
      break;
    }
  return true;
}

void LocalGrid::reverse_sum(double *data, int stride) { reverse_sum({Field{data, stride}}); }
void LocalGrid::forward(double *data, int stride) { forward({Field{data, stride}}); }
void LocalGrid::reverse_sum(std::initializer_list<Field> fields) {
  if (nothing_to_move(fields.begin(), static_cast<int>(fields.size()))) return;
  exchange(fields.begin(), static_cast<int>(fields.size()), true);
}
void LocalGrid::forward(std::initializer_list<Field> fields) {
  if (nothing_to_move(fields.begin(), static_cast<int>(fields.size()))) return;
  exchange(fields.begin(), static_cast<int>(fields.size()), false);
}

namespace {

// A box moves row by row along x: the stride values of the nodes of one row are contiguous in
// data (x fastest). Buffers hold the boxes' rows one after the other (z, y, x, value: the order
// node by node), so that the rows of one box follow each other in the message. sv: values per
// node; row_step: values from one row to the next along y.
double *pack_box(const LocalGrid &g, const double *data, const IndexBox &b, double *buf, std::size_t sv,
                 std::size_t row_step) {
  if (b.empty()) return buf;
  const std::size_t len = std::size_t(b.hi[0] - b.lo[0] + 1) * sv;
  for (int k = b.lo[2]; k <= b.hi[2]; ++k) {
    const double *row = data + g.index(b.lo[0], b.lo[1], k) * sv;
    for (int j = b.lo[1]; j <= b.hi[1]; ++j, row += row_step, buf += len)
      std::memcpy(buf, row, len * sizeof(double));
  }
  return buf;
}

// reverse: each value added to its node once (per transfer, in list order: the same sums);
// forward: stored
const double *unpack_box(const LocalGrid &g, double *data, const IndexBox &b, const double *buf, std::size_t sv,
                         std::size_t row_step, bool reverse) {
  if (b.empty()) return buf;
  const std::size_t len = std::size_t(b.hi[0] - b.lo[0] + 1) * sv;
  for (int k = b.lo[2]; k <= b.hi[2]; ++k) {
    double *row = data + g.index(b.lo[0], b.lo[1], k) * sv;
    for (int j = b.lo[1]; j <= b.hi[1]; ++j, row += row_step, buf += len) {
      if (reverse)
        for (std::size_t m = 0; m < len; ++m) row[m] += buf[m];
      else
        std::memcpy(row, buf, len * sizeof(double));
    }
  }
  return buf;
}

}  // namespace

void LocalGrid::exchange(const Field *fields, int nfields, bool reverse) {
  // reverse: halo boxes are packed and sent, owner boxes receive and add.
  // forward: owner boxes are packed and sent, halo boxes receive and store.
  const std::vector<Transfer> &send = reverse ? halo_side_ : owner_side_;
  const std::vector<Transfer> &recv = reverse ? owner_side_ : halo_side_;
  // the arrays in use; stride: the doubles per node of all of them (a box's part of a message:
  // its rows of the first array, then of the next, ...)
  Field f[8];
  int nf = 0, stride = 0;
  for (int q = 0; q < nfields; ++q)
    if (fields[q].data) {
      if (nf == 8) throw std::logic_error("LocalGrid::exchange: more than 8 arrays at once");
      f[nf++] = fields[q];
      stride += fields[q].stride;
    }
  if (nf == 0) return;
  const std::size_t sv = std::size_t(stride);
  // with a work box (the projection's sweeps) only its part of each box moves: the same part on
  // both sides, since every rank's work box is one global box cut to its patch (the whole patch
  // along periodic dimensions); outside it both sides hold the value of a node without fluid
  auto box_of = [&](const Transfer &t) { return restricted_ ? t.mine.cut(work_) : t.mine; };
  ++counts_.exchanges;

  // the boxes' rows to and from the buffers (pack_box, unpack_box)
  // (each array's values of a node see the same additions in the same order as alone)
  auto pack = [&](const IndexBox &b, double *buf) {
    for (int q = 0; q < nf; ++q)
      buf = pack_box(*this, f[q].data, b, buf, std::size_t(f[q].stride), std::size_t(n_[0]) * f[q].stride);
    return buf;
  };
  auto unpack = [&](const IndexBox &b, const double *buf) {
    for (int q = 0; q < nf; ++q)
      buf = unpack_box(*this, f[q].data, b, buf, std::size_t(f[q].stride), std::size_t(n_[0]) * f[q].stride, reverse);
    return buf;
  };

  // Self images (periodic wrap on this rank): through a buffer, in the same order.
  {
    std::size_t n = 0;
    for (const auto &t : send)
      if (t.peer == me_) n += std::size_t(box_of(t).count()) * sv;
    if (n > 0) {
      if (selfbuf_.size() < n) selfbuf_.resize(n);
      double *w = selfbuf_.data();
      for (const auto &t : send)
        if (t.peer == me_) w = pack(box_of(t), w);
      const double *r = selfbuf_.data();
      for (const auto &t : recv)
        if (t.peer == me_) r = unpack(box_of(t), r);
    }
  }
  if (nprocs_ == 1) return;
  exchange_peers(send, recv, stride, box_of, pack, unpack);
}

// exchange() with the other ranks: one message per peer, its boxes in list order.
template <class BoxOf, class Pack, class Unpack>
void LocalGrid::exchange_peers(const std::vector<Transfer> &send, const std::vector<Transfer> &recv, int stride,
                               BoxOf &&box_of, Pack &&pack, Unpack &&unpack) {
  // One message per peer: all boxes for that peer, in list order.
  // xcount_: values sent to / received from each peer; xoff_: their offsets in the buffers
  // (then the write positions).
  const int np = nprocs_;
  xcount_.assign(2 * std::size_t(np), 0);
  int *sendcount = xcount_.data(), *recvcount = sendcount + np;
  for (const auto &t : send)
    if (t.peer != me_) sendcount[t.peer] += int(box_of(t).count()) * stride;
  for (const auto &t : recv)
    if (t.peer != me_) recvcount[t.peer] += int(box_of(t).count()) * stride;
  xoff_.resize(2 * (std::size_t(np) + 1));
  int *soff = xoff_.data(), *roff = soff + np + 1;
  soff[0] = roff[0] = 0;
  for (int q = 0; q < np; ++q) {
    soff[q + 1] = soff[q] + sendcount[q];
    roff[q + 1] = roff[q] + recvcount[q];
  }
  if (sendbuf_.size() < std::size_t(soff[np])) sendbuf_.resize(soff[np]);
  if (recvbuf_.size() < std::size_t(roff[np])) recvbuf_.resize(roff[np]);
  // each peer's boxes, in list order, at consecutive places of its part of buf (offsets off)
  auto peer_boxes = [&](const std::vector<Transfer> &list, const int *off, double *buf, auto &&move) {
    xpos_.assign(off, off + np);
    for (const auto &t : list)
      if (t.peer != me_) {
        const IndexBox b = box_of(t);
        move(b, buf + xpos_[t.peer]);
        xpos_[t.peer] += int(b.count()) * stride;
      }
  };
  peer_boxes(send, soff, sendbuf_.data(), pack);
  req_.clear();
  for (int q = 0; q < np; ++q)
    if (recvcount[q] > 0) {
      req_.emplace_back();
      MPI_Irecv(recvbuf_.data() + roff[q], recvcount[q], MPI_DOUBLE, q, 7301, comm_, &req_.back());
      ++counts_.msgs_recv;
      counts_.bytes_recv += (long long)recvcount[q] * sizeof(double);
    }
  for (int q = 0; q < np; ++q)
    if (sendcount[q] > 0) {
      req_.emplace_back();
      MPI_Isend(sendbuf_.data() + soff[q], sendcount[q], MPI_DOUBLE, q, 7301, comm_, &req_.back());
      ++counts_.msgs_sent;
      counts_.bytes_sent += (long long)sendcount[q] * sizeof(double);
    }
  const double tw = MPI_Wtime();
  MPI_Waitall(int(req_.size()), req_.data(), MPI_STATUSES_IGNORE);
  wait_seconds_ += MPI_Wtime() - tw;
  peer_boxes(recv, roff, recvbuf_.data(), unpack);
}

std::vector<IndexBox> LocalGrid::exchanged_boxes() const {
  std::vector<IndexBox> out;
  for (const auto &t : halo_side_) out.push_back(t.mine);
  for (const auto &t : owner_side_) out.push_back(t.mine);
  return out;
}

void ActiveBlocks::setup(const LocalGrid &g) {
  patch_ = g.patch();
  owned_ = g.owned();
  for (int d = 0; d < 3; ++d) nb_[d] = (g.extent(d) + kSize - 1) / kSize;
  fixed_.assign(std::size_t(nb_[0]) * nb_[1] * nb_[2], 0);
  on_ = fixed_;
  for (const IndexBox &b : g.exchanged_boxes()) {
    if (b.empty()) continue;
    mark(b.lo, b.hi);
  }
  fixed_ = on_;
  corner_.assign(on_.size(), 0);
  list_.clear();
  boxes_.clear();
  owned_boxes_.clear();
  retired_.clear();
}

void ActiveBlocks::begin() {
  std::copy(fixed_.begin(), fixed_.end(), on_.begin());
  std::fill(corner_.begin(), corner_.end(), 0);
}

IndexBox ActiveBlocks::box_of(std::size_t q) const {
  const int a = int(q % nb_[0]), b = int((q / nb_[0]) % nb_[1]), c = int(q / (std::size_t(nb_[0]) * nb_[1]));
  const int blk[3] = {a, b, c};
  IndexBox r;
  for (int d = 0; d < 3; ++d) {
    r.lo[d] = patch_.lo[d] + kSize * blk[d];
    r.hi[d] = std::min(r.lo[d] + kSize - 1, patch_.hi[d]);
  }
  return r;
}

void ActiveBlocks::finish() {
  const std::size_t sy = nb_[0], sz = std::size_t(nb_[0]) * nb_[1];
  for (int c = 0; c < nb_[2]; ++c)
    for (int b = 0; b < nb_[1]; ++b)
      for (int a = 0; a < nb_[0]; ++a) {
        const std::size_t q = c * sz + b * sy + a;
        if (!corner_[q]) continue;
        const int a1 = std::min(a + 1, nb_[0] - 1), b1 = std::min(b + 1, nb_[1] - 1), c1 = std::min(c + 1, nb_[2] - 1);
        for (int z = c; z <= c1; ++z)
          for (int y = b; y <= b1; ++y)
            for (int x = a; x <= a1; ++x) on_[z * sz + y * sy + x] = 1;
      }
  retired_.clear();
  for (const std::size_t q : list_)
    if (!on_[q]) retired_.push_back(box_of(q));
  list_.clear();
  boxes_.clear();
  owned_boxes_.clear();
  for (std::size_t q = 0; q < on_.size(); ++q) {
    if (!on_[q]) continue;
    list_.push_back(q);
    const IndexBox b = box_of(q);
    boxes_.push_back(b);
    const IndexBox o = b.cut(owned_);
    if (!o.empty()) owned_boxes_.push_back(o);
  }
}

}  // namespace mpm
