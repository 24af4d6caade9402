// Solid conduction after melt onset: the corrected Stefan solution (3-29)-(3-34)
// and the 1-D finite-difference heat solver that replaces MATLAB's pdepe.
//
// All of it is written in the variables of the onset at one xi:
//   x = n / sqrt(N_a tau_m),  s = (tau - tau_m) / tau_m,  theta / theta_i,
// in which the heat equation reads u_s = u_xx and the solution is the same at
// every xi (the text, section 3.5, normalises its figures in the same way).
#pragma once

#include <functional>
#include <memory>
#include <vector>

namespace laser {

// u_s = u_xx on a (possibly stretched) grid 0 = x_0 < ... < x_J with Dirichlet
// values at both ends. Each step is an implicit Euler step with Richardson
// extrapolation (two half steps minus one full step): second order in time
// and free of Crank-Nicolson's ringing on stretched grids.
class HeatSolver1D {
 public:
  HeatSolver1D(std::vector<double> x, std::vector<double> u0);
  // Crank-Nicolson instead of extrapolated implicit Euler (used by the
  // independent reference solution).
  void set_crank_nicolson(bool cn) { cn_ = cn; }
  void step(double ds, double left, double right);
  double gradient_at_left() const;  // second-order one-sided difference
  const std::vector<double>& u() const { return u_; }
  const std::vector<double>& x() const { return x_; }

 private:
  void implicit_step(std::vector<double>& u, double ds, double left, double right,
                     double theta) const;
  std::vector<double> x_, u_;
  bool cn_ = false;
};

// (3-28) minus (3-32) per unit theta_i: the profile G(x) that (3-33) diffuses.
double correction_initial_profile(double x, double c0);

// Tabulated correction to the Stefan gradient, per unit theta_i:
//   d(theta_s2 + theta_s3)/dx at x = 0 as a function of s,
// with theta_s2 by quadrature of (3-33), theta_s3 by HeatSolver1D with the
// boundary value -theta_s2b (3-34). Beyond the table the large-s asymptote
// M1 / (2 sqrt(pi) s^1.5) is used.
class CorrectedConduction {
 public:
  explicit CorrectedConduction(double c0);
  double c0() const { return c0_; }
  // correction h(s) = g2 + g3 and its pieces
  double correction(double s) const;
  // total scaled gradient d(theta_s/theta_i)/dx at x = 0, (3-29)
  double gradient(double s) const;
  // its mean over [sa, sb] (the mean of h from its integral, h at the middle for sb - sa at rounding)
  double gradient_mean(double sa, double sb) const;
  // The integral of h from 0 to s, kept by a caller that asks for the means over successive
  // intervals [s0, s1], [s1, s2], ...: the end of one is the start of the next.
  struct Cumulative {
    double s = -1.0, value = 0.0;
  };
  // gradient_mean(sa, sb) taking the integral at sa from 'known' where it is at sa, and leaving
  // the one at sb there: the same number.
  double gradient_mean(double sa, double sb, Cumulative& known) const;
  const std::vector<double>& s_table() const { return s_; }
  const std::vector<double>& g2_table() const { return g2_; }
  const std::vector<double>& g3_table() const { return g3_; }
  const std::vector<double>& b2_table() const { return th2b_; }

 private:
  double cumulative(double s) const;  // integral of h from 0 to s
  double correction_in(double s, size_t k) const;  // correction(s) for s in [s_[k-1], s_[k])
  double c0_;
  std::vector<double> s_, g2_, g3_, th2b_, h_, H_;
  double asym_coef_ = 0;  // h ~ asym_coef / s^1.5 beyond the table
};

// The table for c0, built on the first request and shared by every later run
// of the process (it depends on c0 only): building it costs about as much as
// the time stepping of the Table 5.1 case, and the step-doubling policy runs
// the model at least twice. Thread-safe.
std::shared_ptr<const CorrectedConduction> shared_corrected_conduction(double c0);

// Independent reference for L2: the full 1-D problem u_s = u_xx, u(0) = 0,
// u(inf) = 1, u(x, 0) = (3-28)/theta_i, on a uniform grid with Crank-Nicolson.
// Returns du/dx at x = 0 at the requested (increasing) s values.
std::vector<double> reference_gradient(const std::vector<double>& s_out, double dx = 0.01,
                                       double L = 40.0);

}  // namespace laser
