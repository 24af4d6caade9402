// Drag laws, buoyancy, exponential drag exchange and the C1 settling numbers
// against hand-computed values (docs/drag.md).
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>

#include "mpm/drag_laws.h"

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
