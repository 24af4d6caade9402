// The nodes a material point touches, as one loop the compiler can flatten.
//
// A point's stencil is NS x NS x NS nodes (NS = 3 for the quadratic B-spline,
// 2 for linear shapes) starting at its base node. The weight of node
// (a, b, c) of the stencil is wx[a] wy[b] wz[c] and its gradient follows the
// product rule. for_stencil walks the nodes with the y-z products hoisted out
// of the x loop and the flat node index advanced by strides, so a transfer
// kernel does ~4 multiplications per node for the weights instead of
// recomputing the index and all products (docs/validation/performance.md).
#pragma once
#include <cstddef>

namespace mpm {

// 1-D weights and their spatial gradients (already divided by dx), the base
// node and its flat index in the rank's grid patch.
struct Stencil {
  int base[3];
  std::size_t n0;
  double w[3][3];
  double dw[3][3];
};

// fn(n, a, b, c, w, gx, gy, gz) for every node of the stencil (except the
// y and z node planes where weight and gradient are exactly 0): n the flat
// index, (a, b, c) its place in the stencil, w its weight, g its gradient.
// sy, sz: flat-index strides of the patch in y and z.
template <int NS, class Fn>
inline void for_stencil(const Stencil &s, std::size_t sy, std::size_t sz, Fn &&fn) {
  // A point at a cell centre reaches the B-spline's last node plane with weight and gradient
  // exactly 0 (the 2-D dam-break slab one cell thick: a third of the work); such a y or z plane
  // is left out (it only adds zeros). Decided once per point, not per node row.
  const int nb = (NS == 3 && s.w[1][2] == 0.0 && s.dw[1][2] == 0.0) ? 2 : NS;
  const int nc = (NS == 3 && s.w[2][2] == 0.0 && s.dw[2][2] == 0.0) ? 2 : NS;
  for (int c = 0; c < nc; ++c) {
    const double wz = s.w[2][c], dwz = s.dw[2][c];
    for (int b = 0; b < nb; ++b) {
      const double wy = s.w[1][b];
      const double wyz = wy * wz, dyz = s.dw[1][b] * wz, ydz = wy * dwz;
      const std::size_t row = s.n0 + c * sz + b * sy;
      for (int a = 0; a < NS; ++a) {
        const double wx = s.w[0][a];
        fn(row + a, a, b, c, wx * wyz, s.dw[0][a] * wyz, wx * dyz, wx * ydz);
      }
    }
  }
}

}  // namespace mpm

namespace mpm {

// Four doubles as one value: a node record row of the transfer kernels.
// With AVX (the build's MPM_SIMD option) it is the GCC/Clang vector type,
// one register; aligned(8) allows unaligned records. Without AVX a plain
// struct, which the compiler keeps in scalar registers (the vector type
// would be split and spilled through memory on SSE2).
#if defined(__AVX__)
typedef double Row4 __attribute__((vector_size(32), aligned(8)));
#else
struct __attribute__((may_alias)) Row4 {
  double v[4];
  double &operator[](int q) { return v[q]; }
  double operator[](int q) const { return v[q]; }
  Row4 &operator+=(const Row4 &o) {
    for (int q = 0; q < 4; ++q) v[q] += o.v[q];
    return *this;
  }
};
inline Row4 operator+(const Row4 &a, const Row4 &b) { return {a.v[0] + b.v[0], a.v[1] + b.v[1], a.v[2] + b.v[2], a.v[3] + b.v[3]}; }
inline Row4 operator-(const Row4 &a, const Row4 &b) { return {a.v[0] - b.v[0], a.v[1] - b.v[1], a.v[2] - b.v[2], a.v[3] - b.v[3]}; }
inline Row4 operator*(double s, const Row4 &a) { return {s * a.v[0], s * a.v[1], s * a.v[2], s * a.v[3]}; }
#endif

inline Row4 &row4(double *p) { return *reinterpret_cast<Row4 *>(p); }
inline const Row4 &row4(const double *p) { return *reinterpret_cast<const Row4 *>(p); }

}  // namespace mpm
