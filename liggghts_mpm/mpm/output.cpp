// The solver's outputs: the global vector f_ID[1..18] and the HDF5 + XDMF series of keyword
// output (points, and grid nodes, gathered on rank 0).
#include <algorithm>
#include <cmath>

#include "mpm/error.h"
#include "mpm/hdf5_series.h"
#include "mpm/projection.h"
#include "mpm/solver.h"

namespace mpm {

void FluidSolver::global_vector(double out[kGlobalSize]) {
  const GridSpec &gs = opt.grid;
  double **x = pts.x, **v = pts.v;
  const double *rmass = pts.rmass;
  const double *spacing = state.spacing;
  double sum[4] = {0, 0, 0, state.n_clamped};  // mass, kinetic energy, points, clamped
  // |v|max, front, height, p max, wall time of the fluid and of the coupling (slowest rank)
  double mx[7] = {0.0, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL, time_fluid, time_couple, time_pressure_solver()};
  for (int i = 0; i < pts.nlocal; ++i) {
    if (!is_point(i)) continue;
    const double v2 = v[i][0] * v[i][0] + v[i][1] * v[i][1] + v[i][2] * v[i][2];
    sum[0] += rmass[i];
    sum[1] += 0.5 * rmass[i] * v2;
    sum[2] += 1.0;
    mx[0] = std::max(mx[0], std::sqrt(v2));
    mx[1] = std::max(mx[1], x[i][opt.front_axis] + 0.5 * spacing[opt.front_axis]);
    if (std::fabs(x[i][opt.wall_axis] - opt.wall_pos) < gs.dx)
      mx[2] = std::max(mx[2], x[i][opt.height_axis] + 0.5 * spacing[opt.height_axis]);
    mx[3] = std::max(mx[3], pts.state[i][C_P]);
  }
  double fg[3] = {0, 0, 0}, gfg[3];
  if (opt.coupled)
    for (int k = 0; k < pts.nlocal; ++k)
      if (is_grain(k))
        for (int d = 0; d < 3; ++d) fg[d] += pts.state[k][C_FGRAIN + d];
  MPI_Allreduce(fg, gfg, 3, MPI_DOUBLE, MPI_SUM, comm_);
  for (int d = 0; d < 3; ++d) out[10 + d] = gfg[d];
  double gsum[4], gmx[7];
  MPI_Allreduce(sum, gsum, 4, MPI_DOUBLE, MPI_SUM, comm_);
  MPI_Allreduce(mx, gmx, 7, MPI_DOUBLE, MPI_MAX, comm_);
  out[0] = gsum[0];
  out[1] = gsum[1];
  out[2] = gmx[0];
  out[3] = std::isfinite(gmx[1]) ? gmx[1] : 0.0;
  out[4] = std::isfinite(gmx[2]) ? gmx[2] - gs.origin[opt.height_axis] : 0.0;
  out[5] = state.nsub;
  out[6] = std::min(dt_stable_, dt_couple_);
  out[7] = gsum[3];
  out[8] = gsum[2];
  out[9] = std::isfinite(gmx[3]) ? gmx[3] : 0.0;
  out[13] = gmx[4];
  out[14] = gmx[5];
  out[15] = proj_ ? proj_->iterations() : 0.0;
  out[16] = proj_ ? proj_->residual() : 0.0;
  out[17] = gmx[6];
}

double FluidSolver::time_pressure_solver() const { return proj_ ? proj_->solver_seconds() : 0.0; }
long FluidSolver::pressure_solves() const { return proj_ ? proj_->solves() : 0; }
long FluidSolver::pressure_iterations_summed() const { return proj_ ? proj_->iterations_summed() : 0; }

namespace {
// rows of all ranks on rank 0 (empty elsewhere)
std::vector<double> gather_rows(const std::vector<double> &mine, MPI_Comm comm, int me, int nprocs) {
  int n = static_cast<int>(mine.size());
  std::vector<int> counts(nprocs), displs(nprocs, 0);
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  std::vector<double> all;
  if (me == 0) {
    for (int q = 1; q < nprocs; ++q) displs[q] = displs[q - 1] + counts[q - 1];
    all.resize(displs.back() + counts.back());
  }
  MPI_Gatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0, comm);
  return all;
}

int point_field_size(const std::string &f) { return f == "v" ? 3 : f == "tau" ? 6 : f == "affine" ? 9 : 1; }
}  // namespace

void FluidSolver::write_output() {
  if (last_output_step_ == clock.step) return;
  last_output_step_ = clock.step;
  const GridSpec &gs = opt.grid;
  const std::vector<std::string> &pfields = opt.out_point_fields, &gfields = opt.out_grid_fields;
  int stride = 3;
  for (const auto &f : pfields) stride += point_field_size(f);

  std::vector<double> buf;
  for (int i = 0; i < pts.nlocal; ++i) {
    if (!is_point(i)) continue;
    const double *s = pts.state[i];
    for (int d = 0; d < 3; ++d) buf.push_back(pts.x[i][d]);
    for (const auto &f : pfields) {
      if (f == "v") for (int d = 0; d < 3; ++d) buf.push_back(pts.v[i][d]);
      else if (f == "p") buf.push_back(s[C_P]);
      else if (f == "rho") buf.push_back(s[C_RHO]);
      else if (f == "vol") buf.push_back(s[C_VOL]);
      else if (f == "tau") for (int c = 0; c < 6; ++c) buf.push_back(s[C_TAU + c]);
      else if (f == "theta") buf.push_back(s[C_THETA]);
      else if (f == "id") buf.push_back(static_cast<double>(pts.tag[i]));
      else if (f == "type") buf.push_back(static_cast<double>(pts.type[i]));
      else if (f == "affine") for (int c = 0; c < 9; ++c) buf.push_back(s[C_AFF + c]);
      else if (f == "mass") buf.push_back(pts.rmass[i]);
    }
  }
  const std::vector<double> all = gather_rows(buf, comm_, me_, nprocs_);

  // Grid: owned real nodes (not the padding) as (global index, values).
  GridBlock gb;
  std::vector<double> gall;
  const bool want_grid = !gfields.empty();
  int gstride = 1;
  for (const auto &f : gfields) gstride += (f == "v") ? 3 : 1;
  if (want_grid) {
    std::vector<double> gbuf;
    int nn[3];
    for (int d = 0; d < 3; ++d) nn[d] = gs.periodic[d] ? gs.ncell[d] : gs.ncell[d] + 1;
    const IndexBox &ob = grid_.owned();
    for (int k = std::max(ob.lo[2], 0); k <= std::min(ob.hi[2], nn[2] - 1); ++k)
      for (int j = std::max(ob.lo[1], 0); j <= std::min(ob.hi[1], nn[1] - 1); ++j)
        for (int i = std::max(ob.lo[0], 0); i <= std::min(ob.hi[0], nn[0] - 1); ++i) {
          const std::size_t n = grid_.index(i, j, k);
          gbuf.push_back(static_cast<double>((static_cast<long>(k) * nn[1] + j) * nn[0] + i));
          for (const auto &f : gfields) {
            if (f == "mass") gbuf.push_back(g_.p2g[P2gRec::N * n + P2gRec::M]);
            else for (int d = 0; d < 3; ++d) gbuf.push_back(g_.vel[VelRec::N * n + VelRec::V_NEW + d]);
          }
        }
    gall = gather_rows(gbuf, comm_, me_, nprocs_);
    for (int d = 0; d < 3; ++d) {
      gb.n[d] = nn[d];
      gb.origin[d] = gs.origin[d];
      gb.spacing[d] = gs.dx;
    }
  }

  if (me_ != 0) return;
  PointBlock pb;
  pb.n = all.size() / stride;
  pb.xyz.resize(3 * pb.n);
  for (const auto &f : pfields) pb.fields.push_back({f, point_field_size(f), std::vector<double>(pb.n * point_field_size(f))});
  for (std::size_t p = 0; p < pb.n; ++p) {
    const double *r = &all[p * stride];
    for (int d = 0; d < 3; ++d) pb.xyz[3 * p + d] = r[d];
    int off = 3;
    for (auto &fl : pb.fields) {
      for (int c = 0; c < fl.ncomp; ++c) fl.data[p * fl.ncomp + c] = r[off + c];
      off += fl.ncomp;
    }
  }
  if (want_grid) {
    const std::size_t nn = std::size_t(gb.n[0]) * gb.n[1] * gb.n[2];
    for (const auto &f : gfields) gb.fields.push_back({f, f == "v" ? 3 : 1, std::vector<double>(nn * (f == "v" ? 3 : 1), 0.0)});
    for (std::size_t r = 0; r + gstride <= gall.size(); r += gstride) {
      const std::size_t n = static_cast<std::size_t>(gall[r]);
      int off = 1;
      for (auto &fl : gb.fields) {
        for (int c = 0; c < fl.ncomp; ++c) fl.data[n * fl.ncomp + c] = gall[r + off + c];
        off += fl.ncomp;
      }
    }
  }
  try {
    if (!series_) series_.reset(new Hdf5Series(opt.out_prefix));
    series_->write_step(clock.step, clock.time, pb, want_grid ? &gb : nullptr);
  } catch (const std::exception &e) {
    throw LocalError(std::string("Fix mpm/fluid: keyword 'output': ") + e.what());
  }
}

}  // namespace mpm
