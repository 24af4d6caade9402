// Solid conduction after onset and the moving fronts of a run (class Drill): (3-25),
// (3-29)..(3-40), (4-13)..(4-15); the a-priori step limit of (4-14).
#include "laser_drill_state.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace laser {
namespace detail {

double Drill::solid_gradient_mean(Node& n, double ta, double tb) const {
  const double ti = G_.theta_i;
  switch (cfg_.solid) {
    case SolidModel::Exact: {
      const double sa = (ta - n.tau_m) / n.tau_m, sb = (tb - n.tau_m) / n.tau_m;
      return ti / std::sqrt(G_.Na * n.tau_m) * exact_->gradient_mean(std::max(sa, 0.0), sb, n.solid);
    }
    case SolidModel::Shifted:
      return stefan_gradient_mean(ti, G_.Na, n.tau_m, ta, tb, cfg_.shift);
    case SolidModel::Stefan:
      return stefan_gradient_mean(ti, G_.Na, n.tau_m, ta, tb, kTau0OverTauM);
  }
  return 0.0;
}

void Drill::book_beam(const Node& n, double ta, double tb) {
  const double dt_pre = std::max(0.0, std::min(tb, n.tau_m) - ta);
  const double beam = cfg_.I0 * gaussian_beam(n.xi) * n.area;  // W
  res_.energy.laser_nodal += beam * (tb - ta) * G_.t_scale;
  res_.energy.solid_premelt += beam * dt_pre * G_.t_scale;
}

// Slope factor J = sqrt(1 + S2'^2) and curvature factor (3-37) of the melting
// front from the fronts at the start of the step (3-38).
Drill::Geometry Drill::front_geometry(int i, const std::vector<double>& S2old, double tb) {
  const int N = static_cast<int>(nodes_.size());
  const double h = cfg_.dxi;
  double s2x = 0.0, s2xx = 0.0;
  if (i == 0) {
    s2xx = 2.0 * (S2old[1] - S2old[0]) / (h * h);
  } else if (i < N - 1) {
    s2x = (S2old[i + 1] - S2old[i - 1]) / (2 * h);
    s2xx = (S2old[i + 1] - 2 * S2old[i] + S2old[i - 1]) / (h * h);
  }
  Geometry geo;
  geo.J = std::sqrt(1.0 + s2x * s2x);
  if (cfg_.curvature) {
    const double a = -s2xx / (geo.J * geo.J * geo.J);
    const double d = h * geo.J;
    if (std::fabs(a * d) >= 2.0 && res_.curvature_clamps++ == 0)
      first_clamp_ = "first at xi = " + fmt(nodes_[i].xi, 4) + ", t = " + fmt(tb * G_.t_scale, 4) + " s";
    geo.Cc = cfg_.curvature_form == CurvatureForm::Text ? curvature_factor(a, d) : curvature_factor_conduction(a, d);
  }
  return geo;
}

// Backward Euler in g: g_new = g_old + dtau R(g_new), R = dS2 - dS1 + v, with the solid
// gradient (its mean over the step), curvature, the flow and its heat flux b2 g frozen over the
// step; trapezoidal (wt = 1/2): g_new = g_old + dtau (R(g_old) + R(g_new))/2. The right side
// decreases with g, so the root is unique and bracketed.
void Drill::solve_implicit_thickness(Node& n, const Geometry& geo, double grad_n, double dtn, double wt) {
  // The flow's part of the layer's gradients, b2 g (half the heat the flow
  // carries sideways, 2 b2 g), is what the last step's (4-27) determined and is
  // held over the step; holding b2 itself would let b2 g grow with g_new.
  const double b2g = n.b2 * n.g;
  auto b2_at = [&](double g) { return g > 0.0 ? b2g / g : 0.0; };
  // the root of the last evaluation (its state: from) starts the next one, and its state is
  // kept for the root
  const InterfaceState* from = &n.itf;
  double g_last = -1.0;
  InterfaceState st, last;
  auto rate_of = [&](const InterfaceState& s) {
    const double d2 = std::max(melting_rate(G_, geo.Cc, grad_n, geo.J, s.grad_bottom, cfg_.moving_origin), 0.0);
    const double d1 = std::max(recession_rate(G_, n.xi, s), 0.0);
    return d2 - d1 + n.v;
  };
  auto rate = [&](double g) {
    st = solve_interface(G_, n.xi, g, b2_at(g), advected_, *from);
    g_last = g;
    if (st.theta_sat > 0.0) {
      last = st;
      from = &last;
    }
    return rate_of(st);
  };
  const double g_old = n.g;
  // R(g_old) from the state the step started with (solve_interfaces: (4-29) at g_old, b2)
  const double R0 = rate_of(n.itf), g_p = g_old + dtn * R0;
  auto F = [&](double g) { return g - g_old - dtn * (wt == 1.0 ? rate(g) : (1.0 - wt) * R0 + wt * rate(g)); };
  // F rises with g; the explicit predictor g_p = g_old + dtn R(g_old) and g_old bracket
  // the root (F(g_old) = -dtn R(g_old), F(g_p) = dtn (R(g_old) - R(g_p))), a bracket
  // narrower than [0, g_p] that saves most of the iterations (each one solves (4-29));
  // for the trapezoidal rule F(g_p) = dtn wt (R(g_old) - R(g_p)), the same signs.
  double lo = std::min(g_old, std::max(g_p, 0.0)), hi = std::max(g_old, g_p);
  double Flo = lo == g_old ? -dtn * R0 : F(lo), Fhi = hi == g_old ? -dtn * R0 : F(hi);
  if (Flo > 0.0) { lo = 0.0; Flo = F(0.0); }  // not monotone here: the wide bracket
  for (int k = 0; Fhi < 0.0 && k < 60; ++k) { hi = 2.0 * hi + 1e-12; Fhi = F(hi); }
  double g_new;
  if (Flo >= 0.0) {
    g_new = lo;  // lo = 0: the layer is used up within the step
  } else {
    // F' >= 1 (R does not rise with g): |F| <= tol puts g within tol of the root
    const double tol = 1e-12 * std::max(hi, 1e-12);
    g_new = illinois_root(F, lo, hi, Flo, Fhi, tol, 200, tol).x;
  }
  n.b2 = b2_at(g_new);
  n.itf = g_new == g_last ? st : solve_interface(G_, n.xi, g_new, n.b2, advected_, *from);
}

// (3-40) melting and (3-25) recession rates; a negative melting rate is
// clamped to 0 and the solid demand it leaves undelivered over dtn is booked.
Drill::Rates Drill::front_rates(const Node& n, const Geometry& geo, double grad_n, double dtn) {
  Rates r;
  r.drive = geo.Cc * grad_n * geo.J + G_.k * n.itf.grad_bottom;  // right side of (3-40)
  r.dS2 = melting_rate(G_, geo.Cc, grad_n, geo.J, n.itf.grad_bottom, cfg_.moving_origin);
  if (r.dS2 < 0.0) {
    ++res_.melt_rate_clamps;
    const double qscale_s = cfg_.mat.ks * G_.dT / cfg_.R;
    res_.energy.clamp_defect += r.drive * qscale_s * n.area * dtn * G_.t_scale;
    r.dS2 = 0.0;
  }
  r.dS1 = std::max(recession_rate(G_, n.xi, n.itf), 0.0);
  return r;
}

// Stability of the explicit update (4-14): lambda = -d(dg/dtau)/dg. The text's
// linear layer has it in closed form; the advected layer by a difference in g.
void Drill::check_stability(Node& n, const Geometry& geo, double grad_n, const Rates& r, double dtn,
                            double tb) {
  if (cfg_.implicit_melt || !(n.itf.theta_sat > 0.0) || !(n.g > 0.0)) return;
  double lambda;
  if (!advected_) {
    const double L = (1.0 / (G_.Ste * G_.Nc) - geo.Cc * (cfg_.moving_origin ? G_.theta_i : 0.0)) / G_.Na;
    double dres;
    interface_residual(G_, n.itf.phi, n.xi, n.g, n.b2, &dres);
    const double dres_dg =
        -G_.kprime * (n.itf.phi - G_.theta_m) / (n.g * n.g * (1.0 - G_.theta_m)) + G_.kprime * n.b2;
    const double dtheta_dg = -dres_dg / dres / (1.0 - G_.theta_m);
    const double dq = n.itf.theta_sat / (n.g * n.g) - dtheta_dg / n.g;  // -d(theta/g)/dg
    lambda = (G_.k / L + G_.hls_hlv * G_.Ste) * dq;
  } else {
    // one Newton step from the current root gives phi(g + dg) to O(dg^2)
    const double dg = 1e-6 * n.g;
    double dres;
    const double res = advected_residual(G_, n.itf.phi, n.xi, n.g + dg, n.b2, &dres);
    const InterfaceState st = interface_at(G_, n.itf.phi - res / dres, n.g + dg, n.b2, true);
    const double r0 = melting_rate(G_, geo.Cc, grad_n, geo.J, n.itf.grad_bottom, cfg_.moving_origin) -
                      recession_rate(G_, n.xi, n.itf);
    const double r1 = melting_rate(G_, geo.Cc, grad_n, geo.J, st.grad_bottom, cfg_.moving_origin) -
                      recession_rate(G_, n.xi, st);
    lambda = -(r1 - r0) / dg;
  }
  lambda_max_ = std::max(lambda_max_, lambda);
  // lambda dtau > 2 makes the update overshoot; it is an instability once g
  // oscillates (a layer only steps old, lambda ~ 1/g^2, may overshoot once)
  const double dg = r.dS2 - r.dS1 + n.v;
  n.flips = (lambda * dtn > 2.0 && dg * n.last_dg < 0.0) ? n.flips + 1 : 0;
  n.last_dg = dg;
  if (n.flips >= kUnstableFlips && !res_.unstable) {
    res_.unstable = true;
    res_.message = "melt thickness update (4-14) unstable at xi = " + fmt(n.xi, 4) + ", t = " +
                   fmt(tb * G_.t_scale, 4) + " s: lambda*dtau = " + fmt(lambda * dtn, 4) + " > 2";
  }
}

// Energy terms [J] of the model's own balance (L3 of CASES.md).
// dtn: the part of the step these rates hold for; content_share: the share of the layer's
// content change booked with them (1, or 1/2 for each end of a trapezoidal step).
void Drill::book_energy(const Node& n, const Geometry& geo, double grad_n, const Rates& r, double dtn,
                        double content_share) {
  Energy& E = res_.energy;
  const Material& m = cfg_.mat;
  const double qscale_l = m.kl * G_.dT / cfg_.R;  // W/m2 per unit nondim gradient
  const double qscale_s = m.ks * G_.dT / cfg_.R;
  const double dts = dtn * G_.t_scale;
  const double theta_mo = cfg_.moving_origin ? G_.theta_i : 0.0;
  E.solid_conduction += -geo.Cc * grad_n * geo.J * qscale_s * n.area * dts;
  E.solid_preheat += -geo.Cc * theta_mo * G_.dT * m.rho * m.cps * r.dS2 * G_.v_scale * n.area * dts;
  E.melt_latent += m.rho * m.hls * r.dS2 * G_.v_scale * n.area * dts;
  const double T = n.itf.phi * m.Tsat0;
  const double jv = evaporation_molar_flux(n.itf.p_pa, T, m.M);
  E.vapour_latent += jv * m.M * m.hlv * n.area * dts;
  const double Vv = vapour_velocity(T, m.M);
  E.vapour_kinetic += 0.5 * jv * m.M * Vv * Vv * n.area * dts;
  // what the advected layer absorbs between its faces, w theta_sat, heats the
  // liquid on its way to the surface; the rest is carried sideways by the flow
  const double sensible = advected_ ? n.itf.w * n.itf.theta_sat : 0.0;
  E.melt_sensible += sensible * qscale_l * n.area * dts;
  // --melt-content transient: of the flow's 2 b2 g (determined by the last march and held
  // over this step), the part that changed the layer's own heat content stays in the column
  const double content = content_share * n.dH * m.rho * m.cpl * G_.dT * cfg_.R * n.area;
  E.melt_content += content;
  E.flow_advected += (n.itf.grad_top - n.itf.grad_bottom - sensible) * qscale_l * n.area * dts - content;
}

// (3-40), (3-25), (4-14), (4-15)
void Drill::move_fronts(Node& n, const Rates& r, double dtn) {
  n.dS2 = r.dS2;
  n.dS1 = r.dS1;
  n.S2 += r.dS2 * dtn;
  n.S1 += r.dS1 * dtn;
  n.S1flow += -n.v * dtn;
  if (cfg_.melt_flow == MeltFlow::Text && n.v > 0.0) n.V_in += n.v * dtn;
  n.g += (r.dS2 - r.dS1 + n.v) * dtn;
  if (n.g < 0.0) {
    ++res_.melt_clamps;
    if (cfg_.melt_flow == MeltFlow::Conservative) {
      // vaporization cannot take more melt than there is: the recession of
      // this step is cut to the melt available (booked, the volume is kept)
      n.S1 += n.g;
      res_.vaporization_cut += -n.g * cfg_.R * n.area;
    }
    n.g = 0.0;
  }
}

// Trapezoidal step of one column: the fronts S1, S2 and g advance with the mean of the rates
// at the start state (solve_interfaces) and at the end state (the root of the trapezoidal
// g-equation); each end books half of the step's energy terms, so the model's balance holds
// as for the other updates (both states satisfy (4-29)).
void Drill::advance_trapezoidal(Node& n, const Geometry& geo, double grad_n, double dtn) {
  const Rates r0 = front_rates(n, geo, grad_n, 0.5 * dtn);
  book_energy(n, geo, grad_n, r0, 0.5 * dtn, 0.5);
  solve_implicit_thickness(n, geo, grad_n, dtn, 0.5);
  Rates r = front_rates(n, geo, grad_n, 0.5 * dtn);
  book_energy(n, geo, grad_n, r, 0.5 * dtn, 0.5);
  r.dS2 = 0.5 * (r0.dS2 + r.dS2);
  r.dS1 = 0.5 * (r0.dS1 + r.dS1);
  move_fronts(n, r, dtn);
}

void Drill::advance_interfaces(double ta, double tb) {
  const int N = static_cast<int>(nodes_.size());
  std::vector<double> S2old(N);
  for (int i = 0; i < N; ++i) S2old[i] = nodes_[i].S2;
  for (int i = 0; i < N; ++i) {
    Node& n = nodes_[i];
    book_beam(n, ta, tb);
    if (!n.molten) continue;
    const double t0 = node_ta(n, ta);
    const double dtn = tb - t0;
    if (!(dtn > 0.0)) continue;
    const Geometry geo = front_geometry(i, S2old, tb);
    const double grad_n = solid_gradient_mean(n, t0, tb);
    // trapezoidal rule for a column molten over the whole step with a layer; its first
    // step (onset inside the step, the layer's stiffest state) and a used-up layer take
    // backward Euler, which damps what the trapezoidal rule would carry on as an oscillation
    if (cfg_.trapezoidal_melt && t0 == ta && n.g > 0.0) {
      advance_trapezoidal(n, geo, grad_n, dtn);
      continue;
    }
    if (cfg_.implicit_melt) solve_implicit_thickness(n, geo, grad_n, dtn, 1.0);
    const Rates r = front_rates(n, geo, grad_n, dtn);
    check_stability(n, geo, grad_n, r, dtn, tb);
    book_energy(n, geo, grad_n, r, dtn, 1.0);
    move_fronts(n, r, dtn);
  }
}

}  // namespace detail

namespace {
// Advected layer: the quasi-steady centre state dS2 = dS1 (solid gradient
// decayed) is found numerically in g, and lambda by a difference in g.
double advected_step_limit(const Config& cfg, const Groups& G) {
  auto rate = [&](double g) {
    const InterfaceState st = solve_interface(G, 0.0, g, 0.0, true);
    return melting_rate(G, 1.0, 0.0, 1.0, st.grad_bottom, cfg.moving_origin) - recession_rate(G, 0.0, st);
  };
  double lo = 1e-8, hi = 1e-8;
  if (!(rate(lo) > 0.0)) return 0.0;
  for (int k = 0; k < 200 && rate(hi) > 0.0; ++k) hi *= 1.5;
  if (rate(hi) > 0.0) return 0.0;
  for (int k = 0; k < 200 && hi - lo > 1e-10 * hi; ++k) {
    const double mid = 0.5 * (lo + hi);
    (rate(mid) > 0.0 ? lo : hi) = mid;
  }
  const double g = 0.5 * (lo + hi), dg = 1e-6 * g;
  const double lambda = -(rate(g + dg) - rate(g)) / dg;
  return lambda > 0.0 ? 2.0 / lambda * G.t_scale : 0.0;
}
}  // namespace

double explicit_step_limit(const Config& cfg) {
  const Groups G = make_groups(cfg.mat, cfg.absorbed_I0(), cfg.R);
  if (cfg.melt_energy == MeltEnergy::Advected) return advected_step_limit(cfg, G);
  const double L0 = 1.0 / (G.Ste * G.Nc) - G.theta_i;
  // surface state for a conduction gradient q into the melt: vapour term = 1 - k' q
  auto phi_of_q = [&](double q) {
    const double target = 1.0 - G.kprime * q;
    auto fdf = [&](double phi, double& f, double& df) {
      const double v = std::exp(G.Hlv * (1.0 - 1.0 / phi)) * (1.0 + G.Lambda * phi) / (G.Iprime * std::sqrt(phi));
      f = v - target;
      df = v * (G.Hlv / (phi * phi) + G.Lambda / (1.0 + G.Lambda * phi) - 0.5 / phi);
    };
    return safe_newton(fdf, G.theta_m, 2.0 * G.Hlv, 1e-14).x;
  };
  auto F = [&](double q, double& f, double& df) {
    const double phi = phi_of_q(q);
    InterfaceState s;
    s.phi = phi;
    s.p_pa = G.p0 * std::exp(G.Hlv * (1.0 - 1.0 / phi));
    s.p_star = s.p_pa / G.p_scale;
    s.grad_top = q;
    f = recession_rate(G, 0.0, s) - G.Na * G.k * q / L0;  // dS1/dtau = dS2/dtau
    df = 0.0;  // bisection only
  };
  const double v_m = std::exp(G.Hlv * (1.0 - 1.0 / G.theta_m)) * (1.0 + G.Lambda * G.theta_m) /
                     (G.Iprime * std::sqrt(G.theta_m));
  const double qmax = (1.0 - v_m * (1.0 + 1e-6)) / G.kprime;  // theta_sat -> 0
  double flo, fhi, d;
  F(1e-9 * qmax, flo, d);
  F(qmax, fhi, d);
  if (!(flo > 0.0 && fhi < 0.0)) return 0.0;
  const RootResult r = safe_newton(F, 1e-9 * qmax, qmax, 1e-12 * qmax, 200);
  if (!r.converged) return 0.0;
  const double q = r.x, phi = phi_of_q(q);
  const double theta = (phi - G.theta_m) / (1.0 - G.theta_m);
  if (!(theta > 0.0)) return 0.0;
  const double g = theta / q;
  const double lambda = (G.Na * G.k / L0 + G.hls_hlv * G.Ste) * q / g;
  return 2.0 / lambda * G.t_scale;
}

}  // namespace laser
