// Fluid boundary conditions on LIGGGHTS wall meshes (fix mesh/surface, moved or not by
// fix move/mesh) for the MPM grid of fix mpm/fluid. User and developer notes: docs/theory/mesh_walls.md.
//
// MeshWalls reads the triangles of the named meshes (node positions and the per-node velocity
// property "v" that fix move/mesh and the surface-velocity options of fix mesh/surface maintain)
// and gathers every triangle that can reach this rank's grid patch from the rank that owns it into
// a WallGeometry (mpm/wall_geometry.h), which applies the wall conditions node by node and point
// by point. The query methods below forward to it.
#pragma once

#include <string>
#include <vector>

#include "mpm/wall_geometry.h"

namespace LAMMPS_NS {
class LAMMPS;
}

namespace mpm {

struct MeshWallSpec : WallSpec {
  std::string fix_id;  // ID of a fix mesh/surface (or a style derived from it)
};

class MeshWalls {
 public:
  // Validates the specs (fix exists, is a fix mesh/surface of triangles, check_wall()); throws
  // std::runtime_error naming the fix ID and the problem. Not collective.
  MeshWalls(LAMMPS_NS::LAMMPS *lmp, std::vector<MeshWallSpec> specs);

  // Collective over lmp->world. Gathers the triangles (node positions and node velocities) whose
  // bounding box comes within 'margin' of this rank's patch box [patch_lo, patch_hi] (positions
  // of the first and last patch nodes), from the ranks that own them, including periodic images.
  // A rank with an empty patch passes lo > hi in any dimension. Re-looks the fixes up by ID (throws
  // if one was deleted). Call once per fluid sub-step (after the meshes moved, before the grid BCs).
  // Returns false if this rank's triangles, box and margin are those of the last call to the bit
  // (WallGeometry::set_triangles).
  bool refresh(const double patch_lo[3], const double patch_hi[3], double margin);

  // Collective. For every mesh with side SIDE_AUTO: the points x[0..n-1] vote
  // (WallGeometry::side_votes); the majority over all ranks fixes the side. Throws if a mesh gets
  // no vote. Needs a refresh() whose patch covers the points. Returns a one-line summary per mesh
  // (for the log). check_given: also throws for a mesh whose side was given (normal or opposite)
  // when more of the points within reach of its faces lie on its other side (the fluid there would
  // be held behind the wall), naming the mesh, the side and the counts.
  std::string infer_sides(const double *const *x, int n, double reach, bool check_given = false);

  // Sum over ranks of the local triangles of all meshes (collective); for logs and tests.
  long global_triangles() const;

  // The gathered triangles and the wall conditions (mesh k of the specs is wall k).
  const WallGeometry &geometry() const { return geo_; }

  // Forwards to geometry() (see there).
  static constexpr int kMaxConstraints = WallGeometry::kMaxConstraints;
  bool apply(const double x[3], double vel[3], double reach, double reach_behind = -1.0,
             double h = 0.0) const {
    return geo_.apply(x, vel, reach, reach_behind, h);
  }
  int collect(const double x[3], double reach, double reach_behind, WallConstraint *out,
              bool *near = nullptr) const {
    return geo_.collect(x, reach, reach_behind, out, near);
  }
  static void impose(const WallConstraint *c, int n, double vel[3], double h = 0.0) {
    WallGeometry::impose(c, n, vel, h);
  }
  bool nearest_face(const double x[3], double reach, double q[3], double n[3]) const {
    return geo_.nearest_face(x, reach, q, n);
  }
  bool push_back(double x[3], double v[3], double reach, const double *x_old = nullptr) const {
    return geo_.push_back(x, v, reach, x_old);
  }
  void set_kinematic_viscosity(double nu) { geo_.set_kinematic_viscosity(nu); }
  // Current fluid side of mesh k (SIDE_NORMAL, SIDE_OPPOSITE, SIDE_BOTH or SIDE_AUTO if unset).
  int side(int k) const { return geo_.wall(k).side; }
  // Triangles gathered by the last refresh() on this rank (own and received, with images).
  int gathered() const { return geo_.gathered(); }
  // Testing: false = every query scans all gathered triangles (no bins).
  void set_use_bins(bool on) { geo_.set_use_bins(on); }

 private:
  void *resolve(int k) const;   // FixMeshSurface* of mesh k (re-looked up by ID)
  void set_corner_frames(const std::vector<double> &mine);  // refresh, the first time

  LAMMPS_NS::LAMMPS *lmp_;
  std::vector<std::string> ids_;  // fix IDs of the meshes
  WallGeometry geo_;
  bool frames_set_ = false;  // the corner frames of the meshes (WallGeometry::set_corner_frames)
};

}  // namespace mpm
