// Time stepping of the single-pulse drilling model on the axisymmetric
// surface grid xi_i = i d(xi). Each step runs the phases of the text:
//   melt_onset -> solve_interfaces (3-22)/(4-30) -> solve_melt_flow (4-17..4-24)
//   -> solid_conduction (3-29..3-36) with corrections (3-37..3-40)
//   -> advance_interfaces: per node book_beam, front_geometry (3-37)/(3-38),
//      front_rates (3-25)/(3-40), check_stability (4-14), book_energy,
//      move_fronts (4-14)/(4-15) -> melt_temperature (4-27)
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "laser_conduction.h"
#include "laser_laws.h"
#include "laser_params.h"

namespace laser {

struct Frame {
  double t = 0;  // s
  double A = 0;  // flow coefficient (nondimensional)
  double u_peak = 0;  // m/s, peak radial surface velocity
  std::vector<double> S1net, S2, S1, g, theta_sat, T, p, melt_rate, vap_rate, flow_v, b2;
};

struct CentreRecord {
  double t, depth, S2, g, T, p, melt_rate, vap_rate, A, u_peak;
  double melt_rate_1, vap_rate_1, flow_v_1;  // at xi = d(xi) (first node off the axis)
  double melt_rate_x1, vap_rate_x1, flow_v_x1;  // at xi = 1
};

// Receives the profile frames of a run as they are produced (the HDF5 writer
// streams them, so memory does not grow with --frames).
struct FrameSink {
  virtual ~FrameSink() = default;
  virtual void begin(const std::vector<double>& xi, const std::vector<double>& t_melt_s) = 0;
  virtual void frame(const Frame& f) = 0;
  virtual void finish() = 0;
};

struct Energy {  // J, over the pulse
  double laser_exact = 0;      // pi R^2 I0 t_p (1 - exp(-xi_out^2))
  double laser_nodal = 0;      // sum of I A dt actually applied
  double solid_premelt = 0;    // absorbed before onset, all conducted into the solid
  double solid_conduction = 0; // k_s C_c |d theta_s/dn| sqrt(1+S2'^2) after onset
  double solid_preheat = 0;    // moving-origin term rho c_ps (T_m - T_i) C_c ds2/dt
  double melt_latent = 0;      // rho h_ls * melted volume (from S2)
  double melt_sensible = 0;    // advected layer: rho c_pl (T_sat - T_m) of the vaporized liquid
  double vapour_latent = 0;    // rho h_lv * j_v M/rho, flux from (3-15), (3-17)
  double vapour_kinetic = 0;   // 1/2 j_v M V_v^2, (3-13), (3-17)
  double flow_advected = 0;    // k_l (grad_top - grad_bottom) - the two terms around it: carried sideways by the flow
  double melt_content = 0;     // heat content the melt layer gained (transient term of (3-3b), --melt-content)
  double clamp_defect = 0;     // (< 0) solid demand not delivered where ds2/dt < 0 was clamped to 0
  double sum() const {
    return solid_premelt + solid_conduction + solid_preheat + melt_latent + melt_sensible + vapour_latent +
           vapour_kinetic + flow_advected + melt_content + clamp_defect;
  }
};

// Energy check that does not use the model's own bookkeeping: the beam
// energy (integrated analytically) must pay at least rho H for every removed
// volume, H = c_ps (T_m - T_i) + h_ls + c_pl (T_s - T_m) + h_lv, plus
// rho (c_ps (T_m - T_i) + h_ls) for the melt still in place; heat left in the
// solid and sensible heat of the melt are >= 0 and left out (lower bound).
struct PhysicalCheck {
  double Ts = 0;                    // K, centre surface temperature at the end
  double H = 0;                     // J/kg with Ts
  double H0 = 0;                    // J/kg with T_sat0
  double removed_over_beam = 0;     // rho H V_removed / beam energy on the grid
  double removed_over_beam_H0 = 0;  // the same with H0
  double melt_vap_over_beam = 0;    // rho (h_m V_melted + h_v V_vaporized) / beam energy (global bound)
  double worst_node_ratio = 0;      // max over nodes of demand / (absorbed + heat the inflowing melt can bring)
  double worst_node_xi = 0;
  double centre_velocity = 0;       // m/s, net recession over the last 10 % of the pulse
  double centre_bound = 0;          // m/s, I0 / (rho H)
  double centre_velocity_ratio = 0;
  bool holds = true;
};

// How the time step was chosen and checked (laser_timestep.h).
struct StepReport {
  bool automatic = false;
  double companion_dt = 0;   // s, step of the coarse run of the three-level estimate (2 dt; dt/2 without one)
  double fine_companion_dt = 0;  // s, step of its fine run (dt/2; dt/4 without a coarse one)
  double depth_ratio = 0, volume_ratio = 0;  // ratio of successive differences of the three runs
  double depth_error = 0;    // relative, estimated error of the reported run
  double volume_error = 0;
  double grid_companion_dxi = 0;  // d(xi) of the grid companion run (0: none)
  double grid_companion_dt = 0;   // s, its step (the step-doubling companion's), compared with the run at that step
  double grid_depth_error = 0;    // relative, estimated d(xi) error of the reported run (NaN: no estimate)
  double grid_volume_error = 0;
  int runs = 0;
  long steps_total = 0;
  double stable_limit = 0;  // s, a-priori explicit limit of (4-14) (0: implicit update or none)
  double accepted_limit = 0;  // s, largest step accepted with the explicit update (a fraction of stable_limit)
  std::string reason;
};

struct Result {
  std::string status = "ok";
  std::string message;
  bool unstable = false;   // time step above the explicit limit: a usage error
  double max_stable_dt = 0;  // s, estimate 2/lambda_max seen
  double t_end = 0;        // s, time reached
  double dt = 0;           // s, step of this run
  double t_melt_center = -1;
  double depth_center = 0, S2_center = 0, g_center = 0;
  double volume_removed = 0, volume_vaporized = 0, volume_flow = 0, volume_melted = 0;
  double volume_expelled = 0;    // m3, melt carried over the rim by the flow (conservative flow)
  double volume_molten = 0;      // m3, melt still in place at the end
  double vaporization_cut = 0;   // m3, recession cut to the melt available (conservative flow)
  double melt_balance = 0;       // (melted - vaporized - expelled - molten) / melted
  long flow_substeps_max = 0;    // most flux sub-steps in one step (conservative flow)
  long heat_substeps_max = 0;    // most heat Courant sub-steps in one step (--melt-heat flux)
  long heat_substeps_extra = 0;  // steps added by the heat Courant limit over the run
  double removal_rate = 0;
  double T_peak = 0, p_peak = 0, u_peak_max = 0, A_last = 0;
  double T_center = 0;     // K, centre surface temperature at the end
  double xi_melt_edge = 0;
  double bl_last_xi = 0;  // boundary model: outermost node where delta < g was met
  long bl_thicker_steps = 0;   // boundary model: steps in which delta >= g at the first node off the axis
  long bl_steps = 0;           // boundary model: steps with melt off the axis
  double bl_first_ratio = 0;   // delta / g there, at the first such step
  double b2_demand_max = 0;    // largest |b2| g^2 / theta_sat that (4-27) asked for (1: limit of (4-25))
  // --melt-content transient: limiter hits that the quasi-steady layer would not have had (the
  // layer's content asked for more than (4-25) holds; the layer keeps the balance's content)
  long b2_content_clamps = 0;
  double b2_content_demand_max = 0;
  int steps = 0, nodes = 0;
  int melt_clamps = 0, melt_rate_clamps = 0, curvature_clamps = 0, b2_clamps = 0;
  double max_interface_residual = 0;
  double dtau = 0, tau_p = 0;
  Energy energy;
  PhysicalCheck check;
  StepReport step;
  std::vector<std::string> notes;  // e.g. the --frames clip
  std::vector<std::string> causes; // named checks that made the status inaccurate/diverged
  std::vector<std::string> warnings;  // physics range (critical temperature)
  double T_over_Tc = 0;            // T_peak / T_critical
  std::vector<double> xi, tau_m_s;
  std::vector<Frame> frames;       // kept only when run without a FrameSink
  Frame final_frame;
  int frames_written = 0;
  std::vector<CentreRecord> centre;
  Groups groups;
};

// Model steps per step of a run whose heat Courant limit added 'extra' sub-steps to 'steps' steps
// (the mean split, 1 for none).
inline double mean_substeps(long steps, long extra) { return double(steps + extra) / double(steps); }

// Runs one case at cfg.dt (> 0); never throws for physical reasons (status
// says why it ended). Frames go to sink when given, else into Result::frames.
Result run_simulation(const Config& cfg, FrameSink* sink = nullptr);

// A priori limit [s] of the explicit melt-thickness update (4-14): 2/lambda
// with lambda = -d(dg/dtau)/dg at the quasi-steady ablation state of the beam
// centre (no flow, solid gradient decayed). Returns 0 if there is no such state.
double explicit_step_limit(const Config& cfg);

}  // namespace laser
