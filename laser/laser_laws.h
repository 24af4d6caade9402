// Physics laws of the laser drilling model (dissertation Part I, ch. 3-4),
// kept apart from the time stepping so that each can be tested on its own.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>

namespace laser {

constexpr double kPi = 3.14159265358979323846;
constexpr double kGasConstant = 8.314462618;  // R_g [J/(mol K)]
constexpr double kGamma = 5.0 / 3.0;           // monoatomic vapour, text after (3-13)

// ---------------------------------------------------------------- root finding
struct RootResult {
  double x = 0.0;
  int iterations = 0;
  bool converged = false;
  double x_eval = std::numeric_limits<double>::quiet_NaN();  // safe_newton: the last point f was evaluated at
};

// Safeguarded Newton ("rtsafe"): f(lo) and f(hi) must have opposite signs; a
// Newton step that leaves the current bracket, or does not halve the bracket
// fast enough, is replaced by bisection, so the iteration never diverges. It starts
// from x0 where x0 lies inside the bracket, else from its midpoint. signs_known: the
// caller has checked f(lo) < 0 < f(hi), and the ends are not evaluated again.
// (A template, so that the callers' lambdas are called directly: the same arithmetic as
// through std::function, without its indirection and allocation.)
template <class FDF>
RootResult safe_newton(const FDF& fdf, double lo, double hi, double xtol, int maxit = 200,
                       double x0 = std::numeric_limits<double>::quiet_NaN(), bool signs_known = false);

// Derivative-free bracketed root (Illinois variant of regula falsi): f(a) and
// f(b) of opposite sign; superlinear and never leaves [a, b]. Stops when the bracket is
// below xtol or |f| <= ftol (for f' >= 1, |f(x)| bounds the distance to the root).
template <class Fn>
RootResult illinois_root(const Fn& f, double a, double b, double fa, double fb, double xtol, int maxit = 200,
                         double ftol = 0.0);

// ---- definitions of the two templates
template <class FDF>
RootResult safe_newton(const FDF& fdf, double lo, double hi, double xtol, int maxit,
                       double x0, bool signs_known) {
  RootResult r;
  double flo = -1.0, fhi = 1.0, d;
  if (!signs_known) {
    fdf(lo, flo, d);
    fdf(hi, fhi, d);
  }
  if (flo == 0.0) { r.x = lo; r.converged = true; return r; }
  if (fhi == 0.0) { r.x = hi; r.converged = true; return r; }
  if ((flo > 0.0) == (fhi > 0.0) || !std::isfinite(flo) || !std::isfinite(fhi)) {
    r.x = std::numeric_limits<double>::quiet_NaN();
    return r;
  }
  if (flo > 0.0) std::swap(lo, hi);  // orient so that f(lo) < 0 < f(hi)
  const bool inside = x0 > std::min(lo, hi) && x0 < std::max(lo, hi);
  double x = inside ? x0 : 0.5 * (lo + hi), dxold = std::fabs(hi - lo), dx = dxold;
  double f, df;
  fdf(x, f, df);
  r.x_eval = x;
  for (int it = 1; it <= maxit; ++it) {
    r.iterations = it;
    const bool newton_leaves = ((x - hi) * df - f) * ((x - lo) * df - f) > 0.0;
    const bool too_slow = std::fabs(2.0 * f) > std::fabs(dxold * df);
    dxold = dx;
    if (newton_leaves || too_slow || !std::isfinite(df) || df == 0.0) {
      dx = 0.5 * (hi - lo);
      x = lo + dx;
    } else {
      dx = f / df;
      x -= dx;
    }
    if (std::fabs(dx) <= xtol) { r.converged = true; break; }
    fdf(x, f, df);
    r.x_eval = x;
    if (f == 0.0) { r.converged = true; break; }
    if (f < 0.0) lo = x; else hi = x;
    if (std::fabs(hi - lo) <= xtol) { r.converged = true; break; }
  }
  r.x = x;
  return r;
}

template <class Fn>
RootResult illinois_root(const Fn& f, double a, double b, double fa, double fb, double xtol, int maxit,
                         double ftol) {
  RootResult r;
  if ((fa > 0.0) == (fb > 0.0) && fa != 0.0 && fb != 0.0) {
    r.x = std::numeric_limits<double>::quiet_NaN();
    return r;
  }
  int side = 0;
  double c = a;
  for (int it = 1; it <= maxit; ++it) {
    r.iterations = it;
    c = (fa * b - fb * a) / (fa - fb);
    if (!(c > std::min(a, b) && c < std::max(a, b))) c = 0.5 * (a + b);
    const double fc = f(c);
    if (std::fabs(fc) <= ftol || std::fabs(b - a) <= xtol) { r.converged = true; break; }
    if ((fc > 0.0) == (fb > 0.0)) {
      b = c; fb = fc;
      if (side == -1) fa *= 0.5;
      side = -1;
    } else {
      a = c; fa = fc;
      if (side == 1) fb *= 0.5;
      side = 1;
    }
    if (std::fabs(b - a) <= xtol) { r.converged = true; break; }
  }
  r.x = c;
  return r;
}


// --------------------------------------------------------- Clausius-Clapeyron
// (3-15): vapour pressure [Pa] at the surface temperature T [K].
inline double clausius_clapeyron_pressure(double T, double p0, double Tsat0, double hlv,
                                          double M) {
  return p0 * std::exp(hlv * M / kGasConstant * (1.0 / Tsat0 - 1.0 / T));
}
// Inverse of (3-15): saturation temperature [K] at pressure p [Pa].
inline double clausius_clapeyron_temperature(double p, double p0, double Tsat0, double hlv,
                                             double M) {
  return 1.0 / (1.0 / Tsat0 - kGasConstant / (hlv * M) * std::log(p / p0));
}
// (3-13): vapour velocity [m/s].
inline double vapour_velocity(double T, double M) {
  return std::sqrt(kGamma * kGasConstant * T / M);
}
// (3-17): molar evaporation flux [mol/(m2 s)].
inline double evaporation_molar_flux(double p, double T, double M) {
  return p / std::sqrt(2.0 * kPi * M * kGasConstant * T);
}
// (3-19), read dimensionally consistent (the square root covers only
// 2 pi R_g T / M): recoil pressure [Pa] that carries the net flux q [W/m2].
inline double recoil_pressure_from_flux(double q, double T, double hlv, double M) {
  return std::sqrt(2.0 * kPi * kGasConstant * T / M) * q /
         (hlv + kGamma * kGasConstant * T / (2.0 * M));
}

// ------------------------------------------------------------------ beam
// (3-21), nondimensional: I / I0. A run asks for the beam at one node many times in a row
// (each evaluation of the interface balance and of the recession rate): the last value is
// kept (per thread) and returned for the same xi, the same number.
inline double gaussian_beam(double xi) {
  thread_local double last_xi = std::numeric_limits<double>::quiet_NaN(), last = 0.0;
  if (!(xi == last_xi)) {
    last = std::exp(-xi * xi);
    last_xi = xi;
  }
  return last;
}

// ----------------------------------------------------- nondimensional groups
struct Material {
  std::string name = "superalloy";
  double hls = 2.31e4;      // J/kg
  double hlv = 6.444e6;     // J/kg
  double rho = 8.4e3;       // kg/m3
  double M = 0.076;         // kg/mol
  double Ti = 293.15;       // K
  double Tm = 1510.0 + 273.15;    // K
  double Tsat0 = 3170.0 + 273.15; // K
  double p0 = 1.01325e5;    // Pa
  double kl = 21.70;        // W/(m K)
  double ks = 52.72;        // W/(m K)
  double cpl = 625.0;       // J/(kg K)
  double cps = 380.0;       // J/(kg K)
  double Pr = 0.142;        // -
  // Critical temperature: the vapour model (3-15)/(3-17) and the sharp melt-vapour
  // interface lose meaning as T_s approaches it. Not in the text; estimates for
  // nickel, the base of the super alloy, range 7800-9500 K: 8500 K is taken.
  double Tc = 8500.0;       // K
};

struct Groups {
  // scales
  double dT = 0, alpha_l = 0, alpha_s = 0, t_scale = 0, p_scale = 0, v_scale = 0;
  // groups of ch. 3
  double Na = 0, Nc = 0, k = 0, Ste = 0, theta_i = 0, theta_m = 0;
  double kprime = 0, Iprime = 0, Lambda = 0, Hlv = 0, Ni = 0, Psi = 0, hls_hlv = 0;
  double p0 = 0;  // Pa, to restore dimensional pressure
  double vapour_melt = 0;  // vapour term of (4-29) at T_m (the bracket of every interface solve)
};

// Builds the groups defined after (3-4a), (3-22), (3-24), (3-25), (3-26).
Groups make_groups(const Material& m, double I0, double R);

// ---------------------------------------------------- melt-vapour interface
// The vapour side of (4-29) at one surface temperature phi, from one exponential: the vapour
// term v (divided by I' sqrt(phi)) and the flux recession rate w = N_i v - Psi p* sqrt(phi), with
// their derivatives in phi (w, dw not clipped at 0).
struct VapourParts {
  double v = 0, dv = 0, w = 0, dw = 0;
  double e = 0;  // exp(H_lv (1 - 1/phi)) = p / p0
};

struct InterfaceState {
  double phi = 0;        // T_sat / T_sat0
  double theta_sat = 0;  // (T_sat - T_m) / (T_sat0 - T_m)
  double p_star = 0;     // p R^2 / (rho alpha_l^2)
  double p_pa = 0;       // Pa
  double grad_top = 0;   // d theta_l / d zeta at zeta = g   (4-26)
  double grad_bottom = 0;// d theta_l / d zeta at zeta = 0   (4-26)
  double w = 0;          // advected layer: liquid velocity through the layer, dS1/dtau
  double peclet = 0;     // advected layer: w g
  double residual = 0;   // of (4-29), relative to exp(-xi^2)
  int iterations = 0;
  bool converged = true;
  // advected layer, a solved state: the vapour parts at phi and em = 1 - exp(-peclet), which a
  // solve started from this state (solve_interface(..., from)) takes instead of computing
  // them again (functions of phi and of peclet alone: the same numbers)
  VapourParts vapour;
  double em = 0;
  bool has_vapour = false;
};

// Residual of (4-29) divided by I' sqrt(phi): vapour term + conduction term -
// beam. Strictly increasing in phi for phi < 2 H_lv, so its root is unique.
double interface_residual(const Groups& G, double phi, double xi, double g, double b2,
                          double* dres = nullptr);
// Peclet factor F(Pe) = Pe / (1 - exp(-Pe)) of the advected melt layer: the
// surface gradient of the steady-ablation profile over the linear one.
double peclet_factor(double Pe);
// Nondimensional recession velocity dS1/dtau carried by the evaporation flux
// at the surface temperature phi alone: N_i (vapour term) - Psi p* sqrt(phi),
// which equals (3-25) once the interface balance (4-29) holds.
double flux_recession_rate(const Groups& G, double phi, double* dw = nullptr);
// Residual of the interface balance of the advected layer (as interface_residual)
// and its derivative in phi.
double advected_residual(const Groups& G, double phi, double xi, double g, double b2, double* dres);
// Interface state (gradients, pressure) of a layer g at a given phi.
InterfaceState interface_at(const Groups& G, double phi, double g, double b2, bool advected);
// Solves (4-28)-(4-30) for the surface temperature of a melt layer of
// nondimensional thickness g with the quadratic profile (4-25) of coefficient
// b2; g = 0 is the limit of a vanishing layer (T_sat = T_m). With advected =
// true the layer is quasi-steady advection-diffusion in the frame of the
// receding surface (liquid moving towards it at w = dS1/dtau): the linear part
// theta_sat zeta/g becomes the exponential steady-ablation profile, so that the
// surface gradient is theta_sat/g F(w g) and the bottom one smaller by
// exp(-w g); their difference w theta_sat heats the vaporized liquid from T_m
// to T_sat (docs/theory/laser_model.md, "Energy-consistent melt layer").
// phi_guess (inside the bracket) starts the Newton iteration: the same root to 1e-15,
// fewer iterations when the caller knows a nearby one.
InterfaceState solve_interface(const Groups& G, double xi, double g, double b2, bool advected = false,
                               double phi_guess = std::numeric_limits<double>::quiet_NaN());
// The same started from the state 'from' of the same groups G (phi_guess = from.phi): where the
// iteration evaluates the residual at from.phi (or at from's Pe) it takes from's vapour parts
// (and 1 - exp(-Pe)) instead of computing them again; the result is that of the call above with
// phi_guess = from.phi, to the last bit.
InterfaceState solve_interface(const Groups& G, double xi, double g, double b2, bool advected,
                               const InterfaceState& from);
// The same with the flow's part of the gradients tied to the surface temperature,
// b2 g = beta theta_sat - gamma (beta >= 0): the layer gives the heat its outflow
// carries at its own temperature and takes gamma from upstream (--melt-heat flux,
// docs/theory/laser_model.md 2.7). Every term still rises with phi: one bracketed root.
//
// With the layer's heat content (--melt-content transient, docs 2.7) the flow's part
// becomes b2 g = beta theta_sat - gamma + kappa (content0(phi) - H_old), where
// content0 = theta_sat g c(Pe) is the content of the layer's profile without b2,
// H_old the content at the start of the step and kappa = s/(2 dtau) >= 0 (the
// caller scales beta and gamma by s = 1/(1 + g^2/(12 dtau))); kappa = 0 is the
// quasi-steady layer.
InterfaceState solve_interface_flux(const Groups& G, double xi, double g, double beta, double gamma,
                                    bool advected = false, double kappa = 0.0, double H_old = 0.0,
                                    double phi_guess = std::numeric_limits<double>::quiet_NaN());
// The same started from the state 'from' (phi_guess = from.phi), taking its vapour parts as
// solve_interface(..., from) does: the result of the call above to the last bit.
InterfaceState solve_interface_flux(const Groups& G, double xi, double g, double beta, double gamma,
                                    bool advected, double kappa, double H_old, const InterfaceState& from);
// Content factor of the layer's profile without b2: int_0^g theta dzeta = theta_sat g c(Pe),
// c(Pe) = 1/Pe - 1/(e^Pe - 1) for the advected (exponential) profile, 1/2 for the
// linear one (Pe = 0); dc receives c'(Pe).
double content_factor(double Pe, double* dc = nullptr);
// Heat content int_0^g theta dzeta of a layer with the profile of s and the
// quadratic term b2 zeta (zeta - g) of (4-25): theta_sat g c(Pe) - b2 g^3/6.
double layer_content(const InterfaceState& s, double g, double b2);
// Nondimensional vaporization recession rate dS1/dtau by (3-25).
double recession_rate(const Groups& G, double xi, const InterfaceState& s);
// The same rate from the dimensional laws (3-16), (3-17): rho ds1/dt = j_v M.
double recession_rate_from_flux(const Material& m, double R, const InterfaceState& s,
                                double Tsat0);

// ------------------------------------------------------------ solid conduction
// Pre-melting surface temperature, (3-26) at n = 0, with the coefficient 2 of
// the classical constant-flux solution (see docs/theory/laser_model.md).
double premelt_temperature(const Groups& G, double xi, double n, double tau);
// Melt onset time (3-27) consistent with premelt_temperature.
double melt_onset_tau(const Groups& G, double xi);
// (3-28): profile at onset, eta_m = n / (2 sqrt(N_a tau_m)).
double established_profile(double theta_i, double eta_m);
// (3-31) as printed: tau_0 = tau_m / (4 pi).
constexpr double kTau0OverTauM = 1.0 / (4.0 * kPi);
// Stefan gradient d theta_s/dn at n = 0 of theta_i erf(n / (2 sqrt(Na (tau - tau_m + c tau_m)))),
// i.e. (3-30) for c = tau_0/tau_m and (3-36) for c = 3 tau_0/tau_m.
double stefan_gradient(double theta_i, double Na, double tau_m, double tau, double c);
// Its mean over [tau_a, tau_b] (closed form), used by the time stepper.
double stefan_gradient_mean(double theta_i, double Na, double tau_m, double ta, double tb,
                            double c);

// ------------------------------------------------- interface corrections
// Curvature factor (3-37) for curvature a and arc d; clamps |a d| < 2.
double curvature_factor(double a, double d);
// The same with the branches exchanged, 1/curvature_factor(a, d) = curvature_factor(-a, d):
// C_c >= 1 where the front bulges into the solid (a > 0), as conduction into the
// curved solid requires (docs/theory/laser_model.md 2.5; --curvature-factor conduction).
double curvature_factor_conduction(double a, double d);

// (3-40): melting rate dS2/dtau (unclamped) from the solid gradient grad_n
// (d theta_s/dn at the front, < 0), the slope factor J = sqrt(1 + S2'^2), the
// curvature factor Cc and the melt gradient d theta_l/dzeta at zeta = 0.
double melting_rate(const Groups& G, double Cc, double grad_n, double J, double grad_l_bottom,
                    bool moving_origin);

// ------------------------------------------------------------ melt flow
// Integral radial profiles u = f(xi) zeta: rising f = A xi^(1/m) (4-17),
// rising-fall f = A xi exp(-xi/xi_p) (4-22).
struct FlowProfile {
  bool rising = false;
  double m = 2.0, xi_p = 1.0;
};
double flow_shape(const FlowProfile& P, double A, double xi);  // f(xi)
// Vertical velocity at the melt surface, v(xi, g) = -(f' + f/xi) g^2 / 2.
double flow_surface_velocity(const FlowProfile& P, double A, double xi, double g);
// Local momentum residual a A^2 + b A + c of (4-17) / (4-23).
void flow_residual_coefficients(const FlowProfile& P, double Pr, double xi, double g, double dpdxi,
                                double& a, double& b, double& c);

struct CubicRoot {
  double A = 0;
  int real_roots = 0;
  bool ok = false;
  std::string note;
};
// Physical root of W(A) = Q1 A^3 - Q2 A^2 + Q3 A - Q4 (4-19) selected as in
// the text after (4-21).
CubicRoot select_flow_root(double Q1, double Q2, double Q3, double Q4);

}  // namespace laser
