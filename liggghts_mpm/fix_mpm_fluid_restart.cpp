/* fix mpm/fluid's restart data (fix_mpm_fluid.h): the points' state rows and the fix's global state. */

#include "fix_mpm_fluid.h"

#include <climits>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "atom.h"
#include "comm.h"
#include "error.h"

#include "mpm/error.h"
#include "fix_mpm_fluid_guarded.h"

using namespace LAMMPS_NS;
using mpm::NCOL;

int FixMpmFluid::pack_restart(int i, double *buf) {
  buf[0] = NCOL + 1;
  std::copy(pdata[i], pdata[i] + NCOL, buf + 1);
  return NCOL + 1;
}

void FixMpmFluid::unpack_restart(int nlocal, int nth) {
  double **extra = atom->extra;
  int m = 0;
  for (int i = 0; i < nth; ++i) m += static_cast<int>(extra[nlocal][m]);
  std::copy(&extra[nlocal][m + 1], &extra[nlocal][m + 1] + NCOL, pdata[nlocal]);
}

int FixMpmFluid::size_restart(int) { return NCOL + 1; }
int FixMpmFluid::maxsize_restart() { return NCOL + 1; }

/* The fix's global restart data. Format 4: R_VERSION = -4, the fields of format 3, then the inflow
   and outflow faces' state (R_DEPTH0..5: per face the depth its inflow owes; R_MIN, R_MOUT: the
   mass created and removed), then the state of the last pressure solve. Format 3 (R_VERSION = -3)
   lacks the flow's fields: read with none owed and nothing created or removed. Format 3: the fields of format 2, the driving
   gradient of superficial_velocity (R_DRIVE) and the state of every auto (R_NEXT..R_TAU: the host
   step of the next fluid step, the N of the last one, the volume correction's countdown, the
   grains' shortest drag response time), then the state of the last pressure solve
   (ProjectionState::pack: a 0 when there is none). Format 2 (R_VERSION = -2) lacks R_DRIVE: read
   with a gradient of 0, which a file written before the keyword existed had, and every auto
   starting with a fluid step. Format 1 (written
   before the pressure projection's state was kept) began with R_FILLED, 0 or 1, and is read as
   before: a `pressure projection` run resumed from one starts its first solve from p = 0 without
   the d(theta)/dt source (a warning says so). */
namespace {
enum { R_FILLED, R_PMASS, R_SP0, R_SP1, R_SP2, R_CLAMPED, R_GATE, R_NSUB, R_THETA, R_TIME, R_TYPE, R_DRIVE,
       R_NEXT, R_LASTN, R_VCDUE, R_TAU, R_DEPTH0, R_MIN = R_DEPTH0 + 6, R_MOUT, R_COUNT };
constexpr double kRestartFormat = 4.0;
constexpr int kCountFormat2 = R_DRIVE;  // the fields of formats 1 and 2
constexpr int kCountFormat3 = R_DEPTH0;  // the fields of format 3
}

void FixMpmFluid::write_restart(FILE *fp) {
  const mpm::SolverState &st = solver->state;
  std::vector<double> list(1 + R_COUNT);
  double *v = list.data() + 1;
  list[0] = -kRestartFormat;
  v[R_FILLED] = filled ? 1.0 : 0.0;
  v[R_PMASS] = st.point_mass_ref;
  for (int d = 0; d < 3; ++d) v[R_SP0 + d] = st.spacing[d];
  v[R_CLAMPED] = st.n_clamped;
  v[R_GATE] = solver->opt.gate.active ? 1.0 : 0.0;
  v[R_NSUB] = st.nsub;
  v[R_THETA] = st.theta_initialized ? 1.0 : 0.0;
  v[R_TIME] = sim_time();
  v[R_TYPE] = point_type;
  v[R_DRIVE] = st.drive_gradient;
  v[R_NEXT] = static_cast<double>(st.next_fluid_step);
  v[R_LASTN] = st.last_every;
  v[R_VCDUE] = st.vc_due;
  v[R_TAU] = st.grain_tau;  // HUGE_VAL (finite) when no grain moved
  for (int f = 0; f < 6; ++f) v[R_DEPTH0 + f] = st.inflow_depth[f];
  v[R_MIN] = st.mass_in;
  v[R_MOUT] = st.mass_out;
  mpm::ProjectionState ps;
  guarded([&] { ps = solver->projection_state(); });  // collective
  ps.pack(list);
  if (list.size() * sizeof(double) > static_cast<std::size_t>(INT_MAX))
    error->all(FLERR, "Fix mpm/fluid: the pressure-projection state of this grid exceeds the 2 GB of a LIGGGHTS "
                      "restart record; write no restart files (or use a coarser 'cell')");
  if (comm->me == 0) {
    int size = static_cast<int>(list.size() * sizeof(double));
    fwrite(&size, sizeof(int), 1, fp);
    fwrite(list.data(), sizeof(double), list.size(), fp);
  }
}

void FixMpmFluid::restart(char *buf) {
  const double *list = reinterpret_cast<const double *>(buf);
  const bool format1 = list[0] >= 0.0;  // R_FILLED first
  const bool format2 = list[0] == -2.0;
  const bool format3 = list[0] == -3.0;
  if (!format1 && !format2 && !format3 && list[0] != -kRestartFormat) {
    std::ostringstream os;
    os << "Fix mpm/fluid: the restart file's fix data has format " << -list[0] << "; this build reads formats 1, 2 and "
       << kRestartFormat << " (write the restart file again with the build that will read it)";
    error->all(FLERR, os.str().c_str());
  }
  const double *v = format1 ? list : list + 1;
  mpm::SolverState &st = solver->state;
  filled = v[R_FILLED] != 0.0;
  st.point_mass_ref = v[R_PMASS];
  for (int d = 0; d < 3; ++d) st.spacing[d] = v[R_SP0 + d];
  st.n_clamped = v[R_CLAMPED];
  // a gate removed before the restart stays removed
  if (v[R_GATE] == 0.0) solver->opt.gate.active = false;
  st.nsub = static_cast<int>(v[R_NSUB]);
  st.theta_initialized = v[R_THETA] != 0.0;
  // LIGGGHTS' time starts again at 0; the fix's time goes on from the saved one. The offset is
  // taken at the next init(): here LIGGGHTS' timestep may not be the run's yet (a resumed run
  // reported times 2.5e-6 s early, 250 steps of LIGGGHTS' default step)
  restart_time = v[R_TIME];
  restart_time_pending = true;
  point_type = static_cast<int>(v[R_TYPE]);
  // superficial_velocity: the gradient of the last fluid step goes on (0 in files of formats 1 and 2)
  st.drive_gradient = format1 || format2 ? 0.0 : v[R_DRIVE];
  // every auto: the schedule goes on (files of formats 1 and 2: a fluid step at the next step)
  const bool schedule = !format1 && !format2;
  st.next_fluid_step = schedule ? static_cast<long>(v[R_NEXT]) : -1;
  st.last_every = schedule ? static_cast<int>(v[R_LASTN]) : 1;
  st.vc_due = schedule ? v[R_VCDUE] : 0.0;
  st.grain_tau = schedule ? v[R_TAU] : HUGE_VAL;
  // inflow and outflow faces: the depth owed and the mass created and removed go on (none before format 4)
  const bool flow = schedule && !format3;
  for (int f = 0; f < 6; ++f) st.inflow_depth[f] = flow ? v[R_DEPTH0 + f] : 0.0;
  st.mass_in = flow ? v[R_MIN] : 0.0;
  st.mass_out = flow ? v[R_MOUT] : 0.0;
  // the last pressure solve (warm start, the grains' gradient, theta for d(theta)/dt)
  st.projection = mpm::ProjectionState();
  if (format1) {
    if (solver->opt.projection && comm->me == 0)
      error->warning(FLERR, "Fix mpm/fluid: the restart file (format 1) holds no pressure-projection state: the first "
                            "pressure solve starts from p = 0 without the d(theta)/dt source, so the resumed run "
                            "differs from an uninterrupted one to the solver tolerance");
    return;
  }
  mpm::ProjectionState ps;
  guarded([&] { ps.unpack(v + (format2 ? kCountFormat2 : format3 ? kCountFormat3 : R_COUNT)); });
  if (!ps.valid || !solver->opt.projection) return;
  const mpm::GridSpec &gs = solver->opt.grid;
  bool fits = true;
  for (int d = 0; d < 3; ++d) fits = fits && ps.box.lo[d] == gs.node_lo(d) && ps.box.hi[d] == gs.node_hi(d);
  if (!fits) {
    if (comm->me == 0) {
      std::ostringstream os;
      os << "Fix mpm/fluid: the restart file's pressure state is for grid nodes " << ps.box.lo[0] << ".." << ps.box.hi[0]
         << " x " << ps.box.lo[1] << ".." << ps.box.hi[1] << " x " << ps.box.lo[2] << ".." << ps.box.hi[2]
         << ", this fix's grid has " << gs.node_lo(0) << ".." << gs.node_hi(0) << " x " << gs.node_lo(1) << ".."
         << gs.node_hi(1) << " x " << gs.node_lo(2) << ".." << gs.node_hi(2)
         << " (keyword 'cell' or 'grid' changed): the first pressure solve starts from p = 0";
      error->warning(FLERR, os.str().c_str());
    }
    return;
  }
  st.projection = std::move(ps);
}

