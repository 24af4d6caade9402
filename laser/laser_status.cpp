// Physical energy check and status of a run (class Drill).
#include "laser_drill_state.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace laser {
namespace detail {

void Drill::physical_check() {
  PhysicalCheck& pc = res_.check;
  const Material& m = cfg_.mat;
  const double R = cfg_.R;
  auto H = [&](double Ts) { return m.cps * (m.Tm - m.Ti) + m.hls + m.cpl * (Ts - m.Tm) + m.hlv; };
  pc.Ts = res_.T_center;
  pc.H = H(std::max(pc.Ts, m.Tm));
  pc.H0 = H(m.Tsat0);
  const double melt_heat = m.cps * (m.Tm - m.Ti) + m.hls;  // J/kg to melt the solid in place
  // sensible heat per kg that melt carried into a column can bring at most
  const double inflow_heat = m.cpl * (std::max(res_.T_peak, m.Tm) - m.Tm);
  double beam = 0, demand = 0, demand0 = 0, need_all = 0;
  pc.worst_node_ratio = 0;
  const double t_end = res_.t_end;
  for (const auto& n : nodes_) {
    const double absorbed = cfg_.I0 * gaussian_beam(n.xi) * t_end;  // J/m2
    beam += absorbed * n.area;
    const double removed = (n.S2 - n.g) * R;
    if (!n.molten) continue;
    const double Ts = std::max(n.itf.phi * m.Tsat0, m.Tm);
    // the column melted S2 in place and vaporized S1 (paying c_pl (T_s - T_m)
    // + h_lv); melt the flow brought in may have carried heat with it
    const double need = m.rho * (melt_heat * n.S2 + (H(Ts) - melt_heat) * n.S1) * R;
    const double avail = absorbed + m.rho * inflow_heat * n.V_in * R;
    need_all += need * n.area;
    demand += m.rho * pc.H * removed * n.area;
    demand0 += m.rho * pc.H0 * removed * n.area;
    const double ratio = need / avail;
    if (!(ratio <= pc.worst_node_ratio)) { pc.worst_node_ratio = ratio; pc.worst_node_xi = n.xi; }
  }
  pc.removed_over_beam = beam > 0 ? demand / beam : 0.0;
  pc.removed_over_beam_H0 = beam > 0 ? demand0 / beam : 0.0;
  pc.melt_vap_over_beam = beam > 0 ? need_all / beam : 0.0;
  // net centre recession over the last 10 % of the pulse
  const auto& c = res_.centre;
  if (c.size() >= 2 && res_.t_melt_center >= 0) {
    const double ta = c.back().t - 0.1 * (c.back().t - res_.t_melt_center);
    size_t k = c.size() - 1;
    while (k > 0 && c[k].t > ta) --k;
    if (c.back().t > c[k].t) pc.centre_velocity = (c.back().depth - c[k].depth) / (c.back().t - c[k].t);
  }
  pc.centre_bound = cfg_.I0 / (m.rho * pc.H);
  pc.centre_velocity_ratio = pc.centre_velocity / pc.centre_bound;
  // I0/(rho H) bounds the recession by vaporization only; a flow that expels
  // melt can remove the centre for rho (c_ps (T_m - T_i) + h_ls) per volume, and
  // the centre column's energy bound (worst_node_ratio) covers that case
  const bool no_flow = cfg_.model == FlowModel::Conduction;
  pc.holds = pc.melt_vap_over_beam < 1.0 && pc.worst_node_ratio < 1.0 && (!no_flow || pc.centre_velocity_ratio < 1.0);
}

// --melt-content transient: limiter hits only the layer's content asked for are a note,
// not a cause (a layer formed within one step; they vanish under dt refinement)
void Drill::note_content_hits() {
  if (res_.b2_content_clamps > 0)
    res_.notes.push_back("melt layer content: the transient balance asked for |b2| g^2 / theta_sat up to " +
                         fmt(res_.b2_content_demand_max, 4) + " (limit of (4-25): 1) " +
                         std::to_string(res_.b2_content_clamps) + " times (" + first_content_ +
                         "), where the quasi-steady layer would not; the layer keeps the content its balance "
                         "gives (a layer formed within one step; these hits vanish under dt refinement, "
                         "docs/theory/laser_model.md 2.7, and the step-doubling estimate measures their effect)");
}

// Status from the physics checks: every check that fails is named (the most
// serious first) in Result::causes and the message; the counts count.
void Drill::assess() {
  const Material& m = cfg_.mat;
  res_.T_over_Tc = res_.T_peak / m.Tc;
  if (res_.T_peak > kTcWarnFraction * m.Tc)
    res_.warnings.push_back("surface temperature " + fmt(res_.T_peak, 5) + " K above " + fmt(kTcWarnFraction, 2) +
                            " of the critical temperature " + fmt(m.Tc, 5) +
                            " K: the Clausius-Clapeyron vapour (3-15) and the sharp melt-vapour interface are "
                            "doubtful there");
  const PhysicalCheck& pc = res_.check;
  const bool finished = res_.status == "ok" || res_.status == "no_flow_solution" || res_.status == "truncated";
  const std::string bound_text = "melting and vaporizing the computed volumes needs " +
                                 fmt(pc.melt_vap_over_beam, 4) +
                                 " times the beam energy (rho (h_m V_melted + h_v V_vaporized) / E_beam must stay below 1)";
  if (finished && (!std::isfinite(res_.volume_removed) || !(pc.melt_vap_over_beam <= kAbsurdEnergy))) {
    res_.status = "diverged";
    res_.causes.insert(res_.causes.begin(), "energy bound of the whole melt");
    res_.message = bound_text + (res_.message.empty() ? "" : "; " + res_.message);
    return;
  }
  if (res_.status != "ok") return;
  std::vector<std::string> why;
  auto cause = [&](const std::string& name, const std::string& text) {
    res_.causes.push_back(name);
    why.push_back(name + ": " + text);
  };
  const double node_steps = double(res_.steps) * res_.nodes;
  if (pc.melt_vap_over_beam >= 1.0) cause("energy bound of the whole melt", bound_text);
  if (pc.worst_node_ratio >= 1.0)
    cause("column energy bound", "the column at xi = " + fmt(pc.worst_node_xi, 4) + " melted and vaporized " +
                                     fmt(pc.worst_node_ratio, 4) + " times the energy it absorbed");
  if (cfg_.model == FlowModel::Conduction && pc.centre_velocity_ratio >= 1.0)
    cause("centre recession bound", "net centre recession " + fmt(pc.centre_velocity_ratio, 4) +
                                        " times I0/(rho H) over the last 10 % of the pulse");
  if (std::fabs(res_.melt_balance) > kMeltBalanceTol)
    cause("melt volume balance", "melted - vaporized - expelled over the rim - still molten = " +
                                     fmt(res_.melt_balance, 4) + " of the melted volume" +
                                     (cfg_.melt_flow == MeltFlow::Text ? " (the text's surface velocity (4-22) does "
                                                                         "not conserve the melt; --melt-flow conservative)"
                                                                       : ""));
  if (res_.b2_clamps > kSafeguardFraction * node_steps)
    cause("b2 limiter", "the quadratic melt temperature profile (4-25) cannot carry the heat the flow moves "
                        "sideways: " + std::string(cfg_.flux_heat() ? "the face heat fluxes ask" : "(4-27) asks") + " for |b2| g^2 / theta_sat up to " + fmt(res_.b2_demand_max, 4) +
                        " (monotone profile: at most 1); limited to 1 " + std::to_string(res_.b2_clamps) +
                        " times (" + fmt(res_.b2_clamps / node_steps, 3) + " of the node steps; " + first_b2_ + ")");
  note_content_hits();
  // named as a cause where the boundary model was not applied in most steps; a
  // few steps (the first ones after onset, when the melt is one step thick) are a note
  if (cfg_.model == FlowModel::Boundary && res_.bl_thicker_steps > 0 && 2 * res_.bl_thicker_steps <= res_.bl_steps)
    res_.notes.push_back("boundary layer thicker than the melt at the first node off the axis in " +
                         std::to_string(res_.bl_thicker_steps) + " of " + std::to_string(res_.bl_steps) +
                         " steps (" + first_bl_ + "): the integral profile was used from the axis there");
  if (cfg_.model == FlowModel::Boundary && 2 * res_.bl_thicker_steps > res_.bl_steps)
    cause("boundary layer thicker than the melt",
          "the boundary layer (4-9) is thicker than the melt at the first node off the axis in " +
              std::to_string(res_.bl_thicker_steps) + " of " + std::to_string(res_.bl_steps) +
              " steps (" + first_bl_ + "); there the boundary-layer profile (4-7) does not apply and the "
              "integral profile of --model risingfall is used from the axis");
  if (res_.curvature_clamps > kSafeguardFraction * node_steps)
    cause("curvature clamp", "|a d| >= 2 in (3-37) clamped " + std::to_string(res_.curvature_clamps) + " times (" +
                                 first_clamp_ + ")");
  if (cfg_.melt_flow == MeltFlow::Text && res_.melt_clamps > kSafeguardFraction * node_steps)
    cause("melt thickness clamp", "g < 0 set to 0 " + std::to_string(res_.melt_clamps) + " times");
  if (res_.volume_melted > 0 && res_.vaporization_cut > kMeltBalanceTol * res_.volume_melted)
    cause("vaporization cut", "recession cut to the melt available " + std::to_string(res_.melt_clamps) +
                                  " times, " + fmt(res_.vaporization_cut / res_.volume_melted, 3) +
                                  " of the melted volume (the step is too long for the thin layer)");
  const double imb = (res_.energy.sum() - res_.energy.laser_exact) / res_.energy.laser_exact;
  if (std::fabs(imb) > 0.01) cause("energy bookkeeping", "imbalance " + fmt(imb, 4) + " (> 1e-2)");
  if (!why.empty()) {
    res_.status = "inaccurate";
    std::string msg;
    for (const auto& w : why) msg += (msg.empty() ? "" : "; ") + w;
    res_.message = msg;
  } else if (res_.curvature_clamps > 0) {
    res_.message = "curvature |a d| >= 2 clamped " + std::to_string(res_.curvature_clamps) + " times (of " +
                   fmt(node_steps, 4) + " node steps; " + first_clamp_ + ")";
  }
}

}  // namespace detail
}  // namespace laser
