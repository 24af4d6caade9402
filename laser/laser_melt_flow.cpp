// Melt flow (4-16)..(4-24) and melt temperature (4-25)/(4-27) of a run (class Drill).
#include "laser_drill_state.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace laser {
namespace detail {

// Least squares coefficient A of (4-18)/(4-19) for the integral profiles and
// the vertical surface velocity v(xi, g) that enters (4-13).
bool Drill::solve_melt_flow(double ta, double tb) {
  const int N = static_cast<int>(nodes_.size());
  for (auto& n : nodes_) { n.v = 0.0; n.f = 0.0; n.v_kin = 0.0; }
  A_ = 0.0;
  u_peak_ = 0.0;
  if (cfg_.model == FlowModel::Conduction) return true;
  int first = 1;  // the centre is pure conduction (text, 5.5)
  if (cfg_.model == FlowModel::Boundary) {
    int last_bl = 0;
    solve_boundary_layer(last_bl);
    first = last_bl + 1;
    res_.bl_last_xi = std::max(res_.bl_last_xi, nodes_[last_bl].xi);
  }
  const double Pr = cfg_.mat.Pr, m = cfg_.m, xp = cfg_.xi_p;
  const bool rising = cfg_.model == FlowModel::Rising;
  const FlowProfile profile{rising, m, xp};
  std::vector<double> dpdx(N, 0.0);
  for (int i = 1; i < N; ++i) {
    if (!nodes_[i].molten) continue;
    const bool lm = nodes_[i - 1].molten, rm = (i + 1 < N) && nodes_[i + 1].molten;
    const double pl = cfg_.recoil * nodes_[i - 1].itf.p_star, pc = cfg_.recoil * nodes_[i].itf.p_star;
    if (rm) {
      const double pr = cfg_.recoil * nodes_[i + 1].itf.p_star;
      dpdx[i] = lm ? (pr - pl) / (2 * cfg_.dxi) : (pr - pc) / cfg_.dxi;
    } else if (lm) {
      dpdx[i] = (pc - pl) / cfg_.dxi;
    }
  }
  double Q1 = 0, Q2 = 0, Q3 = 0, Q4 = 0;
  // trapezoid rule from the axis (the integrals of (4-20)/(4-24) start at 0)
  for (int i = (first == 1 ? 0 : first); i < N; ++i) {
    const Node& n = nodes_[i];
    if (!n.molten || !(n.g > 0.0)) continue;
    const double x = n.xi, g = n.g;
    double a, b, c;
    flow_residual_coefficients(profile, Pr, x, g, dpdx[i], a, b, c);
    const double w = (i == 0 || i == N - 1) ? 0.5 * cfg_.dxi : cfg_.dxi;
    // W(A) = 2 int a^2 A^3 + 3 int ab A^2 + int (b^2 + 2ac) A + int bc, i.e. (4-20)/(4-24)
    Q1 += 2.0 * a * a * w;
    Q2 += -3.0 * a * b * w;
    Q3 += (b * b + 2.0 * a * c) * w;
    Q4 += -b * c * w;
  }
  if (Q1 == 0.0) return true;  // no melt off the axis yet
  const CubicRoot root = select_flow_root(Q1, Q2, Q3, Q4);
  if (!root.ok || !std::isfinite(root.A)) {
    flow_cause_ = "no root of (4-19)";
    flow_failure_ = "no physical root of the cubic (4-19): " + root.note;
    return false;
  }
  A_ = root.A;
  if (cfg_.melt_flow == MeltFlow::Conservative) return conservative_flow(profile, first, ta, tb);
  // The rising-fall v has the finite limit -A g^2 on the axis; the rising v
  // ~ xi^(1/m - 1) is singular there and the centre stays pure conduction.
  const int first_v = (!rising && first == 1) ? 0 : first;
  for (int i = first_v; i < N; ++i) {
    Node& n = nodes_[i];
    if (!n.molten || !(n.g > 0.0) || (rising && n.xi == 0.0)) continue;
    const double x = n.xi, g = n.g;
    n.f = flow_shape(profile, A_, x);
    n.v = flow_surface_velocity(profile, A_, x, g);
    u_peak_ = std::max(u_peak_, std::fabs(n.f * g));
  }
  // Diagnostic only: the volume the profile carries out of the melt zone
  // (face flux pi xi f g^2 at the outer melt edge), booked as in the
  // conservative form so that the melt balance can be compared.
  const double R2 = cfg_.R * cfg_.R;
  for (int k = 0; k < N; ++k) {
    const Node& n = nodes_[k];
    if (!n.molten || !(n.g > 0.0) || (k + 1 < N && nodes_[k + 1].molten)) continue;
    const double xf = (k + 0.5) * cfg_.dxi, c = kPi * xf * flow_shape(profile, A_, xf);
    if (c > 0.0) res_.volume_expelled += c * n.g * n.g * (tb - ta) * R2 * cfg_.R;
  }
  return true;
}

// Flux-conservative surface velocity (docs/theory/laser_model.md, 2.6): the layer's
// volume flux per unit circumference Q = int_0^g u dzeta = f g^2/2 (u = f zeta)
// crosses the cell faces xi_(k+1/2) = (k + 1/2) d(xi), which bound exactly the
// node areas; dg/dtau = -(1/xi) d(xi Q)/dxi = v(xi, g) - u(xi, g) dg/dxi. The
// face value of g is taken upwind; the flux is advanced over the step in
// sub-steps that move at most half of a cell's melt (so g stays >= 0 and no
// clamp is needed), with A and f fixed at this step's values. Melt that
// crosses a face into a node that is not molten, or the outer end of the grid,
// is expelled over the rim. Each node gets v = (its change of g)/(its part of
// the step), which (4-13) and (4-27) then use.
bool Drill::conservative_flow(const FlowProfile& profile, int first, double ta, double tb) {
  const int N = static_cast<int>(nodes_.size());
  const double h = cfg_.dxi, dtau = tb - ta, R2 = cfg_.R * cfg_.R;
  const int first_c = first == 1 ? 0 : first;  // the integral profiles reach the axis
  std::vector<char> active(N, 0);
  std::vector<double> gs(N, 0.0), a(N, 0.0), c(N, 0.0), vin(N, 0.0);
  for (int i = 0; i < N; ++i) {
    Node& n = nodes_[i];
    a[i] = n.area / R2;
    if (i >= first_c && n.molten) {
      active[i] = 1;
      gs[i] = std::max(n.g, 0.0);
      if (n.xi > 0.0) {
        n.f = flow_shape(profile, A_, n.xi);
        u_peak_ = std::max(u_peak_, std::fabs(n.f * n.g));
      }
    }
    // face between node i and i + 1: volume rate c_i g_up^2 (outwards > 0)
    const double xf = (i + 0.5) * h;
    c[i] = kPi * xf * flow_shape(profile, A_, xf);
  }
  face_c_ = c;
  first_c_ = first_c;
  for (int k = first_c; k < N; ++k) {  // rates at the start of the step, for (4-27)
    const int up = c[k] >= 0.0 ? k : k + 1, dn = c[k] >= 0.0 ? k + 1 : k;
    if (up >= N || !active[up]) continue;
    const double q = std::fabs(c[k]) * gs[up] * gs[up];
    nodes_[up].v_kin -= q / a[up];
    if (dn < N && active[dn]) nodes_[dn].v_kin += q / a[dn];
  }
  double t = 0.0, expelled = 0.0;
  long sub = 0;
  std::vector<double> out(N), g0(N);
  while (t < dtau) {
    std::fill(out.begin(), out.end(), 0.0);
    double worst = 0.0;
    for (int k = first_c; k < N; ++k) {
      const int up = c[k] >= 0.0 ? k : k + 1;
      if (up >= N || !active[up]) continue;
      out[up] += std::fabs(c[k]) * gs[up];  // outflow rate / (g a) summed below
    }
    for (int i = first_c; i < N; ++i)
      if (active[i] && a[i] > 0.0) worst = std::max(worst, out[i] / a[i]);
    const double dts = worst > 0.0 ? std::min(dtau - t, 0.5 / worst) : dtau - t;
    // every face flux from the state at the start of the sub-step
    std::copy(gs.begin(), gs.end(), g0.begin());
    for (int k = first_c; k < N; ++k) {
      const int up = c[k] >= 0.0 ? k : k + 1, dn = c[k] >= 0.0 ? k + 1 : k;
      if (up >= N || !active[up]) continue;
      const double vol = std::fabs(c[k]) * g0[up] * g0[up] * dts;
      if (!(vol > 0.0)) continue;
      gs[up] -= vol / a[up];
      // a column melting inside the step takes what arrives after its onset (molten_share)
      const double keep = dn < N && active[dn] ? molten_share(nodes_[dn], ta + t, ta + t + dts) : 0.0;
      const double into = keep * vol / (keep > 0.0 ? a[dn] : 1.0);
      if (keep > 0.0) { gs[dn] += into; vin[dn] += into; }
      expelled += (1.0 - keep) * vol;
    }
    t = (dts == dtau - t) ? dtau : t + dts;
    if (++sub > kMaxFlowSubsteps) {
      flow_cause_ = "melt flow faster than the grid can carry";
      flow_failure_ = "melt flow faster than the grid can carry: more than " + std::to_string(kMaxFlowSubsteps) +
                      " flux sub-steps in one time step (A = " + fmt(A_, 4) + "; Courant number u dt/dr about " +
                      fmt(worst * dtau, 4) + ")";
      return false;
    }
  }
  flow_substeps_ = std::max(flow_substeps_, sub);
  res_.volume_expelled += expelled * R2 * cfg_.R;
  for (int i = 0; i < N; ++i) {
    if (!active[i]) continue;
    Node& n = nodes_[i];
    const double dtn = tb - node_ta(n, ta);
    if (!(dtn > 0.0)) continue;
    n.v = (gs[i] - std::max(n.g, 0.0)) / dtn;
    n.V_in += vin[i];
  }
  return true;
}

// Boundary-layer profile (4-7) near the centre: free stream (4-4), thickness
// from (4-9) by RK4 started at the second node with delta = sqrt(70 Pr xi/(37 U));
// used while the layer is thinner than the melt; V + v_delta by (4-11), (4-12).
void Drill::solve_boundary_layer(int& last_bl) {
  last_bl = 0;
  const int N = static_cast<int>(nodes_.size());
  if (N < 3 || !nodes_[0].molten || !nodes_[1].molten) return;
  const double Pr = cfg_.mat.Pr, h = cfg_.dxi, pc = cfg_.recoil * nodes_[0].itf.p_star;
  std::vector<double> U(N, 0.0);
  int end = 1;
  while (end < N && nodes_[end].molten) ++end;
  for (int i = 0; i < end; ++i) U[i] = std::sqrt(std::max(0.0, 2.0 * (pc - cfg_.recoil * nodes_[i].itf.p_star)));
  auto Ux = [&](double x, double& u, double& du) {
    const double s = x / h;
    int i = std::min(static_cast<int>(s), end - 2);
    const double w = s - i;
    u = (1 - w) * U[i] + w * U[i + 1];
    du = (U[i + 1] - U[i]) / h;
  };
  auto rhs = [&](double x, double d) {
    double u, du;
    Ux(x, u, du);
    if (!(u > 0.0) || !(d > 0.0)) return std::numeric_limits<double>::quiet_NaN();
    const double den = 105.0 * Pr - 39.0 * x * u;
    return (-35.0 * Pr * (12.0 * x / d - 5.0 * d / u * du + 5.0 * d / x) + 39.0 * d * u +
            183.0 * x * d * du) / den;
  };
  if (!(U[1] > 0.0)) return;
  double d = std::sqrt(70.0 * Pr * h / (37.0 * U[1]));
  // The boundary-layer profile (4-7) needs delta < g; where the layer is already
  // thicker than the melt at the first node, the boundary model cannot be
  // applied at all in this step (the integral profile takes over from the axis)
  ++res_.bl_steps;
  if (!(d < nodes_[1].g) && nodes_[1].g > 0.0) {
    if (res_.bl_thicker_steps++ == 0) {
      res_.bl_first_ratio = d / nodes_[1].g;
      first_bl_ = "first at t = " + fmt(tb_ * G_.t_scale, 4) + " s: delta/g = " + fmt(d / nodes_[1].g, 4) +
                  " at xi = " + fmt(nodes_[1].xi, 4);
    }
  }
  for (int i = 1; i < end - 1; ++i) {
    Node& n = nodes_[i];
    if (!(d > 0.0) || !std::isfinite(d) || d >= n.g) break;
    const double dU = (U[i + 1] - U[i - 1]) / (2 * h);
    const double div = dU + U[i] / n.xi;
    n.v = -div * (n.g - d) - 0.625 * d * div;  // V + v_delta
    n.f = 0.0;
    u_peak_ = std::max(u_peak_, U[i]);
    last_bl = i;
    // RK4 to the next node
    const double x = n.xi;
    const double k1 = rhs(x, d), k2 = rhs(x + h / 2, d + h / 2 * k1),
                 k3 = rhs(x + h / 2, d + h / 2 * k2), k4 = rhs(x + h, d + h * k3);
    d += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
}

// b2 of (4-25) from the integral energy balance (4-27), an ODE in xi for
// f J = f (theta_sat g^2/3 - b2 g^4/12) (u = f zeta), solved at every step by
// marching with the flow (upwind, implicit in b2 at the node), given theta_sat,
// g and f of this step. The text lags b2 between steps only in (4-30).
void Drill::melt_temperature() {
  if (cfg_.model == FlowModel::Conduction) return;
  if (cfg_.flux_heat()) {
    flux_heat_march();
    return;
  }
  const int N = static_cast<int>(nodes_.size());
  const double h = cfg_.dxi;
  const bool outward = A_ >= 0.0;
  double fJ_up = 0.0;  // f J at the upwind neighbour
  for (int k = 0; k < N; ++k) {
    const int i = outward ? k : N - 1 - k;
    Node& n = nodes_[i];
    if (i == 0 || !n.molten || !(n.g > 0.0) || n.f == 0.0) {
      n.b2 = 0.0;
      fJ_up = 0.0;
      continue;
    }
    const double g = n.g, th = n.itf.theta_sat, f = n.f, x = n.xi;
    if (!(th > 0.0)) {  // a layer at T_m throughout (beyond the vaporizing zone): b2 = 0 exactly
      n.b2 = 0.0;
      fJ_up = 0.0;
      continue;
    }
    const double sgn = outward ? 1.0 : -1.0;  // d/dxi by the upwind difference
    const double vs = cfg_.melt_flow == MeltFlow::Conservative ? n.v_kin : n.v;  // surface velocity of (4-27)
    const double num = sgn * (f * th * g * g / 3.0 - fJ_up) / h + f / x * th * g * g / 3.0 + vs * th;
    const double den = 2.0 * g + f * std::pow(g, 4) / 12.0 * (sgn / h + 1.0 / x);
    n.b2 = num / den;
    // Safeguard: keep the profile (4-25) monotone in [0, g], |b2 g^2| <= theta_sat.
    const double bmax = th / (g * g);
    if (std::fabs(n.b2) > bmax || !std::isfinite(n.b2)) {
      const double ask = std::fabs(n.b2) / bmax;
      if (res_.b2_clamps == 0)
        first_b2_ = "first at xi = " + fmt(x, 4) + ", t = " + fmt(tb_ * G_.t_scale, 4) + " s";
      if (!(ask <= res_.b2_demand_max)) res_.b2_demand_max = ask;
      ++res_.b2_clamps;
      n.b2 = std::isfinite(n.b2) ? std::copysign(bmax, n.b2) : 0.0;
    }
    fJ_up = f * (th * g * g / 3.0 - n.b2 * std::pow(g, 4) / 12.0);
  }
}

// Safeguard of (4-25): |b2| g^2 <= theta_sat keeps the profile monotone; a hit is
// counted as the flow's, or as the layer content's where only the content asked for
// more (content_only; --melt-content transient), and the interface re-solved at the limit.
void Drill::limit_b2(Node& n, double g, double th, bool content_only) {
  if (!(std::fabs(n.b2) * g * g > th)) return;
  const double ask = th > 0.0 ? std::fabs(n.b2) * g * g / th : std::numeric_limits<double>::infinity();
  const std::string where = "first at xi = " + fmt(n.xi, 4) + ", t = " + fmt(tb_ * G_.t_scale, 4) + " s";
  if (content_only) {
    if (res_.b2_content_clamps++ == 0) first_content_ = where;
    if (!(ask <= res_.b2_content_demand_max)) res_.b2_content_demand_max = ask;
  } else {
    if (res_.b2_clamps++ == 0) first_b2_ = where;
    if (!(ask <= res_.b2_demand_max)) res_.b2_demand_max = ask;
  }
  n.b2 = th > 0.0 ? std::copysign(th / (g * g), n.b2) : 0.0;
  n.itf = solve_interface(G_, n.xi, g, n.b2, advected_);
}

// --melt-heat flux (docs/theory/laser_model.md 2.7): the heat the flow carries through
// the cell faces, volume rate q = |c_k| g_up^2 at the flux-weighted mean
// temperature 2 theta_sat/3 of the upwind layer, and the layer's gradients are
// solved together, marching with the flow: the heat entering a column comes from
// its upwind neighbour (already solved), the heat leaving it depends on its own
// theta_sat, which in turn falls as b2 g rises: one bracketed root in the
// surface temperature (solve_interface_flux). Implicit and upwind, the march has
// no grid-dependent step limit; lagging the divergence from one step to the next
// made an odd-even oscillation beyond xi = 1.6 at Pr 142 (docs 2.7).
// Quasi-steady layer (--melt-content steady): 2 b2 g = D, the divergence of the face
// heat fluxes per unit area. With the transient term of (3-3b) (default): the layer's
// content H = int_0^g theta dzeta obeys dH/dtau = 2 b2 g - D (docs 2.7), backward
// Euler over the column's part of the step, H = content0(theta_sat) - b2 g^3/6.
void Drill::flux_heat_march() {
  const int N = static_cast<int>(nodes_.size());
  const double R2 = cfg_.R * cfg_.R;
  const bool outward = A_ >= 0.0, transient = cfg_.transient_content();
  std::vector<double> theta_out(N, 0.0);  // flux-weighted temperature of the heat a node sends
  std::vector<char> done(N, 0);
  auto active = [&](int i) { return i >= first_c_ && i < N && nodes_[i].molten && nodes_[i].g > 0.0; };
  for (int k = 0; k < N; ++k) {
    const int i = outward ? k : N - 1 - k;
    Node& n = nodes_[i];
    n.dH = 0.0;
    n.itf_solved = false;
    if (!active(i) || face_c_.empty()) {
      n.b2 = 0.0;
      n.H = 0.0;
      continue;
    }
    const double a = n.area / R2, g = n.g;
    double qout = 0.0, hin = 0.0;
    for (int f : {i - 1, i}) {  // faces between i-1|i and i|i+1
      if (f < first_c_ || f < 0 || f >= N) continue;
      const double cf = face_c_[f];
      const int up = cf >= 0.0 ? f : f + 1;
      if (up == i) {
        qout += std::fabs(cf) * g * g;
      } else if (active(up) && done[up]) {
        hin += std::fabs(cf) * nodes_[up].g * nodes_[up].g * theta_out[up];
      }
    }
    const double dtn = tb_ - node_ta(n, ta_);
    if ((qout == 0.0 && hin == 0.0 && !transient) || !(dtn > 0.0)) {
      n.b2 = 0.0;
      n.H = transient ? layer_content(n.itf, g, 0.0) : 0.0;
      done[i] = 1;
      continue;
    }
    // quasi-steady: b2 g = (qout 2 theta_sat/3 - hin) / (2 a) = beta theta_sat - gamma;
    // transient: b2 g = s (beta theta_sat - gamma) + kappa (content0 - H_old),
    // s = 1/(1 + g^2/(12 dtn)), kappa = s/(2 dtn)
    const double s = transient ? 1.0 / (1.0 + g * g / (12.0 * dtn)) : 1.0;
    const double kappa = transient ? s / (2.0 * dtn) : 0.0, H_old = transient ? n.H : 0.0;
    const double beta = qout / (3.0 * a), gamma = hin / (2.0 * a);
    n.itf = solve_interface_flux(G_, n.xi, g, s * beta, s * gamma, advected_, kappa, H_old, n.itf);
    const double th = std::max(n.itf.theta_sat, 0.0);
    n.b2 = (s * (beta * th - gamma) + (transient ? kappa * (layer_content(n.itf, g, 0.0) - H_old) : 0.0)) / g;
    // a hit whose flow part alone is within the limit is the layer's content asking for more
    limit_b2(n, g, th, transient && std::fabs(beta * th - gamma) * g <= th);
    n.itf_solved = true;
    // the column's heat balance: what it sends on is what came in, plus what its
    // gradients give the flow (2 a b2 g), minus what it keeps in its content; with
    // the solved b2 this is qout 2 theta_sat/3; where the limit of (4-25) held b2
    // back, the heat the layer could not take (or give) stays with the flow, so the
    // face fluxes still telescope (heat is moved, never lost or made)
    if (transient) {
      // the content is the state the balance gives, dH = dtn (2 b2 g - D), D = (qout 2 theta_sat/3
      // - hin)/a; with the solved b2 it is the profile's content; where the limit held b2 back,
      // the layer keeps the heat it was sent (or lacks what it could not take) and its content
      // differs from its profile's until later steps close the gap (nothing is moved elsewhere)
      const double D = (qout * 2.0 / 3.0 * std::max(n.itf.theta_sat, 0.0) - hin) / a;
      n.dH = dtn * (2.0 * n.b2 * g - D);
      n.H = H_old + n.dH;
      theta_out[i] = 2.0 / 3.0 * std::max(n.itf.theta_sat, 0.0);
      done[i] = 1;
      continue;
    }
    theta_out[i] = qout > 0.0 ? std::max(hin + 2.0 * a * n.b2 * g, 0.0) / qout
                              : 2.0 / 3.0 * std::max(n.itf.theta_sat, 0.0);
    done[i] = 1;
  }
}

}  // namespace detail
}  // namespace laser
