// Transfer between material points and grid nodes: the policy type that says what a kernel
// computes, the one dispatch that picks it, and the small per-point helpers the kernels share.
#pragma once
#include <type_traits>

#include "mpm/grid.h"
#include "mpm/options.h"
#include "mpm/shape_functions.h"
#include "mpm/stencil.h"

namespace mpm {

// What the transfer kernels do for one choice of shape functions (NS = stencil size), transfer
// and update scheme (instead of a row of bool template flags):
//   apic     P2G and the MUSL remap carry the affine momentum m C (x_i - x_p)
//   inertia  G2P builds APIC's B and stores C = B D^-1 (quadratic B-spline: D exact)
//   need_L   G2P takes the velocity gradient of the new grid velocity: the USL stress update's,
//            and the affine field of APIC with linear shapes and of FLIP/PIC without MUSL
template <int NS_, bool APIC, bool MUSL>
struct TransferPolicy {
  static constexpr int NS = NS_;
  static constexpr bool apic = APIC;
  static constexpr bool musl = MUSL;
  static constexpr bool inertia = APIC && NS_ == 3;
  static constexpr bool need_L = (APIC && NS_ == 2) || !MUSL;
};

// fn(TransferPolicy<...>()) for the options' shape functions, transfer and update.
template <class Fn>
inline void with_policy(const Options &o, Fn &&fn) {
  const bool apic = o.transfer == Transfer::Apic;
  if (o.shape == ShapeKind::QuadraticBSpline) {
    if (apic)
      o.musl ? fn(TransferPolicy<3, true, true>()) : fn(TransferPolicy<3, true, false>());
    else
      o.musl ? fn(TransferPolicy<3, false, true>()) : fn(TransferPolicy<3, false, false>());
  } else {
    if (apic)
      o.musl ? fn(TransferPolicy<2, true, true>()) : fn(TransferPolicy<2, true, false>());
    else
      o.musl ? fn(TransferPolicy<2, false, true>()) : fn(TransferPolicy<2, false, false>());
  }
}

// Offsets x_i - x_p of the stencil's node planes from the point, per direction.
inline void stencil_offsets(const GridSpec &gs, const Stencil &ps, const double *xp, double o[3][3]) {
  for (int d = 0; d < 3; ++d)
    for (int a = 0; a < 3; ++a) o[d][a] = gs.origin[d] + (ps.base[d] + a) * gs.dx - xp[d];
}

// APIC: the affine part m C (x_i - x_p) of the momentum a point gives node (a, b, c) of its
// stencil, from mC = m C (row-major) and the node-plane offsets o, as three 4-wide columns, the
// momentum's components in lanes lane0 .. lane0 + 2 (the other lane 0): col[e][lane0 + r] =
// mC[3 r + e], so that the node's affine momentum is o[0][a] col[0] + o[1][b] col[1] +
// o[2][c] col[2] (affine_row), each lane sum_e mC[3 r + e] o[e] in the order e = 0, 1, 2.
inline void affine_columns(const double mC[9], int lane0, Row4 col[3]) {
  for (int e = 0; e < 3; ++e) {
    col[e] = Row4{0, 0, 0, 0};
    for (int r = 0; r < 3; ++r) col[e][lane0 + r] = mC[3 * r + e];
  }
}
inline Row4 affine_row(const Row4 col[3], const double o[3][3], int a, int b, int c) {
  return o[0][a] * col[0] + o[1][b] * col[1] + o[2][c] * col[2];
}

}  // namespace mpm
