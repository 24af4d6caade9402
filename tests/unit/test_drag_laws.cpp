// Drag laws, buoyancy, exponential drag exchange and the C1 settling numbers
// against hand-computed values (docs/theory/drag.md).
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>

#include "mpm/drag_laws.h"

// Verification helpers (names, beta, exact exponential exchange, settling curves of C1): only
// the tests use them, so they live here rather than in mpm/drag_laws.h.
namespace mpm {
// ---------------------------------------------------------------- names
inline const char* drag_law_name(DragLaw law) {
  switch (law) {
    case DragLaw::ErgunWenYu: return "ergun_wenyu";
    case DragLaw::DiFelice: return "difelice";
    case DragLaw::Stokes: return "stokes";
  }
  return "unknown";
}
inline const char* drag_form_name(DragForm form) {
  return form == DragForm::Consistent ? "consistent" : "literal";
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

// Particle relaxation time m_p / K (infinite without drag).
inline double particle_relaxation_time(double m_p, double K) {
  return K > 0.0 ? m_p / K : HUGE_VAL;
}
// Exact relaxation factor of the particle-fluid slip over dt for a fluid
// of prescribed velocity: exp(-K dt / m_p).
inline double drag_relaxation_factor(double K, double dt, double m_p) {
  return std::exp(-K * dt / m_p);
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

namespace {

using mpm::DragForm;
using mpm::DragLaw;

constexpr double kPi = 3.14159265358979323846;
// Common hand-check set: water-like fluid, 1 mm sphere.
constexpr double kMu = 1e-3, kRho = 1000.0, kD = 1e-3;
const double kVp = kPi * kD * kD * kD / 6.0;  // 5.235987756e-10 m3

double rel(double a, double b) { return std::fabs(a - b) / std::fabs(b); }

TEST(DragLaws, NamesRoundTripAndRejectUnknown) {
  for (DragLaw l : {DragLaw::ErgunWenYu, DragLaw::DiFelice, DragLaw::Stokes}) {
    DragLaw back = DragLaw::Stokes == l ? DragLaw::ErgunWenYu : DragLaw::Stokes;
    ASSERT_TRUE(mpm::parse_drag_law(mpm::drag_law_name(l), back));
    EXPECT_EQ(back, l);
  }
  for (DragForm f : {DragForm::Consistent, DragForm::Literal}) {
    DragForm back = f == DragForm::Literal ? DragForm::Consistent : DragForm::Literal;
    ASSERT_TRUE(mpm::parse_drag_form(mpm::drag_form_name(f), back));
    EXPECT_EQ(back, f);
  }
  DragLaw l = DragLaw::DiFelice;
  EXPECT_FALSE(mpm::parse_drag_law("ergun", l));
  EXPECT_FALSE(mpm::parse_drag_law("", l));
  EXPECT_FALSE(mpm::parse_drag_law(nullptr, l));
  EXPECT_EQ(l, DragLaw::DiFelice);  // untouched on failure
  DragForm f = DragForm::Literal;
  EXPECT_FALSE(mpm::parse_drag_form("Consistent", f));
  EXPECT_EQ(f, DragForm::Literal);
}

TEST(DragLaws, ErgunBetaHandComputed) {
  // theta = 0.5, |u-v| = 0.01: Re = 0.5*1000*0.01*1e-3/1e-3 = 5
  // beta = mu (1-theta)/(d^2 theta) [150 (1-theta) + 1.75 Re]
  //      = 1e-3*0.5/(1e-6*0.5) * (75 + 8.75) = 1000 * 83.75 = 83750 kg/(m3 s)
  EXPECT_NEAR(mpm::drag_reynolds(kRho, kMu, kD, 0.5, 0.01), 5.0, 1e-12);
  EXPECT_NEAR(mpm::drag_beta(DragLaw::ErgunWenYu, kRho, kMu, kD, kVp, 0.5, 0.01), 83750.0, 1e-8);
  // consistent K = beta Vp/(1-theta) = 83750*5.235988e-10/0.5 = 8.770279e-5 kg/s
  EXPECT_NEAR(mpm::drag_coefficient(DragLaw::ErgunWenYu, DragForm::Consistent, kRho, kMu, kD, kVp,
                                    0.5, 0.01),
              8.770279e-5, 1e-11);
  // literal K = beta Vp = 4.385140e-5 kg/s
  EXPECT_NEAR(mpm::drag_coefficient(DragLaw::ErgunWenYu, DragForm::Literal, kRho, kMu, kD, kVp,
                                    0.5, 0.01),
              4.385140e-5, 1e-11);
  // theta = 0.4, |u-v| = 0.1: Re = 40; beta = 1e-3*0.6/(1e-6*0.4) (90 + 70) = 1500*160 = 240000
  EXPECT_NEAR(mpm::drag_beta(DragLaw::ErgunWenYu, kRho, kMu, kD, kVp, 0.4, 0.1), 240000.0, 1e-7);
  // Same as the Gidaspow form 150 (1-t)^2 mu/(t d^2) + 1.75 (1-t) rho |u|/d:
  // 150*0.36*1e-3/(0.4e-6) = 135000; 1.75*0.6*1000*0.1/1e-3 = 105000; sum 240000.
}

TEST(DragLaws, WenYuBetaHandComputed) {
  // theta = 0.9, |u-v| = 0.01: Re = 0.9*1000*0.01*1e-3/1e-3 = 9
  // 9^0.687 = exp(0.687 ln 9) = 4.524269; C_D = 24 (1 + 0.15*4.524269)/9 = 4.476442
  // 0.9^-2.7 = exp(2.7*0.1053605) = 1.329062
  // beta = 3/4 C_D mu (1-theta)/d^2 theta^-2.7 Re = 0.75*4.476442*100*1.329062*9 = 4015.89
  EXPECT_NEAR(mpm::wen_yu_cd_re(9.0) / 9.0, 4.476442, 1e-6);
  EXPECT_NEAR(mpm::drag_beta(DragLaw::ErgunWenYu, kRho, kMu, kD, kVp, 0.9, 0.01), 4015.89, 0.01);
  // theta = 0.95, |u-v| = 2: Re = 1900 > 1000 -> C_D = 0.43
  // 0.95^-2.7 = exp(2.7*0.0512933) = 1.148540
  // beta = 0.75*0.43*1e-3*0.05/1e-6 * 0.95^-2.7 * 1900 = 30637.5 * 1.148540 = 35188.4
  EXPECT_NEAR(mpm::drag_beta(DragLaw::ErgunWenYu, kRho, kMu, kD, kVp, 0.95, 2.0), 35188.4, 0.05);
}

TEST(DragLaws, ErgunWenYuSwitchAtPointEightTakesDocumentedBranch) {
  // At theta = 0.8 (Ergun side), Re = 8: beta = 1e-3*0.2/(1e-6*0.8) (30 + 14) = 11000.
  // Just above (Wen-Yu side): beta = 0.75*C_D(8)*1e-3*0.2/1e-6*0.8^-2.7*8 = 10691.9.
  // The switch jumps by -2.8 % at this Re (and by 32.88/37.5 - 1 = -12 % as Re -> 0).
  const double above = std::nextafter(0.8, 1.0);
  EXPECT_TRUE(mpm::ergun_branch(0.8));
  EXPECT_FALSE(mpm::ergun_branch(above));
  const double be = mpm::drag_beta(DragLaw::ErgunWenYu, kRho, kMu, kD, kVp, 0.8, 0.01);
  const double bw = mpm::drag_beta(DragLaw::ErgunWenYu, kRho, kMu, kD, kVp, above, 0.01);
  EXPECT_NEAR(be, 11000.0, 1e-6);
  EXPECT_NEAR(bw, 10691.94, 0.01);
  EXPECT_NEAR(bw / be - 1.0, -0.0280, 5e-4);
  // Re -> 0 ratio of the consistent coefficients: Wen-Yu 18*0.8^-2.7 = 32.880 vs Ergun 150*0.2/0.8 = 37.5
  const double ke = mpm::drag_coefficient(DragLaw::ErgunWenYu, DragForm::Consistent, kRho, kMu, kD,
                                          kVp, 0.8, 0.0);
  const double kw = mpm::drag_coefficient(DragLaw::ErgunWenYu, DragForm::Consistent, kRho, kMu, kD,
                                          kVp, above, 0.0);
  EXPECT_NEAR(ke / (kVp * kMu / (kD * kD)), 37.5, 1e-9);
  EXPECT_NEAR(kw / (kVp * kMu / (kD * kD)), 18.0 * std::pow(0.8, -2.7), 1e-6);
}

TEST(DragLaws, IsolatedLimitsConsistentAndLiteral) {
  const double stokes = 3.0 * kPi * kMu * kD;
  for (double u : {0.0, 1e-4, 0.01, 0.3}) {
    for (double th : {1.0, 1.0 - 1e-9, 1.0 - 1e-6}) {
      const double Re = mpm::drag_reynolds(kRho, kMu, kD, th, u);
      const double sn = stokes * (1.0 + 0.15 * std::pow(Re, 0.687)) * std::pow(th, -2.7);
      const double kc = mpm::drag_coefficient(DragLaw::ErgunWenYu, DragForm::Consistent, kRho,
                                              kMu, kD, kVp, th, u);
      const double kl = mpm::drag_coefficient(DragLaw::ErgunWenYu, DragForm::Literal, kRho, kMu,
                                              kD, kVp, th, u);
      EXPECT_TRUE(std::isfinite(kc) && std::isfinite(kl));
      EXPECT_NEAR(kc / sn, 1.0, 1e-12) << "u=" << u << " theta=" << th;
      EXPECT_NEAR(kl, (1.0 - th) * kc, 1e-15 * kc);
      EXPECT_LE(kl, 1.01e-6 * kc);  // literal -> 0 linearly in 1 - theta
    }
  }
  // exactly at theta = 1 the consistent form is Schiller-Naumann, the literal form zero
  const double Re1 = mpm::drag_reynolds(kRho, kMu, kD, 1.0, 0.01);  // = 10
  EXPECT_NEAR(mpm::drag_coefficient(DragLaw::ErgunWenYu, DragForm::Consistent, kRho, kMu, kD, kVp,
                                    1.0, 0.01),
              stokes * (1.0 + 0.15 * std::pow(Re1, 0.687)), 1e-15);
  EXPECT_EQ(mpm::drag_coefficient(DragLaw::ErgunWenYu, DragForm::Literal, kRho, kMu, kD, kVp, 1.0,
                                  0.01),
            0.0);
  // Stokes law: 3 pi mu d in the consistent form at any theta
  EXPECT_NEAR(mpm::drag_coefficient(DragLaw::Stokes, DragForm::Consistent, kRho, kMu, kD, kVp,
                                    0.6, 1.0),
              stokes, 1e-18);
}

TEST(DragLaws, NoNanAtZeroSlipOrDegenerateTheta) {
  for (DragLaw l : {DragLaw::ErgunWenYu, DragLaw::DiFelice, DragLaw::Stokes})
    for (DragForm f : {DragForm::Consistent, DragForm::Literal})
      for (double th : {1.0, 1.5, 0.8, 0.5, 0.3, 0.0, -1.0, std::nan("")}) {
        const double K = mpm::drag_coefficient(l, f, kRho, kMu, kD, kVp, th, 0.0);
        EXPECT_TRUE(std::isfinite(K) && K >= 0.0)
            << mpm::drag_law_name(l) << " " << mpm::drag_form_name(f) << " theta=" << th;
      }
  // clamp: below theta_min behaves as theta_min, above 1 as 1
  EXPECT_EQ(mpm::clamp_fluid_fraction(0.1), mpm::kDragThetaMin);
  EXPECT_EQ(mpm::clamp_fluid_fraction(std::nan("")), mpm::kDragThetaMin);
  EXPECT_EQ(mpm::clamp_fluid_fraction(1.2), 1.0);
  EXPECT_EQ(mpm::clamp_fluid_fraction(0.1, 0.05), 0.1);
  EXPECT_EQ(mpm::drag_coefficient(DragLaw::ErgunWenYu, DragForm::Consistent, kRho, kMu, kD, kVp,
                                  0.1, 0.01),
            mpm::drag_coefficient(DragLaw::ErgunWenYu, DragForm::Consistent, kRho, kMu, kD, kVp,
                                  0.3, 0.01));
  // Re = 0 analytic limits: C_D Re -> 24 (Wen-Yu), 23.04 (Di Felice); chi -> 3.7
  EXPECT_EQ(mpm::wen_yu_cd_re(0.0), 24.0);
  EXPECT_NEAR(mpm::di_felice_cd_re(0.0), 23.04, 1e-12);
  EXPECT_EQ(mpm::di_felice_chi(0.0), 3.7);
  EXPECT_NEAR(mpm::drag_coefficient(DragLaw::DiFelice, DragForm::Consistent, kRho, kMu, kD, kVp,
                                    1.0, 0.0),
              2.88 * kPi * kMu * kD, 1e-15);
}

TEST(DragLaws, DiFeliceSingleSphereAndVoidageFunction) {
  // theta = 1: F = 0.5 C_D rho (pi d^2/4) |u| u with C_D = (0.63 + 4.8/sqrt(Re))^2.
  for (double u : {1e-3, 0.01, 0.1, 1.0}) {
    const double Re = kRho * u * kD / kMu;
    const double cd = std::pow(0.63 + 4.8 / std::sqrt(Re), 2);
    const double K = mpm::drag_coefficient(DragLaw::DiFelice, DragForm::Consistent, kRho, kMu, kD,
                                           kVp, 1.0, u);
    EXPECT_NEAR(K * u / (0.5 * kRho * kPi * kD * kD / 4.0 * u * u), cd, 1e-12 * cd);
  }
  // chi: minimum 3.05 at Re = 10^1.5; Re = 1: 3.7 - 0.65 exp(-1.125) = 3.488979
  EXPECT_NEAR(mpm::di_felice_chi(std::pow(10.0, 1.5)), 3.05, 1e-14);
  EXPECT_NEAR(mpm::di_felice_chi(1.0), 3.7 - 0.65 * std::exp(-1.125), 1e-14);
  // theta = 0.6, |u-v| = 0.01: Re = 6, C_D = (0.63 + 4.8/2.449490)^2 = 2.589592^2 = 6.705986,
  // chi = 3.7 - 0.65 exp(-(1.5 - 0.778151)^2/2) = 3.7 - 0.65*0.770641 = 3.199083;
  // K = 0.5 C_D rho pi d^2/4 theta^(2-chi) |u-v| = 2.633434e-5 * 0.6^-1.199083
  //   = 2.633434e-5 * 1.845080 = 4.858897e-5 kg/s
  const double Re = 6.0;
  const double cd = std::pow(0.63 + 4.8 / std::sqrt(Re), 2);
  const double chi = 3.7 - 0.65 * std::exp(-0.5 * std::pow(1.5 - std::log10(Re), 2));
  EXPECT_NEAR(cd, 6.705986, 1e-6);
  EXPECT_NEAR(chi, 3.199083, 1e-6);
  EXPECT_NEAR(mpm::drag_coefficient(DragLaw::DiFelice, DragForm::Consistent, kRho, kMu, kD, kVp,
                                    0.6, 0.01),
              4.858897e-5, 2e-11);
  const double want = 0.5 * cd * kRho * kPi * kD * kD / 4.0 * std::pow(0.6, 2.0 - chi) * 0.01;
  EXPECT_NEAR(mpm::drag_coefficient(DragLaw::DiFelice, DragForm::Consistent, kRho, kMu, kD, kVp,
                                    0.6, 0.01),
              want, 1e-12 * want);
  EXPECT_NEAR(mpm::drag_coefficient(DragLaw::DiFelice, DragForm::Literal, kRho, kMu, kD, kVp, 0.6,
                                    0.01),
              0.4 * want, 1e-12 * want);
}

TEST(DragLaws, ForceAndPressureGradientForce) {
  const double u[3] = {1.0, 0.0, -2.0}, v[3] = {0.5, 1.0, -2.0};
  double F[3];
  mpm::drag_force(2.0, u, v, F);
  EXPECT_DOUBLE_EQ(F[0], 1.0);
  EXPECT_DOUBLE_EQ(F[1], -2.0);
  EXPECT_DOUBLE_EQ(F[2], 0.0);
  // hydrostatic grad p = rho_f g (g = (0,0,-9.81)): -Vp grad p = Archimedes, upward
  const double gradp[3] = {0.0, 0.0, -kRho * 9.81};
  mpm::pressure_gradient_force(kVp, gradp, F);
  EXPECT_EQ(F[0], 0.0);
  EXPECT_NEAR(F[2], kRho * kVp * 9.81, 1e-18);
}

TEST(DragLaws, C1TerminalVelocities) {
  // CASES.md C1: d = 100 um, rho_p = 3000, rho_f = 10, nu = 1e-5 (mu = 1e-4), g = 9.81.
  // Net weight (rho_p - rho_f) Vp g = 2990 * 5.235988e-13 * 9.81 = 1.535815e-8 N
  // Stokes: v = F/(3 pi mu d) = 1.535815e-8 / 9.424778e-8 = 0.162955 m/s
  // Schiller-Naumann: v = 0.162955 / (1 + 0.15 Re^0.687), Re = v d/nu = 10 v -> 0.137337, Re 1.3734
  const double d = 100e-6, rp = 3000.0, rf = 10.0, mu = 1e-5 * rf, g = 9.81;
  const double vs = mpm::terminal_velocity(DragLaw::Stokes, DragForm::Consistent, rp, rf, mu, d, g);
  const double vw =
      mpm::terminal_velocity(DragLaw::ErgunWenYu, DragForm::Consistent, rp, rf, mu, d, g);
  EXPECT_LT(rel(vs, 0.163), 0.005);
  EXPECT_LT(rel(vw, 0.1373), 0.005);
  EXPECT_NEAR(vs, 0.162955, 1e-6);
  const double Re = rf * vw * d / mu;
  EXPECT_NEAR(Re, 1.3735, 2e-4);
  EXPECT_NEAR(vw * (1.0 + 0.15 * std::pow(Re, 0.687)), vs, 1e-12);  // exact root
  // Di Felice single sphere (C_D = (0.63+4.8/sqrt Re)^2): 0.12861 m/s, Re 1.286 (its C_D is
  // larger than Schiller-Naumann at Re ~ 1)
  const double vd = mpm::terminal_velocity(DragLaw::DiFelice, DragForm::Consistent, rp, rf, mu, d, g);
  const double Red = rf * vd * d / mu;
  EXPECT_NEAR(vd, 0.12861, 1e-5);
  EXPECT_NEAR(0.5 * mpm::di_felice_cd_re(Red) / Red * rf * kPi * d * d / 4.0 * vd * vd,
              1.535815e-8, 1e-13);
  // neutrally buoyant stays at rest, lighter rises, literal form has no isolated drag
  EXPECT_EQ(mpm::terminal_velocity(DragLaw::ErgunWenYu, DragForm::Consistent, rf, rf, mu, d, g), 0.0);
  EXPECT_LT(mpm::terminal_velocity(DragLaw::ErgunWenYu, DragForm::Consistent, 5.0, rf, mu, d, g), 0.0);
  EXPECT_TRUE(std::isinf(
      mpm::terminal_velocity(DragLaw::ErgunWenYu, DragForm::Literal, rp, rf, mu, d, g)));
  // hindered settling: at theta = 0.9 slower than isolated
  EXPECT_LT(mpm::terminal_velocity(DragLaw::ErgunWenYu, DragForm::Consistent, rp, rf, mu, d, g, 0.9),
            vw);
}

TEST(DragLaws, C1RelaxationCurve) {
  const double d = 100e-6, rp = 3000.0, rf = 10.0, mu = 1e-4, g = 9.81;
  const double tau = mpm::stokes_relaxation_time(rp, mu, d);  // 3000*1e-8/(18e-4) = 0.0166667 s
  EXPECT_NEAR(tau, 1.0 / 60.0, 1e-15);
  const double vt = mpm::terminal_velocity(DragLaw::Stokes, DragForm::Consistent, rp, rf, mu, d, g);
  for (double t : {0.005, 1.0 / 60.0, 0.05, 0.2}) {
    const double ode = mpm::settling_velocity(DragLaw::Stokes, DragForm::Consistent, rp, rf, mu, d,
                                              g, t);
    EXPECT_NEAR(ode, mpm::relaxation_velocity(t, 0.0, vt, tau), 1e-9 * vt) << t;
  }
  EXPECT_NEAR(mpm::relaxation_velocity(tau, 0.0, vt, tau), vt * (1.0 - std::exp(-1.0)), 1e-15);
  // nonlinear law: approaches its terminal velocity
  const double vw =
      mpm::terminal_velocity(DragLaw::ErgunWenYu, DragForm::Consistent, rp, rf, mu, d, g);
  EXPECT_NEAR(mpm::settling_velocity(DragLaw::ErgunWenYu, DragForm::Consistent, rp, rf, mu, d, g,
                                     0.5),
              vw, 1e-8 * vw);
}

TEST(DragLaws, ExponentialExchangeConservesMomentumAndRelaxes) {
  const double mp = 1.4e-9, mf = 3.0e-9, K = 2.0e-6;
  const double lam = K * (1.0 / mp + 1.0 / mf);
  double v[3] = {0.0, 0.2, -0.1}, u[3] = {0.05, -0.3, 0.4};
  double P0[3];
  for (int a = 0; a < 3; ++a) P0[a] = mp * v[a] + mf * u[a];
  const double dt = 1e-3;  // lambda dt = 2.095: beyond the monotone explicit range
  EXPECT_GT(dt, 0.5 * mpm::drag_explicit_dt_limit(K, mp, mf));
  double w0[3];
  for (int a = 0; a < 3; ++a) w0[a] = u[a] - v[a];
  double J[3];
  mpm::drag_exchange_impulse(v, u, mp, mf, K, dt, J);
  for (int a = 0; a < 3; ++a) {
    v[a] += J[a] / mp;
    u[a] -= J[a] / mf;
    EXPECT_NEAR(mp * v[a] + mf * u[a], P0[a], 1e-16 * (mp + mf));
    EXPECT_NEAR(u[a] - v[a], w0[a] * std::exp(-lam * dt), 1e-14);
  }
  for (int n = 0; n < 50; ++n) {
    mpm::drag_exchange_impulse(v, u, mp, mf, K, dt, J);
    for (int a = 0; a < 3; ++a) { v[a] += J[a] / mp; u[a] -= J[a] / mf; }
  }
  for (int a = 0; a < 3; ++a) {
    const double vc = P0[a] / (mp + mf);  // common velocity
    EXPECT_NEAR(v[a], vc, 1e-15);
    EXPECT_NEAR(u[a], vc, 1e-15);
    EXPECT_NEAR(mp * v[a] + mf * u[a], P0[a], 1e-16 * (mp + mf));
  }
  // prescribed fluid (m_f infinite): slip factor exp(-K dt/m_p)
  const double v1[3] = {0.0, 0.0, 1.0}, u1[3] = {0.0, 0.0, 0.0};
  mpm::drag_exchange_impulse(v1, u1, mp, HUGE_VAL, K, dt, J);
  EXPECT_NEAR(1.0 + J[2] / mp, mpm::drag_relaxation_factor(K, dt, mp), 1e-15);
  EXPECT_NEAR(mpm::drag_relaxation_factor(K, dt, mp), std::exp(-K * dt / mp), 1e-16);
  // K = 0 or dt -> 0: no exchange / explicit Euler limit
  mpm::drag_exchange_impulse(v1, u1, mp, mf, 0.0, dt, J);
  EXPECT_EQ(J[2], 0.0);
  mpm::drag_exchange_impulse(v1, u1, mp, mf, K, 1e-12, J);
  EXPECT_NEAR(J[2], -K * 1e-12, 1e-8 * K * 1e-12);  // lambda dt = 2e-9
}

TEST(DragLaws, ExponentialExchangeWithConstantForcesGivesExactTerminalVelocity) {
  // Stiff settling: lambda dt = 100. Particle kicked by a_p (gravity - buoyancy), fluid fixed.
  const double mp = 1e-9, K = 1e-4, dt = 1.0, ap[3] = {0.0, 0.0, -9.0}, af[3] = {0, 0, 0};
  const double uf[3] = {0, 0, 0};
  double v[3] = {0, 0, 0}, J[3];
  for (int n = 0; n < 3; ++n) {
    mpm::drag_exchange_impulse(v, uf, mp, HUGE_VAL, K, dt, J, ap, af);
    for (int a = 0; a < 3; ++a) v[a] += ap[a] * dt + J[a] / mp;
  }
  EXPECT_NEAR(v[2], mp * ap[2] / K, 1e-10 * std::fabs(mp * ap[2] / K));  // = F/K
  // small lambda dt: matches the exact two-body solution (phi functions stable)
  const double mp2 = 2.0, mf2 = 3.0, K2 = 1e-9, dt2 = 0.1, ap2[3] = {1, 0, 0}, af2[3] = {0, 2, 0};
  const double v2[3] = {0, 0, 0}, u2[3] = {1, 0, 0};
  mpm::drag_exchange_impulse(v2, u2, mp2, mf2, K2, dt2, J, ap2, af2);
  // J ~ K dt (w0 + (a_f - a_p) dt / 2) for lambda dt -> 0
  EXPECT_NEAR(J[0], K2 * dt2 * (1.0 - 0.5 * dt2), 1e-6 * K2 * dt2);
  EXPECT_NEAR(J[1], K2 * dt2 * (0.5 * 2.0 * dt2), 1e-6 * K2 * dt2);
}

TEST(DragLaws, ExplicitStabilityLimit) {
  const double mp = 2.0, mf = 6.0, K = 3.0;
  // 2 / (3 (1/2 + 1/6)) = 2 / 2 = 1
  EXPECT_DOUBLE_EQ(mpm::drag_explicit_dt_limit(K, mp, mf), 1.0);
  EXPECT_DOUBLE_EQ(mpm::drag_explicit_dt_limit(K, mp), 2.0 * mp / K);  // prescribed fluid
  EXPECT_DOUBLE_EQ(mpm::particle_relaxation_time(mp, K), mp / K);
  EXPECT_TRUE(std::isinf(mpm::drag_explicit_dt_limit(0.0, mp, mf)));
  // explicit Euler slip amplification 1 - lambda dt: |.| < 1 just below the limit, > 1 above
  const double lam = K * (1.0 / mp + 1.0 / mf);
  const double lim = mpm::drag_explicit_dt_limit(K, mp, mf);
  EXPECT_LT(std::fabs(1.0 - lam * 0.99 * lim), 1.0);
  EXPECT_GT(std::fabs(1.0 - lam * 1.01 * lim), 1.0);
}

TEST(DragLaws, ImplicitImpulseSteadySlipUnderLeapfrog) {
  // A very stiff particle (K dt / m = 500) under a constant acceleration a,
  // advanced by leapfrog with the impulse held over the step, must settle at
  // the physical slip -m a / K (the terminal velocity), neither drift nor ring.
  const double m = 1e-9, K = 5e-3, dt = 1e-4, a = -9.81;
  const double u[3] = {0, 0, 0}, ap[3] = {0, 0, a};
  double v[3] = {0, 0, 0};
  for (int n = 0; n < 200; ++n) {
    double J[3];
    mpm::drag_implicit_impulse(v, u, m, HUGE_VAL, K, dt, J, ap, nullptr);
    for (int c = 0; c < 3; ++c) v[c] += ap[c] * dt + J[c] / m;
  }
  EXPECT_NEAR(v[2], m * a / K, 1e-12);
  // two-body: total momentum conserved to round-off, relative slip -> steady value
  const double mp = 2.0, mf = 3.0, Kb = 50.0, h = 0.1;
  double vp[3] = {1, 0, -2}, uf[3] = {0, 4, 0};
  const double p0 = mp * vp[0] + mf * uf[0];
  for (int n = 0; n < 50; ++n) {
    double J[3];
    mpm::drag_implicit_impulse(vp, uf, mp, mf, Kb, h, J);
    for (int c = 0; c < 3; ++c) {
      vp[c] += J[c] / mp;
      uf[c] -= J[c] / mf;
    }
  }
  EXPECT_NEAR(mp * vp[0] + mf * uf[0], p0, 1e-12);
  EXPECT_NEAR(vp[1], uf[1], 1e-9);
}

}  // namespace

// The share of a sphere below a plane (grains at the free surface): against the cap volume
// pi h^2 (3 r - h) / 3 integrated independently (slices of the sphere), exactly 1 / 0 beyond the
// sphere, monotone, and f(d) + f(-d) = 1 (the cap above and the cap below make the sphere).
TEST(DragLaws, ImmersedFractionIsTheCapBelowThePlane) {
  const double r = 0.003;
  const double V = 4.0 / 3.0 * M_PI * r * r * r;
  for (double d : {-0.0029, -0.002, -0.001, 0.0, 0.0005, 0.0015, 0.0027}) {
    // the sphere's cross-sections pi (r^2 - z^2) for z from -r up to d (midpoint rule)
    const int n = 200000;
    const double top = std::min(d, r), dz = (top + r) / n;
    double v = 0.0;
    for (int i = 0; i < n; ++i) {
      const double z = -r + (i + 0.5) * dz;
      v += M_PI * (r * r - z * z) * dz;
    }
    EXPECT_NEAR(mpm::immersed_fraction(d, r), v / V, 1e-9) << "d = " << d;
    EXPECT_NEAR(mpm::immersed_fraction(d, r) + mpm::immersed_fraction(-d, r), 1.0, 1e-14) << "d = " << d;
  }
  EXPECT_EQ(mpm::immersed_fraction(r, r), 1.0);
  EXPECT_EQ(mpm::immersed_fraction(0.01, r), 1.0);
  EXPECT_EQ(mpm::immersed_fraction(-r, r), 0.0);
  EXPECT_EQ(mpm::immersed_fraction(-0.01, r), 0.0);
  EXPECT_DOUBLE_EQ(mpm::immersed_fraction(0.0, r), 0.5);
  double last = 0.0;
  for (int i = 0; i <= 100; ++i) {
    const double f = mpm::immersed_fraction(-r + 2.0 * r * i / 100.0, r);
    EXPECT_GE(f, last);
    last = f;
  }
}
