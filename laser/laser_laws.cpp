#include "laser_laws.h"

#include <algorithm>
#include <limits>
#include <vector>

namespace laser {

Groups make_groups(const Material& m, double I0, double R) {
  Groups G;
  G.dT = m.Tsat0 - m.Tm;
  G.alpha_l = m.kl / (m.rho * m.cpl);
  G.alpha_s = m.ks / (m.rho * m.cps);
  G.t_scale = R * R / G.alpha_l;
  G.p_scale = m.rho * G.alpha_l * G.alpha_l / (R * R);
  G.v_scale = G.alpha_l / R;
  G.Na = G.alpha_s / G.alpha_l;
  G.Nc = m.cps / m.cpl;
  G.k = m.kl / m.ks;
  G.Ste = m.cpl * G.dT / m.hls;
  G.theta_i = (m.Ti - m.Tm) / G.dT;
  G.theta_m = m.Tm / m.Tsat0;
  G.kprime = m.kl * G.dT / (R * I0);
  G.Iprime = I0 / (m.p0 * m.hlv) * std::sqrt(2.0 * kPi * kGasConstant * m.Tsat0 / m.M);
  G.Lambda = kGamma * kGasConstant * m.Tsat0 / (2.0 * m.M * m.hlv);
  G.Hlv = m.hlv * m.M / (kGasConstant * m.Tsat0);
  G.Ni = I0 * R / (m.rho * G.alpha_l * m.hlv);
  G.Psi = std::sqrt(kGamma * G.Lambda) / (2.0 * std::sqrt(kPi)) * G.alpha_l /
          (R * std::sqrt(m.hlv));
  G.hls_hlv = m.hls / m.hlv;
  G.p0 = m.p0;
  // vapour_term (below) at theta_m, the same expression
  G.vapour_melt = std::exp(G.Hlv * (1.0 - 1.0 / G.theta_m)) * (1.0 + G.Lambda * G.theta_m) /
                  (G.Iprime * std::sqrt(G.theta_m));
  return G;
}

namespace {
// Vapour side of (4-29) divided by I' sqrt(phi).
inline double vapour_term(const Groups& G, double phi, double* dterm) {
  const double v = std::exp(G.Hlv * (1.0 - 1.0 / phi)) * (1.0 + G.Lambda * phi) /
                   (G.Iprime * std::sqrt(phi));
  if (dterm)
    *dterm = v * (G.Hlv / (phi * phi) + G.Lambda / (1.0 + G.Lambda * phi) - 0.5 / phi);
  return v;
}
}  // namespace

namespace {
// interface_residual with the beam E = exp(-xi^2) given (computed once per solve)
double interface_residual_e(const Groups& G, double phi, double E, double g, double b2, double* dres) {
  double dv = 0;
  const double v = vapour_term(G, phi, dres ? &dv : nullptr);
  const double c = G.kprime / (g * (1.0 - G.theta_m));
  if (dres) *dres = dv + c;
  return v + c * (phi - G.theta_m) + G.kprime * b2 * g - E;
}
}  // namespace

double interface_residual(const Groups& G, double phi, double xi, double g, double b2,
                          double* dres) {
  return interface_residual_e(G, phi, gaussian_beam(xi), g, b2, dres);
}

double peclet_factor(double Pe) {
  if (std::fabs(Pe) < 1e-6) return 1.0 + 0.5 * Pe;
  return Pe / -std::expm1(-Pe);
}

namespace {
// peclet_factor for Pe >= 0 with em = 1 - exp(-Pe) given by a caller that needs it too
double peclet_factor_em(double Pe, double em) { return Pe < 1e-6 ? 1.0 + 0.5 * Pe : Pe / em; }
}  // namespace

namespace {
// The vapour term (vapour_term), its derivative, and the flux recession rate
// N_i v - Psi p* sqrt(phi) with its derivative, from one exponential.
VapourParts vapour_parts(const Groups& G, double phi, bool deriv) {
  VapourParts q;
  const double e = std::exp(G.Hlv * (1.0 - 1.0 / phi));
  q.e = e;
  const double sq = std::sqrt(phi);
  q.v = e * (1.0 + G.Lambda * phi) / (G.Iprime * sq);
  const double p_star = G.p0 * e / G.p_scale;
  q.w = G.Ni * q.v - G.Psi * p_star * sq;
  if (deriv) {
    q.dv = q.v * (G.Hlv / (phi * phi) + G.Lambda / (1.0 + G.Lambda * phi) - 0.5 / phi);
    q.dw = G.Ni * q.dv - G.Psi * p_star * (G.Hlv / (phi * phi) * sq + 0.5 / sq);
  }
  return q;
}
// The evaluations of one interface solve keep what is a function of phi alone (the vapour
// parts, with their derivatives) or of Pe alone (1 - exp(-Pe), e^Pe - 1) from the last one
// (and, before the first, from the state the solve starts from): an evaluation at the same phi
// or Pe takes those numbers instead of computing them again, and every result is the same to
// the last bit.
struct Memo {
  double phi = std::numeric_limits<double>::quiet_NaN();
  VapourParts q;
  double Pe = std::numeric_limits<double>::quiet_NaN(), em = 0.0;   // em = 1 - exp(-Pe)
  double Pe1 = std::numeric_limits<double>::quiet_NaN(), em1 = 0.0; // em1 = e^Pe1 - 1
  Memo() = default;
  explicit Memo(const InterfaceState* from) {
    if (!from || !from->has_vapour) return;
    phi = from->phi;
    q = from->vapour;
    Pe = from->peclet;
    em = from->em;
  }
  const VapourParts& parts(const Groups& G, double p);
  double em_at(double pe) {
    if (!(pe == Pe)) {
      Pe = pe;
      em = -std::expm1(-pe);
    }
    return em;
  }
  double em1_at(double pe) {
    if (!(pe == Pe1)) {
      Pe1 = pe;
      em1 = std::expm1(pe);
    }
    return em1;
  }
};
const VapourParts& Memo::parts(const Groups& G, double p) {
  if (!(p == phi)) {
    phi = p;
    q = vapour_parts(G, p, true);
  }
  return q;
}

// a solved state keeps its vapour parts and 1 - exp(-Pe) for a solve started from it
void keep_vapour(InterfaceState& s, const VapourParts& q, double em) {
  s.vapour = q;
  s.em = em;
  s.has_vapour = true;
}

// The root of an interface solve: where its last Newton correction was at the level of
// rounding (at most kRoundingUlps units in the last place of phi), the point last evaluated,
// which is as close to the root as phi can be resolved and whose vapour parts and
// 1 - exp(-Pe) the solve holds; else the corrected point (evaluated again for the state).
constexpr double kRoundingUlps = 4.0;
double at_rounding(const RootResult& rr) {
  const bool rounding = rr.converged && std::fabs(rr.x - rr.x_eval) <= kRoundingUlps * 0x1p-52 * std::fabs(rr.x);
  return rounding ? rr.x_eval : rr.x;
}

// advected_residual from the vapour parts at phi and the beam E = exp(-xi^2); em_out
// receives 1 - exp(-Pe), which content_factor and interface_at use at the same Pe;
// memo: where 1 - exp(-Pe) may be known
double advected_residual_of(const Groups& G, const VapourParts& q, double phi, double E, double g, double b2,
                            double* dres, double* em_out = nullptr, Memo* memo = nullptr) {
  const double th = (phi - G.theta_m) / (1.0 - G.theta_m);
  const double w = std::max(q.w, 0.0);
  const double Pe = w * g;
  const double em = memo ? memo->em_at(Pe) : -std::expm1(-Pe);  // 1 - exp(-Pe)
  if (em_out) *em_out = em;
  const double F = peclet_factor_em(Pe, em);
  if (dres) {
    const double dw = w > 0.0 ? q.dw : 0.0;
    // F'(Pe) = (1 - e^-Pe (1 + Pe)) / (1 - e^-Pe)^2
    const double dF = Pe < 1e-6 ? 0.5 : (em - Pe * (1.0 - em)) / (em * em);
    *dres = q.dv + G.kprime * (F / (g * (1.0 - G.theta_m)) + th * dF * dw);
  }
  return q.v + G.kprime * (th / g * F + b2 * g) - E;
}
}  // namespace

double flux_recession_rate(const Groups& G, double phi, double* dw) {
  const VapourParts q = vapour_parts(G, phi, dw != nullptr);
  if (dw) *dw = q.dw;
  return q.w;
}

double advected_residual(const Groups& G, double phi, double xi, double g, double b2, double* dres) {
  // one exponential for the vapour term, the pressure and the flux velocity
  return advected_residual_of(G, vapour_parts(G, phi, dres != nullptr), phi, gaussian_beam(xi), g, b2, dres);
}

namespace {
// interface_at from the vapour parts q at phi (their exponential gives the pressure) and, where
// the caller has it, em = 1 - exp(-Pe) at the layer's Pe (else computed, as peclet_factor does)
InterfaceState interface_at_q(const Groups& G, const VapourParts& q, double phi, double g, double b2, bool advected,
                              const double* em = nullptr) {
  InterfaceState s;
  s.phi = phi;
  s.theta_sat = (phi - G.theta_m) / (1.0 - G.theta_m);
  double F = 1.0;
  if (advected) {
    s.w = std::max(q.w, 0.0);
    s.peclet = s.w * g;
    F = peclet_factor_em(s.peclet, em ? *em : -std::expm1(-s.peclet));
  }
  s.grad_top = s.theta_sat / g * F + b2 * g;
  s.grad_bottom = s.theta_sat / g * F * std::exp(-s.peclet) - b2 * g;
  s.p_pa = G.p0 * q.e;
  s.p_star = s.p_pa / G.p_scale;
  return s;
}
}  // namespace

InterfaceState interface_at(const Groups& G, double phi, double g, double b2, bool advected) {
  return interface_at_q(G, vapour_parts(G, phi, false), phi, g, b2, advected);
}

namespace {
InterfaceState solve_interface_m(const Groups& G, double xi, double g, double b2, bool advected, double phi_guess,
                                 Memo& memo) {
  InterfaceState s;
  const double E = gaussian_beam(xi);
  s.phi = G.theta_m;
  s.theta_sat = 0.0;
  if (!(g > 0.0)) {
    // Vanishing layer: all that is not evaporated at T_m is conducted through.
    const double q = std::max(E - G.vapour_melt, 0.0) / G.kprime;
    s.grad_top = s.grad_bottom = q;
  } else {
    const double avail = E - G.kprime * b2 * g;
    const double r0 = G.vapour_melt - avail;
    if (r0 < 0.0) {
      // Upper bracket: the conduction-only root, where the vapour term is > 0.
      const double hi = G.theta_m + avail * g * (1.0 - G.theta_m) / G.kprime;
      // Advected layer: vapour + k' (theta_sat/g F(w(phi) g) + b2 g) - beam; every
      // term rises with phi and F >= 1, so the linear layer's bracket [theta_m, hi] holds.
      auto residual = [&](double phi, double* df) {
        return advected ? advected_residual_of(G, memo.parts(G, phi), phi, E, g, b2, df, nullptr, &memo)
                        : interface_residual_e(G, phi, E, g, b2, df);
      };
      // residual(theta_m) = r0 < 0 < residual(hi): at hi the conduction term is avail, so the
      // residual is the vapour term there (>= vapour_melt > 0) plus k' theta_sat/g (F - 1) >= 0.
      // It is therefore not evaluated where vapour_melt is a normal number: where hi - theta_m
      // is below round-off (a very thin layer) the rounding of theta_sat can make it <= 0, and
      // the iteration then ends within its tolerance of hi, the conduction root. Where the
      // vapour term at T_m underflows (latent heats far beyond a metal's) it can jump from 0 to
      // inf inside the bracket, and the sign at hi is checked.
      if (std::isnormal(G.vapour_melt) || residual(hi, nullptr) > 0.0) {
        auto fdf = [&](double phi, double& f, double& df) { f = residual(phi, &df); };
        const RootResult rr = safe_newton(fdf, G.theta_m, hi, 1e-15 * hi, 200, phi_guess, true);
        s.phi = at_rounding(rr);
        s.iterations = rr.iterations;
        s.converged = rr.converged;
      } else {
        // the conduction root
        s.phi = hi;
      }
      s.theta_sat = (s.phi - G.theta_m) / (1.0 - G.theta_m);
      if (advected) {
        // the state at the root from one exponential of the vapour pressure and one 1 - exp(-Pe)
        const VapourParts q = memo.parts(G, s.phi);
        double em = 0.0;
        const double res = advected_residual_of(G, q, s.phi, E, g, b2, nullptr, &em, &memo);
        InterfaceState a = interface_at_q(G, q, s.phi, g, b2, true, &em);
        a.residual = res / E;
        a.iterations = s.iterations;
        a.converged = s.converged;
        keep_vapour(a, q, em);
        return a;
      }
      s.residual = interface_residual_e(G, s.phi, E, g, b2, nullptr) / E;
    }
    // the linear profile of (4-26): a layer without a vapour root has w = 0 (the advected one
    // with its root returned above)
    s.grad_top = s.theta_sat / g + b2 * g;
    s.grad_bottom = s.theta_sat / g - b2 * g;
  }
  s.p_pa = G.p0 * std::exp(G.Hlv * (1.0 - 1.0 / s.phi));
  s.p_star = s.p_pa / G.p_scale;
  return s;
}
}  // namespace

InterfaceState solve_interface(const Groups& G, double xi, double g, double b2, bool advected, double phi_guess) {
  Memo memo;
  return solve_interface_m(G, xi, g, b2, advected, phi_guess, memo);
}

InterfaceState solve_interface(const Groups& G, double xi, double g, double b2, bool advected,
                               const InterfaceState& from) {
  Memo memo(&from);
  return solve_interface_m(G, xi, g, b2, advected, from.phi, memo);
}

namespace {
// content_factor with em = 1 - exp(-Pe) given where the caller has it (the residual of the
// advected layer computes it at the same Pe)
double content_factor_em(double Pe, double* dc, const double* em, Memo* memo = nullptr) {
  if (Pe < 1e-3) {  // series of 1/Pe - 1/(e^Pe - 1)
    if (dc) *dc = -1.0 / 12.0 + Pe * Pe / 240.0;
    return 0.5 - Pe / 12.0 + Pe * Pe * Pe / 720.0;
  }
  const double em1 = memo ? memo->em1_at(Pe) : std::expm1(Pe);  // e^Pe - 1
  if (dc)
    *dc = -1.0 / (Pe * Pe) +
          (std::isfinite(em1) ? 1.0 / (em1 * (em ? *em : memo ? memo->em_at(Pe) : -std::expm1(-Pe))) : 0.0);
  return 1.0 / Pe - (std::isfinite(em1) ? 1.0 / em1 : 0.0);
}
}  // namespace

double content_factor(double Pe, double* dc) { return content_factor_em(Pe, dc, nullptr); }

double layer_content(const InterfaceState& s, double g, double b2) {
  return s.theta_sat * g * content_factor(s.peclet) - b2 * g * g * g / 6.0;
}

namespace {
InterfaceState solve_interface_flux_m(const Groups& G, double xi, double g, double beta, double gamma, bool advected,
                                      double kappa, double H_old, double phi_guess, Memo& memo) {
  if (!(g > 0.0) || !(beta >= 0.0) || !(kappa >= 0.0)) return solve_interface(G, xi, g, 0.0, advected);
  const double E = gaussian_beam(xi);
  // content0(phi) = theta_sat g c(Pe(phi)) >= 0, so the flow's part is >= beta theta_sat - gamma - kappa H_old
  const double avail = E + G.kprime * (gamma + kappa * H_old);
  // q: the vapour parts at p where the caller has them (one exponential per evaluation); em:
  // 1 - exp(-Pe) at p where the caller has it
  auto content0 = [&](double p, double* dcont, const VapourParts* q, const double* em) {
    const double th = (p - G.theta_m) / (1.0 - G.theta_m);
    double c = 0.5, dc = 0.0, Pe = 0.0, dw = 0.0;
    if (advected) {
      const VapourParts qp = q ? *q : memo.parts(G, p);
      const double w = qp.w;
      dw = qp.dw;
      Pe = std::max(w, 0.0) * g;
      if (!(w > 0.0)) dw = 0.0;
      c = content_factor_em(Pe, &dc, em, &memo);
    }
    if (dcont) *dcont = g * (c / (1.0 - G.theta_m) + th * dc * g * dw);
    return th * g * c;
  };
  auto flow_part = [&](double p, double* dpart, const VapourParts* q, const double* em) {  // b2 g
    const double th = (p - G.theta_m) / (1.0 - G.theta_m);
    double dcont = 0.0;
    const double cont = kappa > 0.0 ? content0(p, dpart ? &dcont : nullptr, q, em) : 0.0;
    if (dpart) *dpart = beta / (1.0 - G.theta_m) + kappa * dcont;
    return beta * th - gamma + (kappa > 0.0 ? kappa * (cont - H_old) : 0.0);
  };
  double phi = G.theta_m;
  RootResult rr;
  rr.converged = true;
  if (G.vapour_melt - avail < 0.0) {
    auto residual = [&](double p, double* df) {
      double r, em = 0.0;
      VapourParts q;
      if (advected) {
        q = memo.parts(G, p);
        r = advected_residual_of(G, q, p, E, g, 0.0, df, &em, &memo);
      } else {
        r = interface_residual_e(G, p, E, g, 0.0, df);
      }
      double dpart = 0.0;
      const double part = flow_part(p, df ? &dpart : nullptr, advected ? &q : nullptr, advected ? &em : nullptr);
      if (df) *df += G.kprime * dpart;
      return r + G.kprime * part;
    };
    // vapour term >= 0, F >= 1, content0 >= 0: theta_sat <= avail / (k' (1/g + beta))
    const double hi = G.theta_m + avail * (1.0 - G.theta_m) / (G.kprime * (1.0 / g + beta));
    // at hi: residual = vapour term + k' theta_sat/g (F - 1) + k' kappa content0 > 0, evaluated
    // only where vapour_melt underflows, as in solve_interface
    if (std::isnormal(G.vapour_melt) || residual(hi, nullptr) > 0.0) {
      auto fdf = [&](double p, double& f, double& df) { f = residual(p, &df); };
      rr = safe_newton(fdf, G.theta_m, hi, 1e-15 * hi, 200, phi_guess, true);
      phi = at_rounding(rr);
    } else {
      phi = hi;
    }
  }
  // the state at the root from one exponential of the vapour pressure and one 1 - exp(-Pe):
  // the values of flow_part, interface_at and advected_residual at phi, each of which would
  // compute them again (test LaserLaws.FluxInterfaceSharesItsExponentials)
  const VapourParts q = memo.parts(G, phi);
  const double b2 = flow_part(phi, nullptr, advected ? &q : nullptr, nullptr) / g;
  double res, em = 0.0;
  if (advected) {
    res = advected_residual_of(G, q, phi, E, g, b2, nullptr, &em, &memo);
  } else {
    res = interface_residual_e(G, phi, E, g, b2, nullptr);
  }
  InterfaceState s = interface_at_q(G, q, phi, g, b2, advected, advected ? &em : nullptr);
  s.iterations = rr.iterations;
  s.converged = rr.converged;
  s.residual = res / E;
  if (advected) keep_vapour(s, q, em);
  return s;
}
}  // namespace

InterfaceState solve_interface_flux(const Groups& G, double xi, double g, double beta, double gamma,
                                    bool advected, double kappa, double H_old, double phi_guess) {
  Memo memo;
  return solve_interface_flux_m(G, xi, g, beta, gamma, advected, kappa, H_old, phi_guess, memo);
}

InterfaceState solve_interface_flux(const Groups& G, double xi, double g, double beta, double gamma,
                                    bool advected, double kappa, double H_old, const InterfaceState& from) {
  Memo memo(&from);
  return solve_interface_flux_m(G, xi, g, beta, gamma, advected, kappa, H_old, from.phi, memo);
}

double recession_rate(const Groups& G, double xi, const InterfaceState& s) {
  return G.Ni * gaussian_beam(xi) - G.Psi * s.p_star * std::sqrt(s.phi) -
         G.hls_hlv * G.Ste * s.grad_top;
}

double recession_rate_from_flux(const Material& m, double R, const InterfaceState& s,
                                double Tsat0) {
  const double T = s.phi * Tsat0;
  const double jv = evaporation_molar_flux(s.p_pa, T, m.M);
  const double alpha_l = m.kl / (m.rho * m.cpl);
  return jv * m.M / m.rho / (alpha_l / R);
}

double premelt_temperature(const Groups& G, double xi, double n, double tau) {
  if (tau <= 0.0) return G.theta_i;
  const double sq = std::sqrt(G.Na * tau);
  const double eta = n / (2.0 * sq);
  const double ierfc = std::exp(-eta * eta) / std::sqrt(kPi) - eta * std::erfc(eta);
  return G.theta_i + 2.0 * G.k / G.kprime * gaussian_beam(xi) * sq * ierfc;
}

double melt_onset_tau(const Groups& G, double xi) {
  const double x = G.theta_i * G.kprime / (G.k * gaussian_beam(xi));
  return kPi / (4.0 * G.Na) * x * x;
}

double established_profile(double theta_i, double eta_m) {
  return theta_i -
         theta_i * (std::exp(-eta_m * eta_m) - std::sqrt(kPi) * eta_m * std::erfc(eta_m));
}

double stefan_gradient(double theta_i, double Na, double tau_m, double tau, double c) {
  return theta_i / std::sqrt(kPi * Na * (tau - tau_m + c * tau_m));
}

double stefan_gradient_mean(double theta_i, double Na, double tau_m, double ta, double tb,
                            double c) {
  const double xa = ta - tau_m + c * tau_m, xb = tb - tau_m + c * tau_m;
  return 2.0 * theta_i / (std::sqrt(kPi * Na) * (std::sqrt(xa) + std::sqrt(xb)));
}

double melting_rate(const Groups& G, double Cc, double grad_n, double J, double grad_l_bottom,
                    bool moving_origin) {
  const double L = (1.0 / (G.Ste * G.Nc) - (moving_origin ? Cc * G.theta_i : 0.0)) / G.Na;
  return (Cc * grad_n * J + G.k * grad_l_bottom) / L;
}

double curvature_factor(double a, double d) {
  double y = 0.5 * a * d;
  if (std::fabs(y) < 1e-8) return 1.0 - (a > 0 ? 1.0 : -1.0) * y * y / 6.0;
  const bool convex = y > 0;  // a > 0
  y = std::min(std::fabs(y), 1.0);
  return convex ? y / std::asin(y) : std::asin(y) / y;
}

double curvature_factor_conduction(double a, double d) { return curvature_factor(-a, d); }

double flow_shape(const FlowProfile& P, double A, double xi) {
  return P.rising ? A * std::pow(xi, 1.0 / P.m) : A * xi * std::exp(-xi / P.xi_p);
}

double flow_surface_velocity(const FlowProfile& P, double A, double xi, double g) {
  if (P.rising) return -(1.0 + P.m) / (2.0 * P.m) * A * std::pow(xi, 1.0 / P.m - 1.0) * g * g;
  return -0.5 * A * g * g * (2.0 - xi / P.xi_p) * std::exp(-xi / P.xi_p);  // (4-22)
}

void flow_residual_coefficients(const FlowProfile& P, double Pr, double xi, double g, double dpdxi,
                                double& a, double& b, double& c) {
  if (P.rising) {  // (4-17)
    a = g * g * std::pow(xi, 2.0 / P.m + 1.0);
    b = -3.0 * Pr * g * std::pow(xi, 1.0 / P.m);
    c = -6.0 * P.m / (P.m - 1.0) * xi * xi * dpdxi;
  } else {  // (4-23)
    const double e = std::exp(xi / P.xi_p);
    a = g * g * xi * xi;
    b = -3.0 * Pr * g * e;
    c = -6.0 * P.xi_p * dpdxi * e * e;
  }
}

CubicRoot select_flow_root(double Q1, double Q2, double Q3, double Q4) {
  CubicRoot out;
  if (!(Q1 > 0.0) || !std::isfinite(Q1) || !std::isfinite(Q2) || !std::isfinite(Q3) ||
      !std::isfinite(Q4)) {
    out.note = "degenerate cubic (no melt or non-finite coefficients)";
    return out;
  }
  if (Q4 == 0.0) { out.ok = true; out.A = 0.0; out.real_roots = 1; return out; }
  auto W = [&](double A) { return ((Q1 * A - Q2) * A + Q3) * A - Q4; };
  auto fdf = [&](double A, double& f, double& df) {
    f = W(A);
    df = (3.0 * Q1 * A - 2.0 * Q2) * A + Q3;
  };
  const double B = 1.0 + std::max({std::fabs(Q2), std::fabs(Q3), std::fabs(Q4)}) / Q1;
  std::vector<std::pair<double, double>> brackets;
  const double disc = Q2 * Q2 - 3.0 * Q1 * Q3;
  if (disc <= 0.0) {
    brackets.push_back({-B, B});
  } else {
    const double A1 = (Q2 - std::sqrt(disc)) / (3.0 * Q1);  // local maximum of W
    const double A2 = (Q2 + std::sqrt(disc)) / (3.0 * Q1);  // local minimum of W
    const double w1 = W(A1), w2 = W(A2);
    if (w1 >= 0.0) brackets.push_back({-B, A1});
    if (w1 >= 0.0 && w2 <= 0.0) brackets.push_back({A1, A2});
    if (w2 <= 0.0) brackets.push_back({A2, B});
  }
  std::vector<double> roots;
  for (auto [lo, hi] : brackets) {
    const RootResult r = safe_newton(fdf, lo, hi, 1e-15 * B);
    if (r.converged && std::isfinite(r.x)) roots.push_back(r.x);
  }
  out.real_roots = static_cast<int>(roots.size());
  if (roots.empty()) { out.note = "no real root found"; return out; }
  if (Q4 > 0.0) {
    // W(0) < 0: the physical root is the smallest positive one, i.e. the root
    // in (0, A1] when W(A1) >= 0 and the single root beyond A2 otherwise.
    double best = std::numeric_limits<double>::infinity();
    for (double r : roots)
      if (r > 0.0 && r < best) best = r;
    if (!std::isfinite(best)) { out.note = "no positive root"; return out; }
    out.A = best;
  } else {
    // Pressure rising outwards (Q4 < 0): take the root nearest zero.
    double best = roots[0];
    for (double r : roots)
      if (std::fabs(r) < std::fabs(best)) best = r;
    out.A = best;
    out.note = "Q4 < 0: inward flow root";
  }
  out.ok = true;
  return out;
}

}  // namespace laser
