// Shape functions of the background grid, in one dimension: the 3-D weight of
// node (i,j,k) is the product wx[i]*wy[j]*wz[k], its gradient the product rule.
// Coordinates are in cell units: xi = (x - origin)/dx.
#pragma once
#include <algorithm>
#include <cmath>
#include <string>

namespace mpm {

enum class ShapeKind { Linear, QuadraticBSpline };

inline const char *shape_name(ShapeKind k) {
  return k == ShapeKind::Linear ? "linear" : "bspline2";
}

// Weights of the nodes base, base+1, ..., base+support-1 that a point at xi
// touches, and the derivatives of the weights with respect to xi (multiply
// by 1/dx for the spatial gradient).
struct Shape1D {
  static constexpr int kMaxSupport = 3;
  int base;
  double w[kMaxSupport];
  double dw[kMaxSupport];
};

inline int support(ShapeKind k) { return k == ShapeKind::Linear ? 2 : 3; }

// Node layers the stencil of a point reaches beyond the owned nodes of its rank, below (reach[0])
// and above (reach[1]) them, for a point at most delta cells outside the rank's subdomain [a, b)
// (x in [a - delta, b + delta)), wherever a and b lie (docs/design.md, "The halo"). The owned
// nodes are ceil(a) .. ceil(b) - 1, except that owned_box() gives a node within 1e-9 cells below
// a face to the rank above it: so a stencil may reach one layer more above the owned nodes than
// below them when delta sits on a step of the count (kTol covers that and round-off in delta).
// Quadratic B-spline: nodes floor(x + 1/2) - 1 .. floor(x + 1/2) + 1; linear: floor(x), floor(x) + 1.
inline void stencil_reach(ShapeKind k, double delta, int reach[2]) {
  constexpr double kTol = 1e-6;
  if (k == ShapeKind::Linear) {
    reach[0] = 1 + static_cast<int>(std::ceil(delta));
    reach[1] = 2 + static_cast<int>(std::floor(delta + kTol));
  } else {
    reach[0] = 2 + std::max(0, static_cast<int>(std::ceil(delta - 0.5)));
    reach[1] = 2 + static_cast<int>(std::floor(delta + 0.5 + kTol));
  }
}

// Linear (tent) function of the text, eq. (8-8): nodes floor(xi), floor(xi)+1.
inline void shape_linear(double xi, Shape1D &s) {
  const double f = std::floor(xi);
  const double r = xi - f;
  s.base = static_cast<int>(f);
  s.w[0] = 1.0 - r;
  s.w[1] = r;
  s.w[2] = 0.0;
  s.dw[0] = -1.0;
  s.dw[1] = 1.0;
  s.dw[2] = 0.0;
}

// Quadratic B-spline: nodes round(xi)-1 .. round(xi)+1. C1 continuous, so a
// point crossing a cell face sees no jump in its force (no cell-crossing noise).
inline void shape_bspline2(double xi, Shape1D &s) {
  const double c = std::floor(xi + 0.5);  // nearest node
  const double r = xi - c;                 // in [-0.5, 0.5)
  s.base = static_cast<int>(c) - 1;
  const double a = 0.5 - r, b = 0.5 + r;
  s.w[0] = 0.5 * a * a;
  s.w[1] = 0.75 - r * r;
  s.w[2] = 0.5 * b * b;
  s.dw[0] = -a;
  s.dw[1] = -2.0 * r;
  s.dw[2] = b;
}

inline void shape_eval(ShapeKind k, double xi, Shape1D &s) {
  if (k == ShapeKind::Linear)
    shape_linear(xi, s);
  else
    shape_bspline2(xi, s);
}

// Inverse of the APIC inertia tensor D = sum_i w_i (x_i - x_p)(x_i - x_p)^T in
// units of 1/dx^2 for the quadratic B-spline (D = dx^2/4 I, exact).
inline double apic_dinv_bspline2() { return 4.0; }

}  // namespace mpm
