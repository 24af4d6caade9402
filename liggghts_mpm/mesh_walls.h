// Fluid boundary conditions on LIGGGHTS wall meshes (fix mesh/surface, moved or not by
// fix move/mesh) for the MPM grid of fix mpm/fluid. User and developer notes: docs/mesh_walls.md.
//
// The class reads the triangles of the named meshes (node positions and the per-node velocity
// property "v" that fix move/mesh and the surface-velocity options of fix mesh/surface maintain),
// gathers every triangle that can reach this rank's grid patch from the rank that owns it, and
// then applies, node by node, the wall condition in the wall's frame:
//   relative velocity r = v - w (w = wall velocity at the closest point),
//   normal part   r.n -> max(0, r.n) on the fluid side, 0 behind the wall,
//   tangential    r_t -> (1 - sticky) r_t;
// kinds 'sticky f' and 'shear delta f' work on the tangential velocity relative to f times the
// wall's tangential velocity instead (imposed, or relaxed by the wall shear stress; see impose()).
#pragma once

#include <string>
#include <vector>

namespace LAMMPS_NS {
class LAMMPS;
}

namespace mpm {

// Fluid side of a mesh, relative to the triangles' normals (right-hand rule on the STL winding
// n0 -> n1 -> n2, i.e. the normals LIGGGHTS computes).
enum MeshSide : int {
  SIDE_NORMAL = 1,     // the fluid is on the side the normals point to
  SIDE_OPPOSITE = -1,  // the fluid is on the other side
  SIDE_AUTO = 0,       // decided by infer_sides() from where the material points are
  SIDE_BOTH = 2        // thin two-sided wall (a plate): no "behind"; only crossings are undone
};

// One wall condition at a grid node: wall velocity w at the closest point, unit normal n towards
// the fluid, whether the node is behind the wall, the tangential fraction (sticky) and whether it
// is imposed (kind 3) rather than damped; rate > 0 (kind 4, shear): the relaxation rate (1/time)
// of the tangential velocity towards sticky times the wall's, from the wall shear stress.
struct WallConstraint {
  double w[3];
  double n[3];
  double sticky;
  double rate;
  bool behind;
  bool imposed;
};

// Relaxation rate (1/time) of the tangential slip of the fluid within 'depth' of a wall whose
// unresolved viscous layer of thickness delta carries the stress mu v_slip / delta: the law of the
// shear kinds of mesh walls and grid faces (docs/mesh_walls.md).
inline double wall_layer_rate(double nu, double delta, double depth) { return nu / (delta * depth); }

struct MeshWallSpec {
  std::string fix_id;  // ID of a fix mesh/surface (or a style derived from it)
  int kind = 0;        // 0 noslip, 1 freeslip, 2 partial, 3 sticky (imposed fraction of the wall's
                       // tangential velocity), 4 shear (wall shear stress mu (f w_t - v_t) / delta)
  double sticky = 1.0; // tangential damping in [0,1]; forced to 1 (noslip) or 0 (freeslip);
                       // kinds 3 and 4: the fraction f of the wall's tangential velocity
  double delta = 0.0;  // kind 4: thickness of the (unresolved) viscous wall layer, > 0 (length)
  int side = SIDE_NORMAL;  // MeshSide
};

class MeshWalls {
 public:
  // Validates the specs (fix exists, is a fix mesh/surface of triangles, sticky in [0,1], kind and
  // side known); throws std::runtime_error naming the fix ID and the problem. Not collective.
  MeshWalls(LAMMPS_NS::LAMMPS *lmp, std::vector<MeshWallSpec> specs);

  // Collective over lmp->world. Gathers the triangles (node positions and node velocities) whose
  // bounding box comes within 'margin' of this rank's patch box [patch_lo, patch_hi] (positions
  // of the first and last patch nodes), from the ranks that own them, including periodic images.
  // A rank with an empty patch passes lo > hi in any dimension. Re-looks the fixes up by ID (throws
  // if one was deleted). Call once per fluid sub-step (after the meshes moved, before the grid BCs).
  void refresh(const double patch_lo[3], const double patch_hi[3], double margin);

  // Applies the wall condition to the velocity vel of a grid node at x, for every gathered
  // triangle within 'reach' of x on its fluid side, or within 'reach_behind' (default: reach) of x
  // behind it (one-sided meshes only). Both reaches <= margin of the last refresh, else the query
  // scans all gathered triangles. Returns true if touched.
  bool apply(const double x[3], double vel[3], double reach, double reach_behind = -1.0,
             double h = 0.0) const;

  // apply() in two halves, for a node whose velocity is constrained more than once between two
  // refresh() calls (the fix's grid update and MUSL remap): collect() writes the constraints
  // apply() would impose at x (at most kMaxConstraints) and returns their number; impose() applies
  // them, in the same order, to vel.
  static constexpr int kMaxConstraints = 16;
  // near (optional): whether any triangle comes within max(reach, reach_behind) of x (false: no
  // wall condition, contact or crossing can concern anything that close to x).
  // A shear wall (kind 4) acts on the fluid mass within 'reach' of it: rate = nu / (delta reach)
  // (set_kinematic_viscosity() first).
  int collect(const double x[3], double reach, double reach_behind, WallConstraint *out,
              bool *near = nullptr) const;
  // h: the time over which a shear wall's stress acts (the grid update's step); h = 0 applies only
  // its normal condition (a second pass over the same velocities, e.g. the MUSL remap, must not
  // apply the stress again).
  static void impose(const WallConstraint *c, int n, double vel[3], double h = 0.0);
  // Kinematic viscosity of the fluid, for the shear walls (kind 4).
  void set_kinematic_viscosity(double nu) { nu_ = nu; }

  // Nearest triangle face to x within 'reach' (the closest point inside a triangle, not on an edge
  // or vertex only): q = that point, n = unit normal towards x's side (the fluid side of a
  // one-sided mesh; false if x is behind it). For the wall traction of the fix. reach <= margin.
  bool nearest_face(const double x[3], double reach, double q[3], double n[3]) const;

  // Material points. Undoes a crossing: (a) if x_old is given and the segment x_old -> x crosses a
  // triangle, x goes back to x_old's side of it; (b) for one-sided meshes, a point behind a
  // triangle (closest point inside the face, depth < reach) is put back on the fluid side. The
  // corrected point sits 'offset' (default 1e-3 * reach) off the plane, and its normal velocity
  // relative to the wall is zeroed. Returns true if x was changed.
  bool push_back(double x[3], double v[3], double reach, const double *x_old = nullptr) const;

  // Collective. For every mesh with side SIDE_AUTO: each of the n points x[i] votes with the sign
  // of its normal distance to the closest triangle face within 'reach'; the majority over all
  // ranks fixes the side. Throws if a mesh gets no vote. Needs a refresh() whose patch covers the
  // points. Returns a one-line summary per mesh (for the log).
  std::string infer_sides(const double *const *x, int n, double reach);

  // Sum over ranks of the local triangles of all meshes (collective); for logs and tests.
  long global_triangles() const;
  // Triangles gathered by the last refresh() on this rank (own and received, with images).
  int gathered() const { return static_cast<int>(tris_.size()); }
  // Current fluid side of mesh k (SIDE_NORMAL, SIDE_OPPOSITE, SIDE_BOTH or SIDE_AUTO if unset).
  int side(int k) const { return specs_[k].side; }
  const std::vector<MeshWallSpec> &specs() const { return specs_; }
  // Offset used by push_back (length); 0 = 1e-3 * reach.
  void set_offset(double off) { offset_ = off; }
  // Testing: false = every query scans all gathered triangles (no bins).
  void set_use_bins(bool on) { use_bins_ = on; }

  struct Tri {
    double p[3][3];   // node positions
    double w[3][3];   // node velocities
    double n[3];      // unit normal of the winding (not yet oriented)
    double lo[3], hi[3];
    int mesh;         // index into specs_
    long long key;    // 27 * global triangle ID + periodic image code (the order of application)
  };

 private:
  struct Hit {
    double p[3];      // closest point
    double b[3];      // barycentric weights of p
    double dist2;
    bool face;        // p lies strictly inside the triangle (face region)
  };
  static void closest_point(const Tri &t, const double x[3], Hit &h);
  void bins_build(const double box[6]);
  // Candidate triangles for a query ball (x, r); returns null if x lies outside the bins (then
  // every triangle is a candidate).
  const std::vector<int> *candidates(const double x[3]) const;
  void *resolve(int k) const;   // FixMeshSurface* of spec k (re-looked up by ID)

  LAMMPS_NS::LAMMPS *lmp_;
  std::vector<MeshWallSpec> specs_;
  std::vector<Tri> tris_;
  double offset_ = 0.0;
  bool use_bins_ = true;
  double margin_ = 0.0;
  double nu_ = 0.0;  // kinematic viscosity (shear walls)
  // uniform bins over [blo_, blo_ + nb_*bsize_]
  double blo_[3] = {0, 0, 0}, bsize_ = 1.0;
  int nb_[3] = {0, 0, 0};
  std::vector<std::vector<int>> bins_;
};

}  // namespace mpm
