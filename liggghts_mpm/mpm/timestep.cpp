// The solver's stable time step: acoustic (CFL) and viscous limits of the fluid, and the
// pore-pressure waves of fluid and grains with couple (docs/theory/coupled_stability.md).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "mpm/error.h"
#include "mpm/solver.h"

namespace mpm {

// Largest stable fluid step of the current state (collective); sets the coupled limits too.
double FluidSolver::stable_dt() {
  const Eos &eos = opt.eos;
  // max |v|, max density, -min density; with couple: max of rho (1 - theta) / theta over the
  // points, -min theta, -min density of the grains an integrator moves.
  // The loop keeps max |v|^2 and takes one square root after it (sqrt is correctly rounded and
  // monotone: the root of the largest square is the largest root, bit for bit), and holds the
  // maxima and the points' arrays in locals (registers, not reloaded per point).
  double v2max = 0.0, rho_max = eos.rho0, mrho_max = -eos.rho0, ratio_max = 0.0, mth_max = -1.0,
         mgrain_max = -HUGE_VAL;
  // pressure eos until range_warning has warned in this run: the largest point pressure and, for
  // the scene's pressure scale, the largest |f/m| squared of the points' external force (gravity)
  // and the points' extent
  double p_max = -HUGE_VAL, a2max = 0.0, ext[6] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  double vg2max = 0.0;  // every auto: the coupled grains' largest |v|^2
  const int n = pts.nlocal, *mask = pts.mask, point_bit = pts.point_bit;
  double *const *vel = pts.v, *const *state = pts.state;
  const bool coupled = opt.coupled, eos_scale = !pressure_->incompressible() && !lim_.range_warned, every_auto = opt.every_auto;
  for (int i = 0; i < n; ++i) {
    if (mask[i] & point_bit) {
      const double *v = vel[i], *s = state[i];
      v2max = std::max(v2max, v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      const double rho = s[C_RHO];
      rho_max = std::max(rho_max, rho);
      mrho_max = std::max(mrho_max, -rho);
      if (eos_scale || every_auto) {  // the external acceleration: eos's pressure scale, every auto's surface limit
        const double *f = pts.f[i], m = pts.rmass[i];
        a2max = std::max(a2max, (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) / (m * m));
      }
      if (eos_scale) {
        p_max = std::max(p_max, s[C_P]);
        const double *x = pts.x[i];
        for (int d = 0; d < 3; ++d) {
          ext[2 * d] = std::max(ext[2 * d], x[d]);
          ext[2 * d + 1] = std::max(ext[2 * d + 1], -x[d]);
        }
      }
      if (coupled) {
        const double th = s[C_THETA];
        if (th > 0.0 && th < 1.0) {
          ratio_max = std::max(ratio_max, rho * (1.0 - th) / th);
          mth_max = std::max(mth_max, -th);
        }
      }
    } else if (is_grain(i) && (mask[i] & pts.integrated_bits) && pts.radius[i] > 0.0) {
      const double r = pts.radius[i];
      mgrain_max = std::max(mgrain_max, -pts.rmass[i] / (4.0 / 3.0 * M_PI * r * r * r));
      if (every_auto) {
        const double *v = vel[i];
        vg2max = std::max(vg2max, v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      }
    }
  }
  double loc[17] = {std::sqrt(v2max), rho_max, mrho_max, ratio_max, mth_max, mgrain_max, p_max, a2max,
                    ext[0], ext[1], ext[2], ext[3], ext[4], ext[5], vg2max, every_auto ? wall_speed2() : 0.0,
                    -this->state.grain_tau};
  double glob[17];
  MPI_Allreduce(loc, glob, every_auto ? 17 : eos_scale ? 14 : 6, MPI_DOUBLE, MPI_MAX, comm_);
  // an inflow moves the fluid at its U from the first step on: the advective limit from the start
  for (int f = 0; f < 6; ++f) glob[0] = std::max(glob[0], opt.face[f].kind == BcKind::Inflow ? opt.face[f].inflow : 0.0);
  if (every_auto) auto_limits(glob);
  if (eos_scale) {
    // rho0 (|a|max H + |v|max^2), H the points' largest extent: hydrostatic plus dynamic pressure
    double extent = 0.0;
    for (int d = 0; d < 3; ++d) extent = std::max(extent, glob[8 + 2 * d] + glob[9 + 2 * d]);
    lim_.p_max = glob[6];
    lim_.p_scale = eos.rho0 * (std::sqrt(glob[7]) * std::max(extent, 0.0) + glob[0] * glob[0]);
  }
  // Sound speed: largest over the density range (Tait stiffens under compression, the linear
  // law under tension). Projection: incompressible, no sound speed; the advective and viscous
  // limits remain.
  lim_.c_max = pressure_->sound_speed(eos, -glob[2], glob[1]);
  lim_.vmax = glob[0];
  lim_.rho_range[0] = -glob[2];
  lim_.rho_range[1] = glob[1];
  const double c = lim_.c_max, dx = opt.grid.dx;
  const double dt_ac = acoustic_dt_limit(opt.cfl, dx, c, glob[0]);
  const double dt_visc = viscous_dt_limit(dx, eos.rho0, opt.viscosity, opt.dimension);
  coupled_limits(glob);
  return std::min(dt_ac, dt_visc);
}

// every auto: the mesh walls' largest node speed squared (the triangles near this rank)
double FluidSolver::wall_speed2() const {
  double w2max = 0.0;
  if (bc.walls())
    for (const WallGeometry::Tri &t : bc.walls()->triangles())
      for (int q = 0; q < 3; ++q) w2max = std::max(w2max, t.w[q][0] * t.w[q][0] + t.w[q][1] * t.w[q][1] + t.w[q][2] * t.w[q][2]);
  return w2max;
}

// every auto: the reduced maxima of stable_dt (|a|^2 at 7, grains' |v|^2 at 14, walls' at 15, minus
// the grains' shortest response time at 16)
void FluidSolver::auto_limits(const double *glob) {
  lim_.every.accel = std::sqrt(glob[7]);
  lim_.every.grain_speed = std::sqrt(glob[14]);
  lim_.every.wall_speed = std::sqrt(glob[15]);
  lim_.every.grain_tau = -glob[16];  // of the last fluid step (HUGE_VAL before the first)
}

// Grains an integrator moves: the pore-pressure waves (fluid_laws.h). The coupled wave limits the
// fluid step when the fluid is not sub-cycled; with sub-cycling the grains' own wave limits the
// grains' step. Largest rho_f (1 - theta) / theta over the points against the lightest moving
// grain. glob: stable_dt's reduced maxima (|v|max, ..., ratio, -theta min, -grain density min).
void FluidSolver::coupled_limits(const double *glob) {
  const double c = lim_.c_max, dx = opt.grid.dx;
  lim_.couple_theta_min = glob[4] < 0.0 ? -glob[4] : 1.0;
  lim_.couple_rho_grain = glob[5] > -HUGE_VAL ? -glob[5] : 0.0;
  lim_.c_couple = lim_.c_grain = 0.0;
  lim_.dt_couple = lim_.dt_grain = HUGE_VAL;
  if (lim_.couple_rho_grain > 0.0) {
    const double r = glob[3] / lim_.couple_rho_grain;
    lim_.c_couple = coupled_wave_speed(c, r);
    lim_.c_grain = grain_wave_speed(c, r);
    lim_.dt_couple = acoustic_dt_limit(opt.cfl, dx, lim_.c_couple, glob[0]);
    lim_.dt_grain = lim_.c_grain > 0.0 ? acoustic_dt_limit(opt.cfl, dx, lim_.c_grain, glob[0]) : HUGE_VAL;
  }
}

// Once per run, under the equation of state (both reduced in stable_dt): the points' density
// deviates from rho0 by more than kDensityDeviation, or the largest point pressure exceeds
// kPressureFactor times the scene's scale rho0 (|a| H + |v|max^2) (hydrostatic plus dynamic): the
// weakly compressible fluid is out of its range (a soft bulk modulus, a fast impact, pressure noise
// in a dense bed), and its pressures and densities are not those of water.
std::string FluidSolver::range_warning() {
  // kRoundOff: a pressure below kRoundOff K is the round-off of the equation of state (a density
  // a few ulps off rho0), not a pressure; a fluid at rest without gravity has a scale of 0 and
  // such pressures (measured 2e-11 Pa with K = 1e5 at a scale of 4e-31 Pa)
  constexpr double kDensityDeviation = 0.03, kPressureFactor = 5.0, kRoundOff = 1e-12;
  if (pressure_->incompressible() || lim_.range_warned) return "";
  const double r0 = opt.eos.rho0, lo = lim_.rho_range[0] / r0, hi = lim_.rho_range[1] / r0;
  const bool density = lo < 1.0 - kDensityDeviation || hi > 1.0 + kDensityDeviation;
  const bool pressure = lim_.p_max > kPressureFactor * lim_.p_scale && lim_.p_scale > 0.0 &&
                        lim_.p_max > kRoundOff * opt.eos.K;
  if (!density && !pressure) return "";
  lim_.range_warned = true;
  std::ostringstream os;
  os.precision(4);
  os << "WARNING: fix mpm/fluid (pressure eos): at step " << clock.step;
  if (density)
    os << " the points' density left rho0 by more than " << 100 * kDensityDeviation << " % (rho/rho0 from " << lo << " to "
       << hi << ")" << (pressure ? " and" : "");
  if (pressure)
    os << " the largest point pressure " << lim_.p_max << " exceeds " << kPressureFactor
       << " times the scene's scale rho0 (|a| H + |v|max^2) = " << lim_.p_scale;
  os << ": the weakly compressible fluid is outside its range. Remedies: a stiffer 'bulk' (" << opt.eos.K
     << ") with a smaller timestep or 'subcycle yes', or the incompressible default 'pressure projection' "
     << "(warned once per run)\n";
  return os.str();
}

/* every auto: N for the fluid step about to be taken, the largest with N dt within every limit of
   the state now. Without sub-cycling: the fluid's own (advective, acoustic, viscous: stable_dt),
   the coupled wave's, and the free-surface limit cfl sqrt(dx / |a|max) of the points' external
   acceleration (a surface wave one cell long has omega^2 = g pi / dx; a point starting from rest
   falls cfl^2 dx / 2 in one step). With 'subcycle yes' the fluid's sub-steps keep those, and the
   grains' pore-pressure wave limits the step instead. Always: the grains' and the mesh walls'
   advective limits cfl dx / |v|max (the fluid sees grains and walls only at its steps, so neither
   may cross more than cfl cells in one), and cfl times the shortest drag response time m / K of a
   moving grain at the last fluid step (the drag exchange is implicit and stable at any step, but a
   grain's approach to its slip is resolved only on steps below m / K: C1's settling curve 7 % off
   at 6 m / K). At least 1 (check_timestep then names a limit that one step exceeds), at most
   kMaxEvery. */
void FluidSolver::choose_every() {
  constexpr double kTauShare = 0.1;  // of the shortest drag response time
  const double cfl = opt.cfl, dx = opt.grid.dx;
  lim_.every.limit = HUGE_VAL;
  lim_.every.which = "none applies";
  auto take = [&](double lim, const char *which) {
    if (lim < lim_.every.limit) {
      lim_.every.limit = lim;
      lim_.every.which = which;
    }
  };
  if (opt.subcycle) {
    take(lim_.dt_grain, "the grains' pore-pressure wave (the fluid sub-cycled)");
  } else {
    take(lim_.dt_stable, "the fluid's stable step");
    take(lim_.dt_couple, "the coupled pore-pressure wave");
    if (lim_.every.accel > 0.0) take(cfl * std::sqrt(dx / lim_.every.accel), "the free-surface limit cfl sqrt(dx/|a|max)");
  }
  if (lim_.every.grain_speed > 0.0) take(cfl * dx / lim_.every.grain_speed, "the grains' advective limit cfl dx/|v_grain|max");
  take(kTauShare * lim_.every.grain_tau, "the grains' drag response 0.1 min(m/K)");
  if (lim_.every.wall_speed > 0.0) take(cfl * dx / lim_.every.wall_speed, "the mesh walls' advective limit cfl dx/|w|max");
  const double nmax = std::floor(lim_.every.limit / clock.dt);  // inf or NaN: none of the limits applies
  opt.fluid_every = nmax >= kMaxEvery || std::isnan(nmax) ? kMaxEvery : nmax < 1.0 ? 1 : static_cast<int>(nmax);
}

std::string FluidSolver::every_auto_limit() const {
  std::ostringstream os;
  os.precision(6);
  os << "limit: " << lim_.every.which;
  if (std::isfinite(lim_.every.limit)) os << " = " << lim_.every.limit;
  return os.str();
}

std::string FluidSolver::check_timestep(bool at_setup) {
  if (at_setup) lim_.range_warned = false;
  lim_.dt_stable = stable_dt();
  if (opt.every_auto && !std::isnan(lim_.dt_stable)) choose_every();
  const int every = opt.fluid_every;
  const double dt = every * clock.dt, cfl = opt.cfl, dx = opt.grid.dx;
  // (projection at rest without viscosity: no limit at all, lim_.dt_stable = inf)
  if (std::isnan(lim_.dt_stable) || (!pressure_->incompressible() && std::isinf(lim_.dt_stable)) || lim_.dt_stable <= 0.0 || std::isnan(lim_.dt_couple) || std::isnan(lim_.dt_grain))
    throw Error("Fix mpm/fluid: the fluid state is not finite (NaN velocity or density); "
                "the run was unstable before this check");
  const char *what = every > 1 ? "fluid step (every x timestep) " : "timestep ";
  // a coupled limit exceeded: the error names the wave, its speed and the step to use
  auto coupled_error = [&](double limit, const char *whose, const char *wave, const char *csym,
                           const char *cformula, double cval, const char *before, const char *after) {
    std::ostringstream os;
    os.precision(6);
    os << "Fix mpm/fluid: " << what << dt << " exceeds the largest stable time step " << limit << " of the "
       << whose << " (" << wave << ": cfl*dx/(" << csym << "+|v|max) with cfl = " << cfl << ", dx = " << dx
       << ", " << csym << " = " << cformula << " = " << cval << ", fluid sound speed c_f = " << lim_.c_max
       << ", lowest fluid fraction theta = " << lim_.couple_theta_min << ", lightest moving grain rho_p = "
       << lim_.couple_rho_grain << "); " << before << "reduce the timestep to " << limit / every << after
       << " (docs/theory/coupled_stability.md)" << (at_setup ? "" : " (limit reached during the run)");
    throw Error(os.str());
  };
  // the grains' wave: sub-cycling the fluid does not help, the grains move once per step
  if (opt.subcycle && dt > lim_.dt_grain)
    coupled_error(lim_.dt_grain, "grains coupled with the fluid", "pore-pressure wave of the grains with the fluid sub-cycled",
                  "c_g", "c_f*sqrt(rho_f*(1-theta)/(theta*rho_p))", lim_.c_grain,
                  "the grains move once per timestep, so 'subcycle yes' cannot help: ", "");
  // without sub-cycling, fluid and grains together: the coupled wave
  if (!opt.subcycle && dt > lim_.dt_couple)
    coupled_error(lim_.dt_couple, "fluid coupled with the grains", "pore-pressure wave of fluid and grains", "c",
                  "c_f*sqrt(1 + rho_f*(1-theta)/(theta*rho_p))", lim_.c_couple, "", " or use keyword 'subcycle yes'");
  // the fluid (sub-)step: its own limit and, so that a step that is not sub-cycled also
  // satisfies it, the coupled one
  const double dt_sub = std::min(lim_.dt_stable, lim_.dt_couple);
  // not at a run's setup: the points' forces then lack those of the fixes set up after this one
  // (fix gravity after fix mpm/fluid in the input), and the scale would miss the hydrostatic
  // pressure (water at rest warned at every run's start); the run's first fluid step checks
  std::string log = at_setup ? std::string() : range_warning();
  if (pressure_->incompressible() && (dt > dt_sub ? !opt.subcycle : at_setup)) return projection_limit(dt, dt_sub, what, at_setup);
  if (dt <= dt_sub) {
    state.nsub = 1;
    return log;
  }
  if (!opt.subcycle) {
    // name the limit that applies and the keyword that sets it
    const double dt_visc = viscous_dt_limit(dx, opt.eos.rho0, opt.viscosity, opt.dimension);
    std::ostringstream os;
    os.precision(6);
    os << "Fix mpm/fluid: " << what << dt << " exceeds the largest stable time step " << lim_.dt_stable;
    if (dt_visc <= lim_.dt_stable)
      os << " (viscous limit dx^2 rho/(2 dim eta) with dx = " << dx << ", rho = " << opt.eos.rho0
         << ", keyword 'viscosity' eta = " << opt.viscosity << ")";
    else
      os << " (acoustic limit cfl*dx/(c+|v|max) with cfl = " << cfl << ", dx = " << dx << ", c = " << lim_.c_max
         << " from keyword 'bulk' " << opt.eos.K << " and 'density' " << opt.eos.rho0 << ")";
    os << "; reduce the timestep to " << lim_.dt_stable / every
       << " or use keyword 'subcycle yes'" << (at_setup ? "" : " (limit reached during the run)");
    throw Error(os.str());
  }
  // in floating point: the count may exceed every integer type (cfl 1e-12 needs more than 2^31)
  const double nsub_needed = std::ceil(dt / dt_sub);
  if (!(nsub_needed <= opt.max_subcycle)) {
    std::ostringstream os;
    os.precision(6);
    os << "Fix mpm/fluid: 'subcycle yes' would need " << nsub_needed << " sub-steps per timestep (more than "
       << opt.max_subcycle << "); reduce the timestep to at most " << opt.max_subcycle * dt_sub;
    throw Error(os.str());
  }
  const int nsub = static_cast<int>(nsub_needed);
  if (at_setup && nsub != state.nsub) {
    std::ostringstream os;
    os << "fix mpm/fluid: sub-cycling with " << nsub << " fluid sub-steps of " << dt / nsub
       << " per timestep (stable limit " << dt_sub << ")\n";
    log += os.str();
  }
  state.nsub = nsub;
  return log;
}

// check_timestep under 'pressure projection' (no sound speed), when the step exceeds the limit
// without sub-cycling or at set-up: the error naming the limit that applies, else its log line.
std::string FluidSolver::projection_limit(double dt, double dt_sub, const char *what, bool at_setup) {
  const int every = opt.fluid_every;
  const double cfl = opt.cfl, dx = opt.grid.dx;
  // the limit applied: advective cfl*dx/|v|max or viscous dx^2 rho/(2 dim eta)
  const double dt_adv = acoustic_dt_limit(cfl, dx, 0.0, lim_.vmax);
  const double dt_visc = viscous_dt_limit(dx, opt.rho0, opt.viscosity, opt.dimension);
  std::ostringstream os;
  os.precision(4);
  os << "advective limit cfl*dx/|v|max = " << dt_adv << " (cfl = " << cfl << ", dx = " << dx << ", |v|max = " << lim_.vmax
     << "), viscous limit dx^2 rho/(2 dim eta) = " << dt_visc << "; "
     << (dt_adv <= dt_visc ? "advective" : "viscous") << " limit applies";
  // six significant digits (std::to_string printed 0.000000 for a step below 1e-6)
  auto sig6 = [](double x) {
    std::ostringstream t;
    t.precision(6);
    t << x;
    return t.str();
  };
  if (dt > dt_sub)
    throw Error("Fix mpm/fluid: " + std::string(what) + sig6(dt) + " exceeds the largest stable time step of " +
                "'pressure projection' (" + os.str() + "); reduce the timestep to " + sig6(dt_sub / every) +
                " or use keyword 'subcycle yes'" + (at_setup ? "" : " (limit reached during the run)"));
  state.nsub = 1;
  return "fix mpm/fluid: pressure projection, no sound speed: " + os.str() + "\n";
}

}  // namespace mpm
