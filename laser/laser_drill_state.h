// Internal to laser/: the state of one run of the drilling model (class Drill)
// and the constants its phases share. The phases live in
//   laser_model.cpp     set-up, time loop, records, run_simulation
//   laser_melt_flow.cpp melt flow (4-16)..(4-24) and the melt temperature (4-25)/(4-27)
//   laser_fronts.cpp    solid conduction and the fronts (3-25), (3-37)..(3-40), (4-13)..(4-15),
//                       explicit step limit of (4-14)
//   laser_status.cpp    physical energy check and status
#pragma once

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "laser_model.h"

namespace laser {
namespace detail {

struct Node {
  double xi = 0, tau_m = 0, area = 0;  // area in m2
  bool molten = false;
  double S1 = 0, S2 = 0, g = 0, b2 = 0, S1flow = 0;
  double V_in = 0;  // gross melt thickness carried into the column by the flow
  InterfaceState itf;
  double dS1 = 0, dS2 = 0, v = 0, f = 0;  // rates of the last step, f: u = f zeta
  double v_kin = 0;  // conservative flow: -(1/xi) d(xi Q)/dxi at the start of the step (used in (4-27))
  double last_dg = 0;  // dg/dtau of the last step
  // --melt-content transient: the layer's heat content int_0^g theta dzeta at the end of
  // the last step, and its change in the last march (booked with the step that uses its b2 g)
  double H = 0, dH = 0;
  int flips = 0;       // consecutive sign changes of dg/dtau with lambda dtau > 2
  // itf was solved by the face heat march at this g and b2 (its flow part b2 g tied to the
  // surface temperature, b2 the value at that root): the next step starts from it as it is
  bool itf_solved = false;
  CorrectedConduction::Cumulative solid;  // the corrected conduction's integral at the last step's end
};

constexpr int kUnstableFlips = 3;
// The model sees the absorbed intensity only (energies, bounds and groups).
inline Config absorbed(Config c) {
  c.I0 = c.absorbed_I0();
  c.absorptivity = 1.0;
  return c;
}
constexpr long kMaxFlowSubsteps = 100000;
// the most parts one step is split into by the heat Courant limit (Config::heat_courant)
constexpr int kMaxHeatSubsteps = 1000;
constexpr double kTcWarnFraction = 0.8;
// rho (h_m V_melted + h_v V_vaporized) above this multiple of the beam energy is
// not a solution at all (diverged); between 1 and this it is a failed check
// (the text's melt layer reaches 1.12 at 7.5e10 W/m2)
constexpr double kAbsurdEnergy = 2.0;     // warning above this fraction of T_c
constexpr double kMeltBalanceTol = 1e-3;    // melt volume balance (text flow: 1e-4 at Pr = 0.142)
constexpr double kSafeguardFraction = 1e-4; // of the node steps

class Drill {
 public:
  Drill(const Config& c, FrameSink* sink)
      : cfg_(absorbed(c)), G_(make_groups(c.mat, c.absorbed_I0(), c.R)), sink_(sink),
        advected_(c.melt_energy == MeltEnergy::Advected) {}
  Result run();

 private:
  void setup();
  void melt_onset(double tb);
  void solve_interfaces();
  bool solve_melt_flow(double ta, double tb);
  bool conservative_flow(const FlowProfile& profile, int first, double ta, double tb);
  void solve_boundary_layer(int& last_bl);
  double solid_gradient_mean(Node& n, double ta, double tb) const;
  // phases of advance_interfaces, per node
  struct Geometry { double J = 1, Cc = 1; };
  struct Rates { double dS2 = 0, dS1 = 0, drive = 0; };
  void advance_interfaces(double ta, double tb);
  void book_beam(const Node& n, double ta, double tb);
  Geometry front_geometry(int i, const std::vector<double>& S2old, double tb);
  void solve_implicit_thickness(Node& n, const Geometry& geo, double grad_n, double dtn, double wt);
  void advance_trapezoidal(Node& n, const Geometry& geo, double grad_n, double dtn);
  Rates front_rates(const Node& n, const Geometry& geo, double grad_n, double dtn);
  void check_stability(Node& n, const Geometry& geo, double grad_n, const Rates& r, double dtn, double tb);
  void book_energy(const Node& n, const Geometry& geo, double grad_n, const Rates& r, double dtn,
                   double content_share);
  void move_fronts(Node& n, const Rates& r, double dtn);
  void melt_temperature();
  void flux_heat_march();
  void limit_b2(Node& n, double g, double th, bool content_only);
  void record(double tau, bool frame);
  void emit(Frame&& f);
  void physical_check();
  bool state_admissible(double tb);
  bool step(long step, double ta, double tb, double& tau);
  int heat_substeps(double dtau) const;
  void finish(double tau);
  void assess();
  void note_content_hits();
  double node_ta(const Node& n, double ta) const { return std::max(ta, n.tau_m); }
  // trapezoidal update: share of [t0, t1] after the column's melt onset (what the flow brings
  // before it goes over the rim, as into any column not molten); 1 for the other updates
  double molten_share(const Node& n, double t0, double t1) const {
    if (!cfg_.trapezoidal_melt || !(t1 > t0)) return 1.0;
    return std::clamp((t1 - std::max(t0, n.tau_m)) / (t1 - t0), 0.0, 1.0);
  }

  Config cfg_;
  Groups G_;
  FrameSink* sink_;
  bool advected_;
  std::shared_ptr<const CorrectedConduction> exact_;
  std::vector<Node> nodes_;
  Result res_;
  double A_ = 0, u_peak_ = 0;
  double lambda_max_ = 0;
  double dtau_ = 0;
  double ta_ = 0, tb_ = 0;  // the current step (tau); tb_ also for messages
  std::string flow_failure_, flow_cause_;
  std::string first_clamp_;
  std::string first_b2_, first_bl_, first_content_;
  long flow_substeps_ = 0;
  long heat_substeps_max_ = 0, heat_substeps_total_ = 0;
  std::vector<double> face_c_;  // conservative flow: face volume-rate coefficients c_k (rate c_k g_up^2)
  int first_c_ = 0;             // first node of the integral profiles
  int idx_x1_ = 0;
};

}  // namespace detail
}  // namespace laser
