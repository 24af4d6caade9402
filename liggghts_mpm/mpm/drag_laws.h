// Fluid-particle interaction laws of the MPM-DEM coupling (chapters 7-8):
// drag coefficients (Ergun / Wen-Yu (8-27)-(8-29), Di Felice 1994, Stokes),
// the pressure-gradient (buoyancy) force (7-15) and the backward-Euler
// two-body drag exchange (the verification helpers, exact exchange and
// settling curves of case C1, live in tests/unit/test_drag_laws.cpp). Independent of the grid, of MPI and of LIGGGHTS so that
// they can be tested alone. Derivation and choices: docs/theory/drag.md.
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
inline bool parse_drag_law(const char* s, DragLaw& out) {
  if (!s) return false;
  if (!std::strcmp(s, "ergun_wenyu")) { out = DragLaw::ErgunWenYu; return true; }
  if (!std::strcmp(s, "difelice")) { out = DragLaw::DiFelice; return true; }
  if (!std::strcmp(s, "stokes")) { out = DragLaw::Stokes; return true; }
  return false;
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

// Pressure-gradient force on a particle (7-15): F = -Vp grad p. With the
// hydrostatic gradient grad p = rho_f g this IS the Archimedes buoyancy
// -rho_f Vp g; no separate buoyancy term may be added on top.
inline void pressure_gradient_force(double Vp, const double gradp[3], double F[3]) {
  for (int a = 0; a < 3; ++a) F[a] = -Vp * gradp[a];
}

// Share of a sphere of radius r that lies below a plane free surface, its centre at depth d
// beneath it (d < 0: above it): the cap of height h = r + d, clipped to [0, 2 r], holds
// V_cap / V = h^2 (3 r - h) / (4 r^3). With the fluid at rest the force of the fluid on the
// sphere is then this share of its full buoyancy (Archimedes for a floating body).
inline double immersed_fraction(double d, double r) {
  if (d >= r) return 1.0;  // (exactly: a grain in the bulk keeps its forces to the bit)
  if (d <= -r) return 0.0;
  const double h = r + d;  // within (0, 2 r) here
  return h * h * (3.0 * r - h) / (4.0 * r * r * r);
}

// ---------------------------------------------------------------- time integration
// 1/m_p + 1/m_f; m_f = HUGE_VAL (infinite) means the fluid velocity is prescribed.
inline double drag_inverse_reduced_mass(double m_p, double m_f) {
  return 1.0 / m_p + (std::isinf(m_f) ? 0.0 : 1.0 / m_f);
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

}  // namespace mpm
