// Constitutive laws of the weakly compressible Newtonian fluid (chapter 7.3)
// and the explicit time-step limits they impose. Independent of the grid,
// of MPI and of LIGGGHTS so that they can be tested alone.
#pragma once
#include <cmath>

namespace mpm {

enum class EosKind { Linear, Tait };

// Equation of state p(rho).
//  Linear, eq. (7-23): rho = rho0 / (1 - p/K)  <=>  p = K (1 - rho0/rho).
//  Tait: p = K/gamma ((rho/rho0)^gamma - 1); same K = rho0 dp/drho at rho0.
struct Eos {
  EosKind kind = EosKind::Linear;
  double rho0 = 1000.0;   // reference density, kg/m3
  double K = 2.2e9;       // bulk modulus at rho0, Pa
  double gamma = 7.0;     // Tait exponent

  double pressure(double rho) const {
    if (kind == EosKind::Linear) return K * (1.0 - rho0 / rho);
    return K / gamma * (std::pow(rho / rho0, gamma) - 1.0);
  }
  // Inverse of pressure(): the density at which the fluid has pressure p.
  double density(double p) const {
    if (kind == EosKind::Linear) return rho0 / (1.0 - p / K);
    return rho0 * std::pow(1.0 + gamma * p / K, 1.0 / gamma);
  }
  // Squared sound speed dp/drho at density rho.
  double sound_speed_sq(double rho) const {
    if (kind == EosKind::Linear) return K * rho0 / (rho * rho);
    return K / rho0 * std::pow(rho / rho0, gamma - 1.0);
  }
};

// Navier-Poisson law (7-24): tau = 2 eta dev(D), D = sym(L). Writes the six
// components xx, yy, zz, yz, xz, xy (Voigt order) of tau for the velocity
// gradient L[a][b] = d v_a / d x_b.
inline void newtonian_deviatoric_stress(double eta, const double L[3][3], double tau[6]) {
  const double tr3 = (L[0][0] + L[1][1] + L[2][2]) / 3.0;
  tau[0] = 2.0 * eta * (L[0][0] - tr3);
  tau[1] = 2.0 * eta * (L[1][1] - tr3);
  tau[2] = 2.0 * eta * (L[2][2] - tr3);
  tau[3] = eta * (L[1][2] + L[2][1]);
  tau[4] = eta * (L[0][2] + L[2][0]);
  tau[5] = eta * (L[0][1] + L[1][0]);
}

// Largest stable explicit time steps.
//  Acoustic (CFL): dt <= cfl * dx / (c + |v|max).
//  Viscous (explicit diffusion in dim dimensions): dt <= dx^2 rho / (2 dim eta).
inline double acoustic_dt_limit(double cfl, double dx, double c, double vmax) {
  return cfl * dx / (c + vmax);
}
inline double viscous_dt_limit(double dx, double rho, double eta, int dim) {
  if (eta <= 0.0) return HUGE_VAL;
  return dx * dx * rho / (2.0 * dim * eta);
}

// Pore-pressure waves of fluid and grains pushed by the same pressure (docs/theory/coupled_stability.md),
// with r = rho_f (1 - theta) / (theta rho_p) and c_f the fluid's sound speed. Fluid and grains
// together (the fluid not sub-cycled): c = c_f sqrt(1 + r). The grains' own wave when the fluid
// follows them within the step (sub-cycled): c_g = c_f sqrt(r).
inline double coupled_wave_speed(double c_f, double r) { return c_f * std::sqrt(1.0 + r); }
inline double grain_wave_speed(double c_f, double r) { return c_f * std::sqrt(r); }

}  // namespace mpm
