// Small operations on a wall triangle shared by the geometry queries (wall_geometry.cpp) and
// the wall conditions (wall_constraints.cpp); included by those two files only.
#pragma once

#include "mpm/wall_geometry.h"

namespace mpm {
namespace wall_tri {

// x lies farther than r from the triangle's bounding box along some axis (cannot be within r).
inline bool beyond_box(const WallGeometry::Tri &t, const double x[3], double r) {
  return x[0] < t.lo[0] - r || x[0] > t.hi[0] + r || x[1] < t.lo[1] - r || x[1] > t.hi[1] + r ||
         x[2] < t.lo[2] - r || x[2] > t.hi[2] + r;
}

// Velocity of the wall at barycentric weights b.
inline void wall_velocity(const WallGeometry::Tri &t, const double b[3], double w[3]) {
  for (int d = 0; d < 3; ++d) w[d] = b[0] * t.w[0][d] + b[1] * t.w[1][d] + b[2] * t.w[2][d];
}

}  // namespace wall_tri
}  // namespace mpm
