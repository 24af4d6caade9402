// The solver's outputs: the global vector f_ID[1..18] and the HDF5 + XDMF series of keyword
// output (points, and grid nodes; each rank gives its own, mpm/hdf5_series.h writes them).
#include <algorithm>
#include <cmath>

#include "mpm/cell_pressure.h"
#include "mpm/error.h"
#include "mpm/hdf5_series.h"
#include "mpm/projection.h"
#include "mpm/solver.h"

namespace mpm {

OutputState::OutputState() = default;
OutputState::~OutputState() = default;

void FluidSolver::global_vector(double *out, int walls) {
  const GridSpec &gs = opt.grid;
  double **x = pts.x, **v = pts.v;
  const double *rmass = pts.rmass;
  const double *spacing = state.spacing;
  const Projection *proj = pressure_->solve();
  double sum[4] = {0, 0, 0, state.n_clamped};  // mass, kinetic energy, points, clamped
  // |v|max, front, height, p max, wall time of the fluid, of the coupling and of the pressure solver
  // (slowest rank), largest averaged nodal pressure (f_ID[19])
  double mx[8] = {0.0, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL, io_.time_fluid, io_.time_couple, time_pressure_solver(),
                  proj ? proj->largest_average_pressure() : -HUGE_VAL};
  std::vector<long long> cell;  // the grid cell of each point and its pressure (f_ID[10])
  std::vector<double> pcell;
  for (int i = 0; i < pts.nlocal; ++i) {
    if (!is_point(i)) continue;
    cell.push_back(cell_key(gs, x[i]));
    pcell.push_back(pts.state[i][C_P]);
    const double v2 = v[i][0] * v[i][0] + v[i][1] * v[i][1] + v[i][2] * v[i][2];
    sum[0] += rmass[i];
    sum[1] += 0.5 * rmass[i] * v2;
    sum[2] += 1.0;
    mx[0] = std::max(mx[0], std::sqrt(v2));
    mx[1] = std::max(mx[1], x[i][opt.front_axis] + 0.5 * spacing[opt.front_axis]);
    if (std::fabs(x[i][opt.wall_axis] - opt.wall_pos) < gs.dx)
      mx[2] = std::max(mx[2], x[i][opt.height_axis] + 0.5 * spacing[opt.height_axis]);
  }
  // f_ID[10]: the largest cell-mean point pressure (cell_pressure.h); the largest single point's is
  // compute reduce max f_ID[3] of the input
  mx[3] = largest_cell_mean(comm_, cell, pcell);
  double fg[3] = {0, 0, 0}, gfg[3];
  if (opt.coupled)
    for (int k = 0; k < pts.nlocal; ++k)
      if (is_grain(k))
        for (int d = 0; d < 3; ++d) fg[d] += pts.state[k][C_FGRAIN + d];
  MPI_Allreduce(fg, gfg, 3, MPI_DOUBLE, MPI_SUM, comm_);
  for (int d = 0; d < 3; ++d) out[10 + d] = gfg[d];
  double gsum[4], gmx[8];
  MPI_Allreduce(sum, gsum, 4, MPI_DOUBLE, MPI_SUM, comm_);
  MPI_Allreduce(mx, gmx, 8, MPI_DOUBLE, MPI_MAX, comm_);
  out[0] = gsum[0];
  out[1] = gsum[1];
  out[2] = gmx[0];
  out[3] = std::isfinite(gmx[1]) ? gmx[1] : 0.0;
  out[4] = std::isfinite(gmx[2]) ? gmx[2] - gs.origin[opt.height_axis] : 0.0;
  out[5] = state.nsub;
  out[6] = std::min(lim_.dt_stable, lim_.dt_couple);
  out[7] = gsum[3];
  out[8] = gsum[2];
  out[9] = std::isfinite(gmx[3]) ? gmx[3] : 0.0;
  out[13] = gmx[4];
  out[14] = gmx[5];
  out[15] = proj ? proj->iterations() : 0.0;
  out[16] = proj ? proj->residual() : 0.0;
  out[17] = gmx[6];
  out[18] = std::isfinite(gmx[7]) ? gmx[7] : 0.0;
  // the mesh walls' loads and the probes (wall_loads.cpp): 0 before the first fluid step
  for (int c = 0; c < 6 * walls; ++c)
    out[kGlobalSize + c] = c < static_cast<int>(io_.wall_mean.size()) ? io_.wall_mean[c] : 0.0;
  for (std::size_t j = 0; j < opt.probes.size(); ++j)
    out[kGlobalSize + 6 * walls + j] = j < io_.probe_mean.size() ? io_.probe_mean[j] : 0.0;
  const std::size_t next = kGlobalSize + 6 * walls + opt.probes.size() + (opt.drive.active ? 1 : 0);
  if (opt.drive.active) out[next - 1] = state.drive_gradient;
  if (opt.flow_faces()) {
    // the points that left in the last fluid step and wait for their removal count as out
    double gone = 0.0, all = 0.0;
    for (int i = 0; i < pts.nlocal; ++i)
      if ((pts.mask[i] & pts.point_bit) && pts.state[i][C_FLAG] == kPointGone) gone += rmass[i];
    MPI_Allreduce(&gone, &all, 1, MPI_DOUBLE, MPI_SUM, comm_);
    out[next] = state.mass_in;
    out[next + 1] = state.mass_out + all;
  }
}

// since the solver was made (PressureModel's counters; 0 with eos)
double FluidSolver::time_pressure_solver() const { return pressure_->solver_seconds(); }
long FluidSolver::pressure_solves() const { return pressure_->solves(); }
long FluidSolver::pressure_iterations_summed() const { return pressure_->iterations_summed(); }

long FluidSolver::pressure_sealed_nodes() const {
  const Projection *proj = pressure_->solve();
  return proj ? proj->sealed_nodes() : 0;
}
long FluidSolver::pressure_sealed_sets() const {
  const Projection *proj = pressure_->solve();
  return proj ? proj->sealed_sets() : 0;
}

namespace {
int point_field_size(const std::string &f) { return f == "v" ? 3 : f == "tau" ? 6 : f == "affine" ? 9 : 1; }
}  // namespace

void FluidSolver::write_output() {
  if (io_.last_step == clock.step) return;
  io_.last_step = clock.step;
  // the ranks meet first (they would at the first collective call anyway), so that io_.time_output is
  // the output's own and not the wait for a rank still in the preceding step
  MPI_Barrier(comm_);
  const double t0 = MPI_Wtime();
  const GridSpec &gs = opt.grid;
  const std::vector<std::string> &pfields = opt.out_point_fields, &gfields = opt.out_grid_fields;

  // This rank's points and owned real grid nodes (not the padding): Hdf5Series places them.
  // Field by field, so that each name is looked up once, not once per point.
  std::vector<int> mine;
  for (int i = 0; i < pts.nlocal; ++i)
    if (is_point(i)) mine.push_back(i);
  PointBlock pb;
  pb.n = mine.size();
  pb.xyz.reserve(3 * pb.n);
  for (int i : mine) pb.xyz.insert(pb.xyz.end(), pts.x[i], pts.x[i] + 3);
  for (const auto &f : pfields) {
    pb.fields.push_back({f, point_field_size(f), {}});
    std::vector<double> &out = pb.fields.back().data;
    out.reserve(pb.n * point_field_size(f));
    auto state = [&](int c0, int nc) {
      for (int i : mine) out.insert(out.end(), pts.state[i] + c0, pts.state[i] + c0 + nc);
    };
    if (f == "v") for (int i : mine) out.insert(out.end(), pts.v[i], pts.v[i] + 3);
    else if (f == "p") state(C_P, 1);
    else if (f == "rho") state(C_RHO, 1);
    else if (f == "vol") state(C_VOL, 1);
    else if (f == "tau") state(C_TAU, 6);
    else if (f == "theta") state(C_THETA, 1);
    else if (f == "affine") state(C_AFF, 9);
    else if (f == "id") for (int i : mine) out.push_back(static_cast<double>(pts.tag[i]));
    else if (f == "type") for (int i : mine) out.push_back(static_cast<double>(pts.type[i]));
    else if (f == "mass") for (int i : mine) out.push_back(pts.rmass[i]);
  }

  GridBlock gb;
  const bool want_grid = !gfields.empty();
  if (want_grid) {
    const IndexBox in = gs.interior(grid_.owned());  // the owned nodes without padding
    for (int d = 0; d < 3; ++d) {
      gb.n[d] = gs.periodic[d] ? gs.ncell[d] : gs.ncell[d] + 1;
      gb.origin[d] = gs.origin[d];
      gb.spacing[d] = gs.dx;
      gb.lo[d] = in.lo[d];
      gb.count[d] = std::max(in.hi[d] - in.lo[d] + 1, 0);
    }
    if (gb.count[0] == 0 || gb.count[1] == 0 || gb.count[2] == 0)
      for (int d = 0; d < 3; ++d) gb.lo[d] = gb.count[d] = 0;  // owns no node
    for (const auto &f : gfields) {
      gb.fields.push_back({f, f == "v" ? 3 : 1, {}});
      std::vector<double> &out = gb.fields.back().data;
      const bool mass = f == "mass";
      grid_.for_box(in, [&](int, int, int, std::size_t n) {
        if (mass) out.push_back(g_.p2g[P2gRec::N * n + P2gRec::M]);
        else out.insert(out.end(), &g_.vel[VelRec::N * n + VelRec::V_NEW], &g_.vel[VelRec::N * n + VelRec::V_NEW] + 3);
      });
    }
  }

  try {  // collective: a failure on any rank throws the same message on every rank
    if (!io_.series) io_.series.reset(new Hdf5Series(opt.out_prefix, comm_));
    io_.series->write_step(clock.step, clock.time, pb, want_grid ? &gb : nullptr);
  } catch (const std::exception &e) {
    throw Error(std::string("Fix mpm/fluid: keyword 'output': ") + e.what());
  }
  io_.time_output += MPI_Wtime() - t0;
  ++io_.n_outputs;
}

}  // namespace mpm
