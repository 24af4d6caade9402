// fill ... inside mesh-ID [outside mesh-ID ...] of fix mpm/fluid: which points of the fill's
// lattice lie inside a closed triangle mesh, outside others, and at least a gap from every
// triangle. Independent of LIGGGHTS (the host gathers the triangles: mesh_fill_host.cpp).
//
// Inside: ray parity. The lattice's columns along z are crossed with every triangle once (the
// crossings sorted per column, each point counts those below it); a column that passes within a
// round-off of an edge or a vertex of a triangle, or lies in the plane of a triangle parallel to
// z, is classified point by point instead, by parity along fixed oblique directions (the next one
// where a ray grazes an edge). Parity needs no orientation of the triangles, only a closed mesh.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace mpm {

using Tri9 = std::array<double, 9>;  // the three vertices x y z of a triangle

// "" if the mesh is closed: vertices matched to 1e-9 of the mesh's extent, every edge belongs to
// exactly two triangles. Else what is wrong (edges of one triangle, of more than two, or no
// triangle).
std::string mesh_closed_problem(const std::vector<Tri9> &tris);

// Point x inside the closed mesh (ray parity along oblique directions; see above).
bool inside_closed(const std::vector<Tri9> &tris, const double x[3]);

// Squared distance of x to the triangle t.
double tri_distance2(const Tri9 &t, const double x[3]);

// The lattice of the fill's points: x_d = first[d] + i_d s[d] for i_d = lo[d] .. hi[d].
struct FillLattice {
  double first[3] = {0, 0, 0};
  double s[3] = {1, 1, 1};
  int lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};
  long long size() const;
  // index of lattice point (i, j, k) in the mask, i fastest
  long long index(int i, int j, int k) const {
    return (static_cast<long long>(k - lo[2]) * (hi[1] - lo[1] + 1) + (j - lo[1])) * (hi[0] - lo[0] + 1) + (i - lo[0]);
  }
};

// 1 for the lattice points inside the mesh 'inside' (every point if it is null), outside each mesh
// of 'outside', and at no less than gap (less 1e-6 of the smallest spacing, so that a point half a
// spacing from a wall on a lattice cell face stays) from every triangle of all of them.
std::vector<char> mesh_fill_mask(const FillLattice &lat, const std::vector<Tri9> *inside,
                                 const std::vector<std::vector<Tri9>> &outside, double gap);

}  // namespace mpm
