// The pressure projection's state between runs and in restart files (docs/theory/projection.md,
// "Restart and the state between runs").
#include "mpm/projection.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "mpm/error.h"
#include "mpm/grid_fields.h"

namespace mpm {

void Projection::save(ProjectionState &s) const {
  s.valid = true;
  s.box = grid_.owned();
  s.have_theta_last = have_theta_last_;
  s.iterations = last_.iterations;
  s.residual = last_.relative_residual;
  const std::size_t nb = static_cast<std::size_t>(s.box.count());
  s.p.resize(nb);
  s.grad.resize(3 * nb);
  s.theta_last.resize(have_theta_last_ ? nb : 0);
  s.have_avg = have_avg_;
  s.p_avg.resize(have_avg_ ? nb : 0);
  const bool acc = acceleration_on();
  s.have_acc = acc;
  s.p_acc.resize(acc ? nb : 0);
  const bool gl = grain_level() != nullptr;
  s.have_grain_level = gl;
  s.grain_level.resize(gl ? nb : 0);
  // the gradient the grains feel at the next step (grain_pressure: of the multiplier or of the
  // acceleration pressure)
  const std::vector<double> &grad = opt_.grain_pressure_acceleration ? grad_acc_ : grad_;
  std::size_t q = 0;
  grid_.for_owned([&](int, int, int, std::size_t n) {  // k, j, i with i fastest: the box's order
    s.p[q] = p_[n];
    for (int d = 0; d < 3; ++d) s.grad[3 * q + d] = grad[3 * n + d];
    if (have_theta_last_) s.theta_last[q] = theta_last_[n];
    if (have_avg_) s.p_avg[q] = p_avg_[n];
    if (acc) s.p_acc[q] = p_acc_[n];
    if (gl) s.grain_level[q] = gl_[n];
    ++q;
  });
}

bool Projection::load(const ProjectionState &s) {
  const IndexBox &b = s.box;
  int ok = s.valid ? 1 : 0, all = 0;
  const IndexBox &ob = grid_.owned();
  if (!ob.empty())
    for (int d = 0; d < 3; ++d)
      if (ob.lo[d] < b.lo[d] || ob.hi[d] > b.hi[d]) ok = 0;
  MPI_Allreduce(&ok, &all, 1, MPI_INT, MPI_MIN, comm_);
  if (!all) return false;
  const long ex = b.hi[0] - b.lo[0] + 1, ey = b.hi[1] - b.lo[1] + 1;
  // the place of node (i, j, k) in the state's box
  auto at = [&](int i, int j, int k) {
    return static_cast<std::size_t>(((k - b.lo[2]) * ey + (j - b.lo[1])) * ex + (i - b.lo[0]));
  };
  const bool grains_acc = opt_.grain_pressure_acceleration;
  std::vector<double> &grad = grains_acc ? grad_acc_ : grad_;  // the grains' (save)
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    const std::size_t q = at(i, j, k);
    p_[n] = s.p[q];
    for (int d = 0; d < 3; ++d) grad[3 * n + d] = s.grad[3 * q + d];
  });
  grid_.forward(p_.data(), 1);
  grid_.forward(grad.data(), 3);
  have_theta_last_ = s.have_theta_last;
  if (have_theta_last_) {
    theta_last_.assign(grid_.size(), 1.0);
    grid_.for_owned([&](int i, int j, int k, std::size_t n) {
      theta_last_[n] = s.theta_last[at(i, j, k)];
    });
    grid_.forward(theta_last_.data(), 1);
  }
  // the averaged pressure goes on only if this run averages too (else it starts at the next solve)
  have_avg_ = s.have_avg && opt_.pressure_average > 0.0;
  if (have_avg_) grid_.for_owned([&](int i, int j, int k, std::size_t n) { p_avg_[n] = s.p_avg[at(i, j, k)]; });
  const bool acc = acceleration_on();
  if (s.have_acc && acc) {
    grid_.for_owned([&](int i, int j, int k, std::size_t n) { p_acc_[n] = s.p_acc[at(i, j, k)]; });
    grid_.forward(p_acc_.data(), 1);
  }
  if (s.have_grain_level) {
    gl_.assign(grid_.size(), 0.0);
    grid_.for_owned([&](int i, int j, int k, std::size_t n) { gl_[n] = s.grain_level[at(i, j, k)]; });
    grid_.forward(gl_.data(), 1);
  } else {
    gl_.clear();
  }
  largest_pressure();
  last_.iterations = s.iterations;
  last_.relative_residual = s.residual;
  // the padding nodes' copies, as after a solve (their labels are SOLID from the grid alone)
  lab_.reset(grid_);
  extend_to_padding(p_, p_ext_, 1);
  extend_to_padding(grad_, grad_ext_, 3);
  if (acc) extend_to_padding(p_acc_, p_acc_ext_, 1);
  if (grains_acc) extend_to_padding(grad_acc_, grad_acc_ext_, 3);
  if (have_theta_last_ && !mesh_) {  // with grains: as after a solve (project, acceleration_pressure)
    mirror_to_padding(grad_, grad_ext_);
    if (grains_acc) mirror_to_padding(grad_acc_, grad_acc_ext_);
  }
  work_prev_ = grid_.patch();  // values anywhere: a sparse step retires all outside its work box
  have_prev_ = true;
  return true;
}

namespace {
// layout of ProjectionState::pack (1: without p_avg; 2: without grain_level)
constexpr double kStateVersion = 3.0;
}

void ProjectionState::pack(std::vector<double> &out) const {
  out.push_back(valid ? kStateVersion : 0.0);
  if (!valid) return;
  for (int d = 0; d < 3; ++d) out.push_back(box.lo[d]);
  for (int d = 0; d < 3; ++d) out.push_back(box.hi[d]);
  out.push_back(have_theta_last ? 1.0 : 0.0);
  out.push_back(iterations);
  out.push_back(residual);
  out.insert(out.end(), p.begin(), p.end());
  out.insert(out.end(), grad.begin(), grad.end());
  out.insert(out.end(), theta_last.begin(), theta_last.end());
  out.push_back(have_avg ? 1.0 : 0.0);
  out.insert(out.end(), p_avg.begin(), p_avg.end());
  out.push_back(have_acc ? 1.0 : 0.0);
  out.insert(out.end(), p_acc.begin(), p_acc.end());
  out.push_back(have_grain_level ? 1.0 : 0.0);
  out.insert(out.end(), grain_level.begin(), grain_level.end());
}

std::size_t ProjectionState::unpack(const double *in) {
  *this = ProjectionState();
  if (in[0] == 0.0) return 1;
  if (in[0] != kStateVersion && in[0] != 1.0 && in[0] != 2.0) {
    std::ostringstream os;
    os << "Fix mpm/fluid: the restart file holds a pressure-projection state of layout " << in[0]
       << "; this build reads layout " << kStateVersion;
    throw Error(os.str());
  }
  std::size_t m = 1;
  for (int d = 0; d < 3; ++d) box.lo[d] = static_cast<int>(in[m++]);
  for (int d = 0; d < 3; ++d) box.hi[d] = static_cast<int>(in[m++]);
  have_theta_last = in[m++] != 0.0;
  iterations = static_cast<int>(in[m++]);
  residual = in[m++];
  const std::size_t nb = static_cast<std::size_t>(box.count());
  p.assign(in + m, in + m + nb);
  m += nb;
  grad.assign(in + m, in + m + 3 * nb);
  m += 3 * nb;
  if (have_theta_last) {
    theta_last.assign(in + m, in + m + nb);
    m += nb;
  }
  if (in[0] >= 2.0) {
    have_avg = in[m++] != 0.0;
    if (have_avg) {
      p_avg.assign(in + m, in + m + nb);
      m += nb;
    }
    have_acc = in[m++] != 0.0;
    if (have_acc) {
      p_acc.assign(in + m, in + m + nb);
      m += nb;
    }
  }
  if (in[0] >= 3.0) {
    have_grain_level = in[m++] != 0.0;
    if (have_grain_level) {
      grain_level.assign(in + m, in + m + nb);
      m += nb;
    }
  }
  valid = true;
  return m;
}

ProjectionState gather_global(const ProjectionState &local, const GridSpec &spec, MPI_Comm comm) {
  int nprocs = 1;
  MPI_Comm_size(comm, &nprocs);
  int v = local.valid ? 1 : 0, allv = 0;
  MPI_Allreduce(&v, &allv, 1, MPI_INT, MPI_MIN, comm);
  ProjectionState g;
  if (!allv) return g;
  g.valid = true;
  for (int d = 0; d < 3; ++d) {
    g.box.lo[d] = spec.node_lo(d);
    g.box.hi[d] = spec.node_hi(d);
  }
  // the optional fields every rank holds
  const int mine_has[4] = {local.have_theta_last, local.have_avg, local.have_acc, local.have_grain_level};
  int all_have[4];
  MPI_Allreduce(mine_has, all_have, 4, MPI_INT, MPI_MIN, comm);
  g.have_theta_last = all_have[0] != 0;
  g.have_avg = all_have[1] != 0;
  g.have_acc = all_have[2] != 0;
  g.have_grain_level = all_have[3] != 0;
  g.iterations = local.iterations;
  g.residual = local.residual;
  // every rank's box and values (p, grad, theta, p_avg, p_acc, grain_level per node), copied into
  // place on every rank
  const int per = 4 + (g.have_theta_last ? 1 : 0) + (g.have_avg ? 1 : 0) + (g.have_acc ? 1 : 0) +
                  (g.have_grain_level ? 1 : 0);
  std::vector<double> mine;
  const std::size_t nb = static_cast<std::size_t>(local.box.count());
  mine.reserve(per * nb);
  for (std::size_t q = 0; q < nb; ++q) {
    mine.push_back(local.p[q]);
    for (int d = 0; d < 3; ++d) mine.push_back(local.grad[3 * q + d]);
    if (g.have_theta_last) mine.push_back(local.theta_last[q]);
    if (g.have_avg) mine.push_back(local.p_avg[q]);
    if (g.have_acc) mine.push_back(local.p_acc[q]);
    if (g.have_grain_level) mine.push_back(local.grain_level[q]);
  }
  std::vector<int> boxes(6 * nprocs), counts(nprocs), displs(nprocs);
  const int mybox[6] = {local.box.lo[0], local.box.lo[1], local.box.lo[2], local.box.hi[0], local.box.hi[1], local.box.hi[2]};
  MPI_Allgather(mybox, 6, MPI_INT, boxes.data(), 6, MPI_INT, comm);
  int mycount = static_cast<int>(mine.size());
  MPI_Allgather(&mycount, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  long total = 0;
  for (int r = 0; r < nprocs; ++r) {
    displs[r] = static_cast<int>(total);
    total += counts[r];
  }
  std::vector<double> all(static_cast<std::size_t>(total));
  MPI_Allgatherv(mine.data(), mycount, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, comm);
  const std::size_t ng = static_cast<std::size_t>(g.box.count());
  g.p.assign(ng, 0.0);
  g.grad.assign(3 * ng, 0.0);
  g.theta_last.assign(g.have_theta_last ? ng : 0, 1.0);
  g.p_avg.assign(g.have_avg ? ng : 0, 0.0);
  g.p_acc.assign(g.have_acc ? ng : 0, 0.0);
  g.grain_level.assign(g.have_grain_level ? ng : 0, kLevelMin);
  const long gx = g.box.hi[0] - g.box.lo[0] + 1, gy = g.box.hi[1] - g.box.lo[1] + 1;
  for (int r = 0; r < nprocs; ++r) {
    const int *b = &boxes[6 * r];
    std::size_t q = static_cast<std::size_t>(displs[r]);
    for (int k = b[2]; k <= b[5]; ++k)
      for (int j = b[1]; j <= b[4]; ++j)
        for (int i = b[0]; i <= b[3]; ++i) {
          const std::size_t n = static_cast<std::size_t>(((k - g.box.lo[2]) * gy + (j - g.box.lo[1])) * gx + (i - g.box.lo[0]));
          g.p[n] = all[q++];
          for (int d = 0; d < 3; ++d) g.grad[3 * n + d] = all[q++];
          if (g.have_theta_last) g.theta_last[n] = all[q++];
          if (g.have_avg) g.p_avg[n] = all[q++];
          if (g.have_acc) g.p_acc[n] = all[q++];
          if (g.have_grain_level) g.grain_level[n] = all[q++];
        }
  }
  return g;
}

}  // namespace mpm
