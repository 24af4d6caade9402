#include "laser_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <cstdlib>

#include "laser_drill_state.h"

namespace laser {
namespace detail {

void Drill::setup() {
  res_.groups = G_;
  dtau_ = cfg_.dt / G_.t_scale;
  res_.dtau = dtau_;
  res_.tau_p = cfg_.tp / G_.t_scale;
  const double tau_m0 = melt_onset_tau(G_, 0.0);
  double xi_edge = 0.0;
  if (res_.tau_p > tau_m0) xi_edge = std::sqrt(0.5 * std::log(res_.tau_p / tau_m0));
  res_.xi_melt_edge = xi_edge;
  int N;
  if (cfg_.xi_max > 0.0) N = static_cast<int>(std::lround(cfg_.xi_max / cfg_.dxi)) + 1;
  else N = static_cast<int>(std::floor(xi_edge / cfg_.dxi)) + 3;
  N = std::max(N, 3);
  nodes_.resize(N);
  const double R2 = cfg_.R * cfg_.R;
  for (int i = 0; i < N; ++i) {
    Node& n = nodes_[i];
    n.xi = i * cfg_.dxi;
    n.tau_m = melt_onset_tau(G_, n.xi);
    n.area = (i == 0) ? kPi * 0.25 * cfg_.dxi * cfg_.dxi * R2 : 2.0 * kPi * n.xi * cfg_.dxi * R2;
    n.itf.phi = G_.theta_m;
    res_.xi.push_back(n.xi);
    res_.tau_m_s.push_back(n.tau_m * G_.t_scale);
  }
  idx_x1_ = std::min(N - 1, static_cast<int>(std::lround(1.0 / cfg_.dxi)));
  res_.nodes = N;
  const double xi_out = (N - 0.5) * cfg_.dxi;
  res_.energy.laser_exact = kPi * R2 * cfg_.I0 * cfg_.tp * (1.0 - std::exp(-xi_out * xi_out));
  if (cfg_.solid == SolidModel::Exact) exact_ = shared_corrected_conduction(kTau0OverTauM);
}

// A node melts inside [ta, tb) at its onset time (3-27); until then the beam
// went into the solid (3-26), which advance_interfaces books.
void Drill::melt_onset(double tb) {
  for (auto& n : nodes_)
    if (!n.molten && n.tau_m < tb) n.molten = true;
}

// (4-29) at each molten node's g and b2; a state the face heat march solved at them (the
// flow's part b2 g tied to the surface temperature, b2 that root's) is kept: solving it again
// at b2 moves phi by rounding only
void Drill::solve_interfaces() {
  for (auto& n : nodes_) {
    if (!n.molten) continue;
    if (!n.itf_solved) n.itf = solve_interface(G_, n.xi, n.g, n.b2, advected_, n.itf);
    n.itf_solved = false;
    res_.max_interface_residual = std::max(res_.max_interface_residual, std::fabs(n.itf.residual));
  }
}

void Drill::record(double tau, bool frame) {
  const double R = cfg_.R, vs = G_.v_scale;
  const Node& c = nodes_[0];
  const Node& c1 = nodes_[1];
  const Node& x1 = nodes_[idx_x1_];
  auto T = [&](const Node& n) {
    if (n.molten) return n.itf.phi * cfg_.mat.Tsat0;
    return cfg_.mat.Tm + G_.dT * premelt_temperature(G_, n.xi, 0.0, tau);
  };
  CentreRecord r{tau * G_.t_scale, (c.S2 - c.g) * R, c.S2 * R, c.g * R, T(c),
                 c.molten ? c.itf.p_pa : 0.0, c.dS2 * vs, c.dS1 * vs, A_, u_peak_ * vs,
                 c1.dS2 * vs, c1.dS1 * vs, c1.v * vs, x1.dS2 * vs, x1.dS1 * vs, x1.v * vs};
  res_.centre.push_back(r);
  if (!frame) return;
  Frame f;
  f.t = tau * G_.t_scale;
  f.A = A_;
  f.u_peak = u_peak_ * vs;
  for (const auto& n : nodes_) {
    f.S1net.push_back((n.S2 - n.g) * R);
    f.S2.push_back(n.S2 * R);
    f.S1.push_back(n.S1 * R);
    f.g.push_back(n.g * R);
    f.theta_sat.push_back(n.molten ? n.itf.theta_sat : 0.0);
    f.T.push_back(T(n));
    f.p.push_back(n.molten ? n.itf.p_pa : 0.0);
    f.melt_rate.push_back(n.dS2 * vs);
    f.vap_rate.push_back(n.dS1 * vs);
    f.flow_v.push_back(n.v * vs);
    f.b2.push_back(n.b2);
  }
  emit(std::move(f));
}

void Drill::emit(Frame&& f) {
  ++res_.frames_written;
  if (sink_) sink_->frame(f);
  else res_.frames.push_back(f);
  res_.final_frame = std::move(f);
}

// A surface state beyond the model's range stops the run as diverged: a
// non-finite temperature or pressure, or a temperature above the critical one.
bool Drill::state_admissible(double tb) {
  const Material& m = cfg_.mat;
  for (const auto& n : nodes_) {
    if (!n.molten) continue;
    const double T = n.itf.phi * m.Tsat0;
    if (std::isfinite(T) && std::isfinite(n.itf.p_pa) && T <= m.Tc) continue;
    res_.status = "diverged";
    res_.causes.push_back(std::isfinite(T) && std::isfinite(n.itf.p_pa) ? "surface temperature above the critical temperature"
                                                                       : "non-finite surface state");
    res_.message = "surface state beyond the model at xi = " + fmt(n.xi, 4) + ", t = " + fmt(tb * G_.t_scale, 4) +
                   " s: T_s = " + fmt(T, 5) + " K (critical temperature --T-critical " + fmt(m.Tc, 5) +
                   " K), p = " + fmt(n.itf.p_pa, 4) + " Pa (melt thickness g = " + fmt(n.g * cfg_.R, 4) + " m)";
    return false;
  }
  return true;
}

// Heat Courant number of the face heat fluxes: the share of a column's melt that the flow
// sends out of it in one step, C = dtau sum|c_k| g / a (c_k: the last flow solve's face
// rates, g: the column's thickness now). Beyond C = 1 the column's layer is asked to give
// more heat than it holds and the limit of (4-25) acts; the step is split into the fewest
// equal parts with C <= heat_courant (at most kMaxHeatSubsteps; 0: not split).
int Drill::heat_substeps(double dtau) const {
  if (!(cfg_.heat_courant > 0.0) || !cfg_.flux_heat() || face_c_.empty()) return 1;
  const int N = static_cast<int>(nodes_.size());
  const double R2 = cfg_.R * cfg_.R;
  double rate = 0.0;  // max over columns of sum|c_k| g / a
  for (int i = std::max(first_c_, 0); i < N; ++i) {
    const Node& n = nodes_[i];
    if (!n.molten || !(n.g > 0.0) || !(n.area > 0.0)) continue;
    double out = 0.0;
    for (int f : {i - 1, i}) {
      if (f < first_c_ || f < 0 || f >= N) continue;
      if ((face_c_[f] >= 0.0 ? f : f + 1) == i) out += std::fabs(face_c_[f]);
    }
    rate = std::max(rate, out * n.g * R2 / n.area);
  }
  const double parts = std::ceil(dtau * rate / cfg_.heat_courant - 1e-12);
  return static_cast<int>(std::clamp(parts, 1.0, static_cast<double>(kMaxHeatSubsteps)));
}

// One time step [ta, tb]: the phases of the text in order (laser_model.h).
// Returns false when the run stops (status and message set); tau is moved to
// tb once the fronts have moved.
bool Drill::step(long step, double ta, double tb, double& tau) {
  ta_ = ta;
  tb_ = tb;
  melt_onset(tb);
  solve_interfaces();
  if (!state_admissible(tb)) return false;
  if (!solve_melt_flow(ta, tb)) {
    res_.status = "no_flow_solution";
    res_.causes.push_back(flow_cause_);
    res_.message = flow_failure_ + " at t = " + fmt(ta * G_.t_scale, 4) + " s";
    return false;
  }
  advance_interfaces(ta, tb);
  melt_temperature();
  tau = tb;
  res_.steps = static_cast<int>(step + 1);
  res_.A_last = A_;
  res_.u_peak_max = std::max(res_.u_peak_max, u_peak_ * G_.v_scale);
  if (!state_admissible(tb)) return false;  // the interface re-solved by the step (implicit update)
  for (const auto& n : nodes_) {
    if (!n.molten) continue;
    res_.T_peak = std::max(res_.T_peak, n.itf.phi * cfg_.mat.Tsat0);
    res_.p_peak = std::max(res_.p_peak, n.itf.p_pa);
  }
  // Non-finite state: stop with the location instead of writing NaN.
  for (const auto& n : nodes_) {
    if (!std::isfinite(n.S2) || !std::isfinite(n.g) || !std::isfinite(n.S1) ||
        !std::isfinite(n.b2) || !std::isfinite(n.itf.phi)) {
      res_.status = "diverged";
      res_.causes.push_back("non-finite state");
      res_.message = "non-finite state at xi = " + fmt(n.xi, 4) + ", t = " + fmt(tb * G_.t_scale, 4) +
                     " s (model " + to_string(cfg_.model) + "; S2 " + fmt(n.S2, 4) + ", g " + fmt(n.g, 4) +
                     ", S1 " + fmt(n.S1, 4) + ", phi " + fmt(n.itf.phi, 4) + ", b2 " + fmt(n.b2, 4) + ")";
      break;
    }
  }
  if (res_.status != "ok") return false;
  if (res_.unstable) {
    res_.status = "unstable_time_step";
    return false;
  }
  return true;
}

Result Drill::run() {
  setup();
  const double tau_p = res_.tau_p;
  const long nsteps = static_cast<long>(std::ceil(tau_p / dtau_ - 1e-9));
  const long centre_every = std::max(1L, nsteps / 20000);
  int nframes = std::max(2, cfg_.frames);
  if (nframes > nsteps + 1) {
    res_.notes.push_back("--frames " + std::to_string(cfg_.frames) + " clipped to " + std::to_string(nsteps + 1) +
                         " (the run has " + std::to_string(nsteps) + " time steps)");
    nframes = static_cast<int>(nsteps + 1);
  }
  if (sink_) sink_->begin(res_.xi, res_.tau_m_s);
  int next_frame = 1;
  record(0.0, true);
  long next_progress = nsteps / 10;
  auto last_progress = std::chrono::steady_clock::now();
  double tau = 0.0;
  // the first run of an automatic ladder stops after its probe steps where they were split into
  // more than heat_probe_mbar sub-steps on average (Config::heat_probe_share)
  const long probe_steps =
      cfg_.heat_probe_share > 0.0 ? std::max(1L, static_cast<long>(std::ceil(cfg_.heat_probe_share * nsteps))) : 0;
  bool probed = false;
  for (long step_no = 0; step_no < nsteps; ++step_no) {
    const double ta = tau;
    const double tb = (step_no == nsteps - 1) ? tau_p : std::min(tau_p, (step_no + 1) * dtau_);
    // the face heat fluxes of a column are advanced with the step's flow: keep each step's
    // heat Courant number (docs/theory/laser_model.md 2.10) at most Config::heat_courant
    const int m = heat_substeps(tb - ta);
    heat_substeps_max_ = std::max<long>(heat_substeps_max_, m);
    heat_substeps_total_ += m - 1;
    bool going = true;
    for (int k = 1; k <= m && going; ++k)
      going = step(step_no, ta + (tb - ta) * (k - 1) / m, k == m ? tb : ta + (tb - ta) * k / m, tau);
    if (!going) break;
    if (step_no + 1 == probe_steps && step_no + 1 < nsteps &&
        mean_substeps(step_no + 1, heat_substeps_total_) > cfg_.heat_probe_mbar) {
      probed = true;
      break;
    }
    const bool frame = tb >= tau_p * next_frame / (nframes - 1) - 1e-12 * tau_p;
    if (frame) ++next_frame;
    if (frame || step_no % centre_every == 0 || step_no == nsteps - 1) record(tb, frame);
    // progress every 10 % of the pulse, and at least every 10 s of wall time
    const bool slow = !cfg_.quiet && (step_no & 63) == 0 &&
                      std::chrono::steady_clock::now() - last_progress > std::chrono::seconds(10);
    if (slow || (!cfg_.quiet && nsteps >= 1000 && next_progress > 0 && step_no + 1 >= next_progress)) {
      last_progress = std::chrono::steady_clock::now();
      std::fprintf(stderr, "laser_drill: t = %.1f us (%3.0f %%), centre depth %.2f um, T %.0f K\n",
                   tb * G_.t_scale * 1e6, 100.0 * (step_no + 1) / nsteps,
                   (nodes_[0].S2 - nodes_[0].g) * cfg_.R * 1e6, res_.centre.back().T);
      if (!slow) next_progress += nsteps / 10;
    }
  }
  if (res_.frames_written == 0 || (res_.status != "diverged" && res_.final_frame.t < tau * G_.t_scale))
    record(tau, true);
  if (sink_) sink_->finish();
  if (probed) res_.status = "split_probe";
  finish(tau);
  return res_;
}

// Summary quantities, the physical check and the status at the end of the run
// (tau: time reached).
void Drill::finish(double tau) {
  const double tau_p = res_.tau_p;
  res_.t_end = tau * G_.t_scale;
  res_.dt = cfg_.dt;
  res_.max_stable_dt = lambda_max_ > 0 ? 2.0 / lambda_max_ * G_.t_scale : 0.0;
  if (res_.unstable)
    res_.message += "; use --dt below about " + fmt(res_.max_stable_dt, 4) + " s (--dtau " +
                    fmt(res_.max_stable_dt / G_.t_scale, 4) + ")";
  const double R = cfg_.R;
  const Node& c = nodes_[0];
  if (c.tau_m < tau_p) res_.t_melt_center = c.tau_m * G_.t_scale;
  res_.depth_center = (c.S2 - c.g) * R;
  res_.S2_center = c.S2 * R;
  res_.g_center = c.g * R;
  res_.T_center = res_.centre.back().T;
  for (const auto& n : nodes_) {
    res_.volume_removed += (n.S2 - n.g) * R * n.area;
    res_.volume_vaporized += n.S1 * R * n.area;
    res_.volume_flow += n.S1flow * R * n.area;
    res_.volume_melted += n.S2 * R * n.area;
    res_.volume_molten += n.g * R * n.area;
  }
  res_.flow_substeps_max = flow_substeps_;
  res_.heat_substeps_max = heat_substeps_max_;
  res_.heat_substeps_extra = heat_substeps_total_;
  if (res_.volume_melted > 0.0)
    res_.melt_balance = (res_.volume_melted - res_.volume_vaporized - res_.volume_expelled - res_.volume_molten) /
                        res_.volume_melted;
  res_.removal_rate = res_.t_end > 0 ? res_.volume_removed / res_.t_end : 0.0;
  physical_check();
  if (res_.status == "ok" && c.tau_m >= tau_p) {
    res_.status = "no_melt";
    res_.message = "the surface does not reach T_m within the pulse: melt onset at the centre would be at t = " +
                   fmt(c.tau_m * G_.t_scale, 4) + " s > pulse " + fmt(cfg_.tp, 4) + " s";
    res_.T_peak = cfg_.mat.Tm + G_.dT * premelt_temperature(G_, 0.0, 0.0, tau_p);
  }
  if (res_.status == "ok" && nodes_.back().molten) {
    res_.status = "truncated";
    res_.message = "the melt zone reaches the last node (xi = " + fmt(nodes_.back().xi, 4) +
                   "; melting would reach xi = " + fmt(res_.xi_melt_edge, 4) +
                   "): removed volume and energy are cut at --xi-max";
  }
  assess();
}

}  // namespace detail

Result run_simulation(const Config& cfg, FrameSink* sink) {
  detail::Drill d(cfg, sink);
  return d.run();
}

}  // namespace laser
