#include "laser_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <cstdlib>

namespace laser {

namespace {

struct Node {
  double xi = 0, tau_m = 0, area = 0;  // area in m2
  bool molten = false;
  double S1 = 0, S2 = 0, g = 0, b2 = 0, S1flow = 0;
  double V_in = 0;  // gross melt thickness carried into the column by the flow
  InterfaceState itf;
  double dS1 = 0, dS2 = 0, v = 0, f = 0;  // rates of the last step, f: u = f zeta
  double v_kin = 0;  // conservative flow: -(1/xi) d(xi Q)/dxi at the start of the step (used in (4-27))
  double last_dg = 0;  // dg/dtau of the last step
  int flips = 0;       // consecutive sign changes of dg/dtau with lambda dtau > 2
};

constexpr int kUnstableFlips = 3;
// The model sees the absorbed intensity only (energies, bounds and groups).
Config absorbed(Config c) {
  c.I0 = c.absorbed_I0();
  c.absorptivity = 1.0;
  return c;
}
constexpr long kMaxFlowSubsteps = 100000;
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
  double solid_gradient_mean(const Node& n, double ta, double tb) const;
  // phases of advance_interfaces, per node
  struct Geometry { double J = 1, Cc = 1; };
  struct Rates { double dS2 = 0, dS1 = 0, drive = 0; };
  void advance_interfaces(double ta, double tb);
  void book_beam(const Node& n, double ta, double tb);
  Geometry front_geometry(int i, const std::vector<double>& S2old, double tb);
  void solve_implicit_thickness(Node& n, const Geometry& geo, double grad_n, double dtn);
  Rates front_rates(const Node& n, const Geometry& geo, double grad_n, double dtn);
  void check_stability(Node& n, const Geometry& geo, double grad_n, const Rates& r, double dtn, double tb);
  void book_energy(const Node& n, const Geometry& geo, double grad_n, const Rates& r, double dtn);
  void move_fronts(Node& n, const Rates& r, double dtn);
  void melt_temperature();
  void flux_heat_march();
  void record(double tau, bool frame);
  void emit(Frame&& f);
  void physical_check();
  bool state_admissible(double tb);
  void assess();
  double node_ta(const Node& n, double ta) const { return std::max(ta, n.tau_m); }

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
  double tb_ = 0;  // end of the current step (tau), for messages
  std::string flow_failure_, flow_cause_;
  std::string first_clamp_;
  std::string first_b2_, first_bl_;
  long flow_substeps_ = 0;
  std::vector<double> face_c_;  // conservative flow: face volume-rate coefficients c_k (rate c_k g_up^2)
  int first_c_ = 0;             // first node of the integral profiles
  int idx_x1_ = 0;
};

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

void Drill::solve_interfaces() {
  for (auto& n : nodes_) {
    if (!n.molten) continue;
    n.itf = solve_interface(G_, n.xi, n.g, n.b2, advected_);
    res_.max_interface_residual = std::max(res_.max_interface_residual, std::fabs(n.itf.residual));
  }
}

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

// Flux-conservative surface velocity (docs/laser_model.md, 2.6): the layer's
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
      if (dn < N && active[dn]) {
        gs[dn] += vol / a[dn];
        vin[dn] += vol / a[dn];
      } else {
        expelled += vol;
      }
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

double Drill::solid_gradient_mean(const Node& n, double ta, double tb) const {
  const double ti = G_.theta_i;
  switch (cfg_.solid) {
    case SolidModel::Exact: {
      const double sa = (ta - n.tau_m) / n.tau_m, sb = (tb - n.tau_m) / n.tau_m;
      return ti / std::sqrt(G_.Na * n.tau_m) * exact_->gradient_mean(std::max(sa, 0.0), sb);
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
    geo.Cc = curvature_factor(a, d);
  }
  return geo;
}

// Backward Euler in g: g_new = g_old + dtau (dS2 - dS1 + v)(g_new), with the
// solid gradient, curvature, the flow and its heat flux b2 g frozen over the step. The right side
// decreases with g, so the root is unique and bracketed.
void Drill::solve_implicit_thickness(Node& n, const Geometry& geo, double grad_n, double dtn) {
  // The flow's part of the layer's gradients, b2 g (half the heat the flow
  // carries sideways, 2 b2 g), is what the last step's (4-27) determined and is
  // held over the step; holding b2 itself would let b2 g grow with g_new.
  const double b2g = n.b2 * n.g;
  auto b2_at = [&](double g) { return g > 0.0 ? b2g / g : 0.0; };
  auto rate = [&](double g) {
    const InterfaceState st = solve_interface(G_, n.xi, g, b2_at(g), advected_);
    const double d2 =
        std::max(melting_rate(G_, geo.Cc, grad_n, geo.J, st.grad_bottom, cfg_.moving_origin), 0.0);
    const double d1 = std::max(recession_rate(G_, n.xi, st), 0.0);
    return d2 - d1 + n.v;
  };
  const double g_old = n.g;
  auto F = [&](double g) { return g - g_old - dtn * rate(g); };
  double g_new;
  const double F0 = F(0.0);
  if (F0 >= 0.0) {
    g_new = 0.0;
  } else {
    const double R0 = rate(g_old);
    double hi = R0 > 0.0 ? g_old + dtn * R0 : g_old;
    double Fhi = F(hi);
    for (int k = 0; Fhi < 0.0 && k < 60; ++k) { hi = 2.0 * hi + 1e-12; Fhi = F(hi); }
    g_new = illinois_root(F, 0.0, hi, F0, Fhi, 1e-12 * std::max(hi, 1e-12)).x;
  }
  n.b2 = b2_at(g_new);
  n.itf = solve_interface(G_, n.xi, g_new, n.b2, advected_);
}

// (3-40) melting and (3-25) recession rates; a negative melting rate is
// clamped to 0 and the solid demand it leaves undelivered is booked.
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
void Drill::book_energy(const Node& n, const Geometry& geo, double grad_n, const Rates& r, double dtn) {
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
  E.flow_advected += (n.itf.grad_top - n.itf.grad_bottom - sensible) * qscale_l * n.area * dts;
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
    if (cfg_.implicit_melt) solve_implicit_thickness(n, geo, grad_n, dtn);
    const Rates r = front_rates(n, geo, grad_n, dtn);
    check_stability(n, geo, grad_n, r, dtn, tb);
    book_energy(n, geo, grad_n, r, dtn);
    move_fronts(n, r, dtn);
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

// --melt-heat flux (docs/laser_model.md 2.7): the heat the flow carries through
// the cell faces, volume rate q = |c_k| g_up^2 at the flux-weighted mean
// temperature 2 theta_sat/3 of the upwind layer, and the layer's gradients
// 2 b2 g = D (heat per unit area and time leaving the column) are solved
// together, marching with the flow: the heat entering a column comes from its
// upwind neighbour (already solved), the heat leaving it depends on its own
// theta_sat, which in turn falls as b2 g rises: one bracketed root in the
// surface temperature (solve_interface_flux). Implicit and upwind, the
// march has no grid-dependent step limit; lagging D from one step to the next
// made an odd-even oscillation beyond xi = 1.6 at Pr 142 (docs 2.7).
void Drill::flux_heat_march() {
  const int N = static_cast<int>(nodes_.size());
  const double R2 = cfg_.R * cfg_.R;
  const bool outward = A_ >= 0.0;
  std::vector<double> theta_out(N, 0.0);  // flux-weighted temperature of the heat a node sends
  std::vector<char> done(N, 0);
  auto active = [&](int i) { return i >= first_c_ && i < N && nodes_[i].molten && nodes_[i].g > 0.0; };
  for (int k = 0; k < N; ++k) {
    const int i = outward ? k : N - 1 - k;
    Node& n = nodes_[i];
    if (!active(i) || face_c_.empty()) { n.b2 = 0.0; continue; }
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
    if (qout == 0.0 && hin == 0.0) {
      n.b2 = 0.0;
      done[i] = 1;
      continue;
    }
    // b2 g = (qout 2 theta_sat/3 - hin) / (2 a) = beta theta_sat - gamma
    n.itf = solve_interface_flux(G_, n.xi, g, qout / (3.0 * a), hin / (2.0 * a), advected_);
    n.b2 = (qout / (3.0 * a) * std::max(n.itf.theta_sat, 0.0) - hin / (2.0 * a)) / g;
    const double th = std::max(n.itf.theta_sat, 0.0);
    if (std::fabs(n.b2) * g * g > th) {
      const double ask = th > 0.0 ? std::fabs(n.b2) * g * g / th : std::numeric_limits<double>::infinity();
      if (res_.b2_clamps == 0) first_b2_ = "first at xi = " + fmt(n.xi, 4) + ", t = " + fmt(tb_ * G_.t_scale, 4) + " s";
      if (!(ask <= res_.b2_demand_max)) res_.b2_demand_max = ask;
      ++res_.b2_clamps;
      n.b2 = th > 0.0 ? std::copysign(th / (g * g), n.b2) : 0.0;
      n.itf = solve_interface(G_, n.xi, g, n.b2, advected_);
    }
    // what the column sends on is what came in minus what it keeps, 2 a b2 g: with
    // the solved b2 g this is qout 2 theta_sat/3; where the limit of (4-25) held b2
    // back, the heat the layer could not take (or give) stays with the flow, so the
    // face fluxes still telescope (heat is moved, never lost or made)
    theta_out[i] = qout > 0.0 ? std::max(hin + 2.0 * a * n.b2 * g, 0.0) / qout
                              : 2.0 / 3.0 * std::max(n.itf.theta_sat, 0.0);
    done[i] = 1;
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
  for (long step = 0; step < nsteps; ++step) {
    const double ta = tau;
    const double tb = (step == nsteps - 1) ? tau_p : std::min(tau_p, (step + 1) * dtau_);
    tb_ = tb;
    melt_onset(tb);
    solve_interfaces();
    if (!state_admissible(tb)) break;
    if (!solve_melt_flow(ta, tb)) {
      res_.status = "no_flow_solution";
      res_.causes.push_back(flow_cause_);
      res_.message = flow_failure_ + " at t = " + fmt(ta * G_.t_scale, 4) + " s";
      break;
    }
    advance_interfaces(ta, tb);
    melt_temperature();
    tau = tb;
    res_.steps = static_cast<int>(step + 1);
    res_.A_last = A_;
    res_.u_peak_max = std::max(res_.u_peak_max, u_peak_ * G_.v_scale);
    if (!state_admissible(tb)) break;  // the interface re-solved by the step (implicit update)
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
    if (res_.status != "ok") break;
    if (res_.unstable) {
      res_.status = "unstable_time_step";
      break;
    }
    const bool frame = tb >= tau_p * next_frame / (nframes - 1) - 1e-12 * tau_p;
    if (frame) ++next_frame;
    if (frame || step % centre_every == 0 || step == nsteps - 1) record(tb, frame);
    // progress every 10 % of the pulse, and at least every 10 s of wall time
    const bool slow = !cfg_.quiet && (step & 63) == 0 &&
                      std::chrono::steady_clock::now() - last_progress > std::chrono::seconds(10);
    if (slow || (!cfg_.quiet && nsteps >= 1000 && next_progress > 0 && step + 1 >= next_progress)) {
      last_progress = std::chrono::steady_clock::now();
      std::fprintf(stderr, "laser_drill: t = %.1f us (%3.0f %%), centre depth %.2f um, T %.0f K\n",
                   tb * G_.t_scale * 1e6, 100.0 * (step + 1) / nsteps,
                   (nodes_[0].S2 - nodes_[0].g) * cfg_.R * 1e6, res_.centre.back().T);
      if (!slow) next_progress += nsteps / 10;
    }
  }
  if (res_.frames_written == 0 || (res_.status != "diverged" && res_.final_frame.t < tau * G_.t_scale))
    record(tau, true);
  if (sink_) sink_->finish();
  res_.t_end = tau * G_.t_scale;
  res_.dt = cfg_.dt;
  res_.max_stable_dt = lambda_max_ > 0 ? 2.0 / lambda_max_ * G_.t_scale : 0.0;
  if (res_.unstable)
    res_.message += "; use --dt below about " + fmt(res_.max_stable_dt, 4) + " s (--dtau " +
                    fmt(res_.max_stable_dt / G_.t_scale, 4) + ")";
  // summary quantities
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
  return res_;
}

}  // namespace

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

Result run_simulation(const Config& cfg, FrameSink* sink) {
  Drill d(cfg, sink);
  return d.run();
}

}  // namespace laser
