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
  const bool coupled = opt.coupled, eos_scale = !opt.projection && !range_warned_, every_auto = opt.every_auto;
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
    p_max_ = glob[6];
    p_scale_ = eos.rho0 * (std::sqrt(glob[7]) * std::max(extent, 0.0) + glob[0] * glob[0]);
  }
  // Sound speed: largest over the density range (Tait stiffens under compression, the linear
  // law under tension).
  // Projection: incompressible, no sound speed; the advective and viscous limits remain.
  c_max_ = opt.projection ? 0.0 : std::sqrt(std::max(eos.sound_speed_sq(glob[1]), eos.sound_speed_sq(-glob[2])));
  vmax_ = glob[0];
  rho_range_[0] = -glob[2];
  rho_range_[1] = glob[1];
  const double c = c_max_, dx = opt.grid.dx;
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
  auto_.accel = std::sqrt(glob[7]);
  auto_.grain_speed = std::sqrt(glob[14]);
  auto_.wall_speed = std::sqrt(glob[15]);
  auto_.grain_tau = -glob[16];  // of the last fluid step (HUGE_VAL before the first)
}

// Grains an integrator moves: the pore-pressure waves (fluid_laws.h). The coupled wave limits the
// fluid step when the fluid is not sub-cycled; with sub-cycling the grains' own wave limits the
// grains' step. Largest rho_f (1 - theta) / theta over the points against the lightest moving
// grain. glob: stable_dt's reduced maxima (|v|max, ..., ratio, -theta min, -grain density min).
void FluidSolver::coupled_limits(const double *glob) {
  const double c = c_max_, dx = opt.grid.dx;
  couple_theta_min_ = glob[4] < 0.0 ? -glob[4] : 1.0;
  couple_rho_grain_ = glob[5] > -HUGE_VAL ? -glob[5] : 0.0;
  c_couple_ = c_grain_ = 0.0;
  dt_couple_ = dt_grain_ = HUGE_VAL;
  if (couple_rho_grain_ > 0.0) {
    const double r = glob[3] / couple_rho_grain_;
    c_couple_ = coupled_wave_speed(c, r);
    c_grain_ = grain_wave_speed(c, r);
    dt_couple_ = acoustic_dt_limit(opt.cfl, dx, c_couple_, glob[0]);
    dt_grain_ = c_grain_ > 0.0 ? acoustic_dt_limit(opt.cfl, dx, c_grain_, glob[0]) : HUGE_VAL;
  }
}

// Once per run, under the equation of state (both reduced in stable_dt): the points' density
// deviates from rho0 by more than kDensityDeviation, or the largest point pressure exceeds
// kPressureFactor times the scene's scale rho0 (|a| H + |v|max^2) (hydrostatic plus dynamic): the
// weakly compressible fluid is out of its range (a soft bulk modulus, a fast impact, pressure noise
// in a dense bed), and its pressures and densities are not those of water.
std::string FluidSolver::range_warning() {
  constexpr double kDensityDeviation = 0.03, kPressureFactor = 5.0;
  if (opt.projection || range_warned_) return "";
  const double r0 = opt.eos.rho0, lo = rho_range_[0] / r0, hi = rho_range_[1] / r0;
  const bool density = lo < 1.0 - kDensityDeviation || hi > 1.0 + kDensityDeviation;
  const bool pressure = p_max_ > kPressureFactor * p_scale_ && p_scale_ > 0.0;
  if (!density && !pressure) return "";
  range_warned_ = true;
  std::ostringstream os;
  os.precision(4);
  os << "WARNING: fix mpm/fluid (pressure eos): at step " << clock.step;
  if (density)
    os << " the points' density left rho0 by more than " << 100 * kDensityDeviation << " % (rho/rho0 from " << lo << " to "
       << hi << ")" << (pressure ? " and" : "");
  if (pressure)
    os << " the largest point pressure " << p_max_ << " exceeds " << kPressureFactor
       << " times the scene's scale rho0 (|a| H + |v|max^2) = " << p_scale_;
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
  auto_.limit = HUGE_VAL;
  auto_.which = "none applies";
  auto take = [&](double lim, const char *which) {
    if (lim < auto_.limit) {
      auto_.limit = lim;
      auto_.which = which;
    }
  };
  if (opt.subcycle) {
    take(dt_grain_, "the grains' pore-pressure wave (the fluid sub-cycled)");
  } else {
    take(dt_stable_, "the fluid's stable step");
    take(dt_couple_, "the coupled pore-pressure wave");
    if (auto_.accel > 0.0) take(cfl * std::sqrt(dx / auto_.accel), "the free-surface limit cfl sqrt(dx/|a|max)");
  }
  if (auto_.grain_speed > 0.0) take(cfl * dx / auto_.grain_speed, "the grains' advective limit cfl dx/|v_grain|max");
  take(kTauShare * auto_.grain_tau, "the grains' drag response 0.1 min(m/K)");
  if (auto_.wall_speed > 0.0) take(cfl * dx / auto_.wall_speed, "the mesh walls' advective limit cfl dx/|w|max");
  const double nmax = std::floor(auto_.limit / clock.dt);  // inf or NaN: none of the limits applies
  opt.fluid_every = nmax >= kMaxEvery || std::isnan(nmax) ? kMaxEvery : nmax < 1.0 ? 1 : static_cast<int>(nmax);
}

std::string FluidSolver::every_auto_limit() const {
  std::ostringstream os;
  os.precision(6);
  os << "limit: " << auto_.which;
  if (std::isfinite(auto_.limit)) os << " = " << auto_.limit;
  return os.str();
}

std::string FluidSolver::check_timestep(bool at_setup) {
  if (at_setup) range_warned_ = false;
  dt_stable_ = stable_dt();
  if (opt.every_auto && !std::isnan(dt_stable_)) choose_every();
  const int every = opt.fluid_every;
  const double dt = every * clock.dt, cfl = opt.cfl, dx = opt.grid.dx;
  // (projection at rest without viscosity: no limit at all, dt_stable_ = inf)
  if (std::isnan(dt_stable_) || (!opt.projection && std::isinf(dt_stable_)) || dt_stable_ <= 0.0 || std::isnan(dt_couple_) || std::isnan(dt_grain_))
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
       << ", " << csym << " = " << cformula << " = " << cval << ", fluid sound speed c_f = " << c_max_
       << ", lowest fluid fraction theta = " << couple_theta_min_ << ", lightest moving grain rho_p = "
       << couple_rho_grain_ << "); " << before << "reduce the timestep to " << limit / every << after
       << " (docs/theory/coupled_stability.md)" << (at_setup ? "" : " (limit reached during the run)");
    throw Error(os.str());
  };
  // the grains' wave: sub-cycling the fluid does not help, the grains move once per step
  if (opt.subcycle && dt > dt_grain_)
    coupled_error(dt_grain_, "grains coupled with the fluid", "pore-pressure wave of the grains with the fluid sub-cycled",
                  "c_g", "c_f*sqrt(rho_f*(1-theta)/(theta*rho_p))", c_grain_,
                  "the grains move once per timestep, so 'subcycle yes' cannot help: ", "");
  // without sub-cycling, fluid and grains together: the coupled wave
  if (!opt.subcycle && dt > dt_couple_)
    coupled_error(dt_couple_, "fluid coupled with the grains", "pore-pressure wave of fluid and grains", "c",
                  "c_f*sqrt(1 + rho_f*(1-theta)/(theta*rho_p))", c_couple_, "", " or use keyword 'subcycle yes'");
  // the fluid (sub-)step: its own limit and, so that a step that is not sub-cycled also
  // satisfies it, the coupled one
  const double dt_sub = std::min(dt_stable_, dt_couple_);
  std::string log = range_warning();
  if (opt.projection && (dt > dt_sub ? !opt.subcycle : at_setup)) return projection_limit(dt, dt_sub, what, at_setup);
  if (dt <= dt_sub) {
    state.nsub = 1;
    return log;
  }
  if (!opt.subcycle) {
    // name the limit that applies and the keyword that sets it
    const double dt_visc = viscous_dt_limit(dx, opt.eos.rho0, opt.viscosity, opt.dimension);
    std::ostringstream os;
    os.precision(6);
    os << "Fix mpm/fluid: " << what << dt << " exceeds the largest stable time step " << dt_stable_;
    if (dt_visc <= dt_stable_)
      os << " (viscous limit dx^2 rho/(2 dim eta) with dx = " << dx << ", rho = " << opt.eos.rho0
         << ", keyword 'viscosity' eta = " << opt.viscosity << ")";
    else
      os << " (acoustic limit cfl*dx/(c+|v|max) with cfl = " << cfl << ", dx = " << dx << ", c = " << c_max_
         << " from keyword 'bulk' " << opt.eos.K << " and 'density' " << opt.eos.rho0 << ")";
    os << "; reduce the timestep to " << dt_stable_ / every
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
  const double dt_adv = acoustic_dt_limit(cfl, dx, 0.0, vmax_);
  const double dt_visc = viscous_dt_limit(dx, opt.rho0, opt.viscosity, opt.dimension);
  std::ostringstream os;
  os.precision(4);
  os << "advective limit cfl*dx/|v|max = " << dt_adv << " (cfl = " << cfl << ", dx = " << dx << ", |v|max = " << vmax_
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
