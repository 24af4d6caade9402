// Laws of the fluid-grain coupling that the solver's coupling phases use (coupling.cpp), here so
// that they can be tested alone.
#pragma once

namespace mpm {

// Pressure at a node for the force on the grains: the linear least-squares fit p_j + b.(x - x_j)
// to the pressures of the points around node j, weighted by S_j V_p, from the moments
// m = (r (4), M (4 x 4)) of PfitRec (r = sum S V p e, M = sum S V e e^T, e = (1, x_s - x_j)).
// Writes (p_j, b) and returns true if the fit is determined (well conditioned, finite). A plain
// weighted mean would be the pressure of the points' centre, which next to a wall or the bed's
// floor lies up to a cell off the node (docs/theory/drag.md); the fit reproduces any linear field.
bool fit_linear_pressure(const double *moments, double dx, double out[4]);

// Passes of the [1/4 1/2 1/4] filter that smooth the solid fraction to a Gaussian of standard
// deviation L: each pass adds dx^2/2 to the variance (docs/theory/drag.md, "Smoothing the fluid fraction").
int smoothing_passes(double L, double dx);

// One pass of that filter along one direction at a node of volume V and fraction phi, from its
// two neighbours (Vn, phin; Vn = 0: none): the flux (phi_n - phi) min(V, V_n) / 4 keeps the solid
// volume exactly, a uniform fraction uniform, and takes nodes outside a wall (V = 0) out.
inline double smoothing_step(double V, double phi, const double Vn[2], const double phin[2], const bool has[2]) {
  double S = phi * V;
  for (int q = 0; q < 2; ++q)
    if (has[q]) S += 0.25 * (V < Vn[q] ? V : Vn[q]) * (phin[q] - phi);
  return V > 0.0 ? S / V : 0.0;
}

}  // namespace mpm
