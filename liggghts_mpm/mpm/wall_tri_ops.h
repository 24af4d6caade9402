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

// The smooth surface's normal speed at barycentric weights b of t (t.smooth: set_corner_frames).
inline double smooth_normal_speed(const WallGeometry::Tri &t, const double b[3]) {
  return geom::dot3(b, t.vn);
}

// w's component along the unit vector n set to s, the others kept.
inline void set_normal_part(double w[3], const double n[3], double s) {
  const double dn = s - geom::dot3(w, n);
  for (int d = 0; d < 3; ++d) w[d] += dn * n[d];
}

// Velocity of the wall at barycentric weights b. On a facet of a smooth surface (t.smooth), the
// component along the facet's normal is the smooth surface's normal speed at b (set_corner_frames):
// a tessellated surface of revolution turning about its axis moves along itself.
inline void wall_velocity(const WallGeometry::Tri &t, const double b[3], double w[3]) {
  for (int d = 0; d < 3; ++d) w[d] = b[0] * t.w[0][d] + b[1] * t.w[1][d] + b[2] * t.w[2][d];
  if (t.smooth) set_normal_part(w, t.n, smooth_normal_speed(t, b));
}

}  // namespace wall_tri
}  // namespace mpm
