// Fluid-particle interaction laws of the MPM-DEM coupling (chapters 7-8):
// drag coefficients (Ergun / Wen-Yu (8-27)-(8-29), Di Felice 1994, Stokes),
// the pressure-gradient (buoyancy) force (7-15), the exact exponential
// two-body drag exchange and the isolated-sphere settling helpers used to
// verify case C1. Independent of the grid, of MPI and of LIGGGHTS so that
// they can be tested alone. Derivation and choices: docs/drag.md.
//
// Sign convention: K >= 0 is the per-particle linear drag coefficient
// [kg/s]; the drag force on the particle is F = K (u_f - v_s) and the fluid
// receives -F (mapped to the nodes with the interpolation weights).
#pragma once
#include <cmath>
#include <cstring>

namespace mpm {

enum class DragLaw { ErgunWenYu, DiFelice, Stokes };

// Consistent: force on ONE particle F = beta V_p / (1 - theta) (u_f - v_s),
//   beta the per-mixture-volume coefficient; isolated sphere (theta -> 1)
//   gets 3 pi mu d (1 + 0.15 Re^0.687) (u_f - v_s)   (default).
// Literal: the dissertation's (7-7)/(8-26) F = beta V_p (u_f - v_s);
//   vanishes as theta -> 1. For every law K_literal = (1 - theta) K_consistent.
enum class DragForm { Consistent, Literal };

constexpr double kDragThetaMin = 0.3;      // default lower clamp of theta
constexpr double kErgunWenYuSwitch = 0.8;  // Ergun for theta <= 0.8, Wen-Yu above
constexpr double kWenYuReNewton = 1000.0;  // C_D = 0.43 above this Re (8-28)
constexpr double kWenYuCdNewton = 0.43;
constexpr double kDragPi = 3.14159265358979323846;

// ---------------------------------------------------------------- names
inline const char* drag_law_name(DragLaw law) {
  switch (law) {
    case DragLaw::ErgunWenYu: return "ergun_wenyu";
    case DragLaw::DiFelice: return "difelice";
    case DragLaw::Stokes: return "stokes";
  }
  return "unknown";
}
inline bool parse_drag_law(const char* s, DragLaw& out) {
  if (!s) return false;
  if (!std::strcmp(s, "ergun_wenyu")) { out = DragLaw::ErgunWenYu; return true; }
  if (!std::strcmp(s, "difelice")) { out = DragLaw::DiFelice; return true; }
  if (!std::strcmp(s, "stokes")) { out = DragLaw::Stokes; return true; }
  return false;
}
inline const char* drag_form_name(DragForm form) {
  return form == DragForm::Consistent ? "consistent" : "literal";
}
inline bool parse_drag_form(const char* s, DragForm& out) {
  if (!s) return false;
  if (!std::strcmp(s, "consistent")) { out = DragForm::Consistent; return true; }
  if (!std::strcmp(s, "literal")) { out = DragForm::Literal; return true; }
  return false;
}

// ---------------------------------------------------------------- helpers
// theta clamped to [theta_min, 1]; NaN or below theta_min -> theta_min.
inline double clamp_fluid_fraction(double theta, double theta_min = kDragThetaMin) {
  if (!(theta >= theta_min)) return theta_min;
  return theta > 1.0 ? 1.0 : theta;
}

// Particle Reynolds number as in (8-29): Re = theta rho_f |u_f - v_s| d / mu
// (superficial slip velocity; the same convention is used for Di Felice).
inline double drag_reynolds(double rho_f, double mu, double d, double theta, double urel) {
  return theta * rho_f * std::fabs(urel) * d / mu;
}

// C_D Re of (8-28) (Schiller-Naumann below Re = 1000, 0.43 above); finite
// (= 24) at Re = 0.
inline double wen_yu_cd_re(double Re) {
  if (Re > kWenYuReNewton) return kWenYuCdNewton * Re;
  return 24.0 * (1.0 + 0.15 * std::pow(Re, 0.687));
}

// Di Felice (1994) single-sphere C_D = (0.63 + 4.8/sqrt(Re))^2 (Dallavalle).
// Written as C_D Re = (0.63 sqrt(Re) + 4.8)^2, finite (= 23.04) at Re = 0.
inline double di_felice_cd_re(double Re) {
  const double s = 0.63 * std::sqrt(Re) + 4.8;
  return s * s;
}
// Di Felice exponent chi = 3.7 - 0.65 exp(-(1.5 - log10 Re)^2 / 2); -> 3.7 as Re -> 0.
inline double di_felice_chi(double Re) {
  if (!(Re > 0.0)) return 3.7;
  const double a = 1.5 - std::log10(Re);
  return 3.7 - 0.65 * std::exp(-0.5 * a * a);
}

// ---------------------------------------------------------------- coefficient
// Per-particle linear drag coefficient K [kg/s], F_particle = K (u_f - v_s).
//  rho_f fluid density, mu dynamic viscosity, d particle diameter, Vp particle
//  volume (pi d^3/6 for a sphere; Ergun / Wen-Yu scale with Vp, Di Felice and
//  Stokes with d), theta fluid fraction (clamped to [theta_min, 1]),
//  urel = |u_f - v_s|.
// Consistent form (computed without dividing by 1 - theta):
//  Ergun   (theta <= 0.8): K = Vp mu / (d^2 theta) [150 (1-theta) + 1.75 Re]
//  Wen-Yu  (theta >  0.8): K = Vp (3/4) (mu/d^2) (C_D Re) theta^-2.7
//  DiFelice:               K = (pi mu d / 8) (C_D Re) theta^(1-chi)
//                          (= 0.5 C_D rho_f pi d^2/4 theta^(2-chi) |u-v|)
//  Stokes:                 K = 3 pi mu d (no voidage correction)
// Literal form: the above times (1 - theta).
inline double drag_coefficient(DragLaw law, DragForm form, double rho_f, double mu, double d,
                               double Vp, double theta, double urel,
                               double theta_min = kDragThetaMin) {
  const double th = clamp_fluid_fraction(theta, theta_min);
  const double Re = drag_reynolds(rho_f, mu, d, th, urel);
  double K = 0.0;
  switch (law) {
    case DragLaw::ErgunWenYu:
      if (th <= kErgunWenYuSwitch)
        K = Vp * mu / (d * d * th) * (150.0 * (1.0 - th) + 1.75 * Re);
      else
        K = Vp * 0.75 * mu / (d * d) * wen_yu_cd_re(Re) * std::pow(th, -2.7);
      break;
    case DragLaw::DiFelice:
      K = kDragPi * mu * d / 8.0 * di_felice_cd_re(Re) * std::pow(th, 1.0 - di_felice_chi(Re));
      break;
    case DragLaw::Stokes:
      K = 3.0 * kDragPi * mu * d;
      break;
  }
  return form == DragForm::Literal ? (1.0 - th) * K : K;
}

// Per-mixture-volume interphase coefficient beta [kg/(m^3 s)] of (8-27)
// (drag of all particles in a unit mixture volume per unit slip velocity):
// beta = n K_consistent with n = (1 - theta)/Vp; equals K_literal / Vp.
inline double drag_beta(DragLaw law, double rho_f, double mu, double d, double Vp, double theta,
                        double urel, double theta_min = kDragThetaMin) {
  return drag_coefficient(law, DragForm::Literal, rho_f, mu, d, Vp, theta, urel, theta_min) / Vp;
}

// Which branch of (8-27) drag_coefficient uses at this theta (after clamping).
inline bool ergun_branch(double theta, double theta_min = kDragThetaMin) {
  return clamp_fluid_fraction(theta, theta_min) <= kErgunWenYuSwitch;
}

// F = K (u_f - v_s), the drag on the particle (the fluid receives -F).
inline void drag_force(double K, const double u_f[3], const double v_s[3], double F[3]) {
  for (int a = 0; a < 3; ++a) F[a] = K * (u_f[a] - v_s[a]);
}

// Pressure-gradient force on a particle (7-15): F = -Vp grad p. With the
// hydrostatic gradient grad p = rho_f g this IS the Archimedes buoyancy
// -rho_f Vp g; no separate buoyancy term may be added on top.
inline void pressure_gradient_force(double Vp, const double gradp[3], double F[3]) {
  for (int a = 0; a < 3; ++a) F[a] = -Vp * gradp[a];
}

// ---------------------------------------------------------------- time integration
// Particle relaxation time m_p / K (infinite without drag).
inline double particle_relaxation_time(double m_p, double K) {
  return K > 0.0 ? m_p / K : HUGE_VAL;
}
// Exact relaxation factor of the particle-fluid slip over dt for a fluid
// of prescribed velocity: exp(-K dt / m_p).
inline double drag_relaxation_factor(double K, double dt, double m_p) {
  return std::exp(-K * dt / m_p);
}
// 1/m_p + 1/m_f; m_f = HUGE_VAL (infinite) means the fluid velocity is prescribed.
inline double drag_inverse_reduced_mass(double m_p, double m_f) {
  return 1.0 / m_p + (std::isinf(m_f) ? 0.0 : 1.0 / m_f);
}
// Explicit (forward Euler) drag is stable for dt < 2 / (K (1/m_p + 1/m_f))
// (amplification factor of the slip 1 - K (1/m_p + 1/m_f) dt); it is
// monotone (no sign flip of the slip) for half of that.
inline double drag_explicit_dt_limit(double K, double m_p, double m_f = HUGE_VAL) {
  if (!(K > 0.0)) return HUGE_VAL;
  return 2.0 / (K * drag_inverse_reduced_mass(m_p, m_f));
}

// phi1(x) = (1 - e^-x)/x and phi2(x) = (x - 1 + e^-x)/x^2, accurate for x -> 0.
inline double drag_phi1(double x) {
  if (x < 1e-8) return 1.0 - 0.5 * x;
  return -std::expm1(-x) / x;
}
inline double drag_phi2(double x) {
  if (x < 1e-3) return 0.5 - x / 6.0 + x * x / 24.0 - x * x * x / 120.0;
  return (x + std::expm1(-x)) / (x * x);
}

// Exact drag impulse J [kg m/s] over dt for the two-body system particle
// (mass m_p, velocity v_p) + fluid (effective mass m_f, velocity u_f)
// coupled by a frozen coefficient K: m_p dv/dt = m_p a_p + K (u - v),
// m_f du/dt = m_f a_f - K (u - v). Add J to the particle momentum and
// subtract it from the fluid momentum (together with the a_p dt, a_f dt
// kicks, if given): total momentum is conserved exactly, the slip decays as
// w(dt) = w_inf + (w0 - w_inf) exp(-lambda dt), lambda = K (1/m_p + 1/m_f),
// w_inf = (a_f - a_p)/lambda. Optional a_p, a_f: the other accelerations
// (gravity, pressure, contacts) held constant over the step; without them
// J = m_red w0 (1 - exp(-lambda dt)). Unconditionally stable.
// J = K dt [w0 phi1(lambda dt) + (a_f - a_p) dt phi2(lambda dt)].
inline void drag_exchange_impulse(const double v_p[3], const double u_f[3], double m_p, double m_f,
                                  double K, double dt, double J[3],
                                  const double a_p[3] = nullptr, const double a_f[3] = nullptr) {
  const double x = K * drag_inverse_reduced_mass(m_p, m_f) * dt;
  const double p1 = drag_phi1(x), p2 = drag_phi2(x);
  for (int a = 0; a < 3; ++a) {
    const double da = (a_f ? a_f[a] : 0.0) - (a_p ? a_p[a] : 0.0);
    J[a] = K * dt * ((u_f[a] - v_p[a]) * p1 + da * dt * p2);
  }
}

// Backward-Euler drag impulse over dt for the same two-body system:
// w' = (w0 + (a_f - a_p) dt) / (1 + lambda dt), J = K dt w'. Unconditionally
// stable and, unlike the exact exponential, it keeps the right steady slip
// w = (a_f - a_p) / (K (1/m_p + 1/m_f)) when the particle is advanced by a
// leapfrog / velocity-Verlet integrator that holds the force over the step
// (LIGGGHTS' nve/sphere): the particle then follows exactly backward Euler.
inline void drag_implicit_impulse(const double v_p[3], const double u_f[3], double m_p, double m_f,
                                  double K, double dt, double J[3],
                                  const double a_p[3] = nullptr, const double a_f[3] = nullptr) {
  const double x = K * drag_inverse_reduced_mass(m_p, m_f) * dt;
  for (int a = 0; a < 3; ++a) {
    const double da = (a_f ? a_f[a] : 0.0) - (a_p ? a_p[a] : 0.0);
    J[a] = K * dt * ((u_f[a] - v_p[a]) + da * dt) / (1.0 + x);
  }
}

// ---------------------------------------------------------------- settling (C1)
// Terminal settling velocity [m/s] of a sphere of diameter d and density
// rho_p in quiescent fluid (rho_f, mu) under gravity g > 0 and buoyancy, at
// fluid fraction theta (1 = isolated): solves (rho_p - rho_f) Vp g = K(v) v
// by bisection. Signed: > 0 sinks (along g), < 0 rises, 0 neutrally buoyant.
// HUGE_VAL (with the sign) if the law gives no drag (literal form at theta = 1).
inline double terminal_velocity(DragLaw law, DragForm form, double rho_p, double rho_f, double mu,
                                double d, double g, double theta = 1.0,
                                double theta_min = kDragThetaMin) {
  const double Vp = kDragPi * d * d * d / 6.0;
  const double F = (rho_p - rho_f) * Vp * g;
  if (F == 0.0) return 0.0;
  const double Fa = std::fabs(F);
  auto Kof = [&](double v) {
    return drag_coefficient(law, form, rho_f, mu, d, Vp, theta, v, theta_min);
  };
  const double K0 = Kof(0.0);
  if (!(K0 > 0.0)) return F > 0.0 ? HUGE_VAL : -HUGE_VAL;
  // K(v) v is increasing; bracket [lo, hi] with K(hi) hi >= Fa.
  double lo = 0.0, hi = Fa / K0;
  for (int i = 0; i < 200 && Kof(hi) * hi < Fa; ++i) { lo = hi; hi *= 2.0; }
  for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (Kof(mid) * mid < Fa ? lo : hi) = mid;
  }
  const double v = 0.5 * (lo + hi);
  return F > 0.0 ? v : -v;
}

// Stokes relaxation time of a sphere (added mass neglected, as in DEM):
// tau = m_p / (3 pi mu d) = rho_p d^2 / (18 mu).
inline double stokes_relaxation_time(double rho_p, double mu, double d) {
  return rho_p * d * d / (18.0 * mu);
}
// Analytic relaxation curve for linear (Stokes) drag:
// v(t) = v_t + (v0 - v_t) exp(-t / tau).
inline double relaxation_velocity(double t, double v0, double v_t, double tau) {
  return v_t + (v0 - v_t) * std::exp(-t / tau);
}

// Settling velocity v(t) (signed along g) of an isolated sphere released
// with v0, for any law: rho_p Vp dv/dt = (rho_p - rho_f) Vp g - K(|v|) v,
// integrated with classical RK4 in `steps` steps (reference curve for C1
// when the drag is not linear).
inline double settling_velocity(DragLaw law, DragForm form, double rho_p, double rho_f, double mu,
                                double d, double g, double t, double v0 = 0.0, double theta = 1.0,
                                int steps = 4000, double theta_min = kDragThetaMin) {
  const double Vp = kDragPi * d * d * d / 6.0;
  const double m = rho_p * Vp, F = (rho_p - rho_f) * Vp * g;
  auto acc = [&](double v) {
    return (F - drag_coefficient(law, form, rho_f, mu, d, Vp, theta, v, theta_min) * v) / m;
  };
  if (steps < 1) steps = 1;
  const double h = t / steps;
  double v = v0;
  for (int i = 0; i < steps; ++i) {
    const double k1 = acc(v), k2 = acc(v + 0.5 * h * k1), k3 = acc(v + 0.5 * h * k2),
                 k4 = acc(v + h * k3);
    v += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  return v;
}

}  // namespace mpm
