// Fluid wall conditions on triangle walls: the geometry alone (no LIGGGHTS, no MPI). The triangles
// (node positions and velocities) are handed in by liggghts_mpm/mesh_walls.h, which reads them from
// LIGGGHTS meshes and gathers them over the ranks; docs/theory/mesh_walls.md.
//
// At a grid node the wall condition acts in the wall's frame:
//   relative velocity r = v - w (w = wall velocity at the closest point),
//   normal part   r.n -> max(0, r.n) on the fluid side, 0 behind the wall,
//   tangential    r_t -> (1 - sticky) r_t;
// kinds 'sticky f' and 'shear delta f' work on the tangential velocity relative to f times the
// wall's tangential velocity instead (imposed, or relaxed by the wall shear stress; see impose()).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace mpm {

// Wall condition of a mesh (keyword mesh_wall of fix mpm/fluid).
enum WallKind : int {
  WALL_NOSLIP = 0,    // no relative velocity
  WALL_FREESLIP = 1,  // no relative normal velocity into the wall
  WALL_PARTIAL = 2,   // freeslip, and a fraction 'sticky' of the relative tangential velocity removed
  WALL_STICKY = 3,    // tangential velocity imposed: 'sticky' times the wall's
  WALL_SHEAR = 4      // tangential velocity relaxed towards 'sticky' times the wall's by the stress
                      // mu (f w_t - v_t) / delta of an unresolved viscous layer of thickness delta
};

// Fluid side of a mesh, relative to the triangles' normals (right-hand rule on the STL winding
// n0 -> n1 -> n2, i.e. the normals LIGGGHTS computes).
enum MeshSide : int {
  SIDE_NORMAL = 1,     // the fluid is on the side the normals point to
  SIDE_OPPOSITE = -1,  // the fluid is on the other side
  SIDE_AUTO = 0,       // decided from where the material points are (side votes)
  SIDE_BOTH = 2        // thin two-sided wall (a plate): no "behind"; only crossings are undone
};

// The condition of one wall mesh.
struct WallSpec {
  WallKind kind = WALL_NOSLIP;
  double sticky = 1.0;  // tangential damping in [0,1]; forced to 1 (noslip) or 0 (freeslip);
                        // sticky and shear: the fraction f of the wall's tangential velocity
  double delta = 0.0;   // shear: thickness of the (unresolved) viscous wall layer, > 0 (length)
  bool delta_auto = false;  // shear auto: delta = sqrt(2 nu / omega), the Stokes layer of the
                            // mesh's rotation rate omega (fitted to its triangles' velocities)
  int side = SIDE_NORMAL;  // MeshSide
  double ref[3] = {0.0, 0.0, 0.0};  // reference point of the fluid's torque on the wall (mesh_wall reference_point)
  bool loads = false;  // mesh_wall loads yes: the fluid's force and torque on the wall are computed
};

// Checks s (kind and side known, sticky in [0,1], delta > 0 for shear) and forces sticky of the
// noslip and freeslip kinds. Returns "" if valid, else the problem in words.
std::string check_wall(WallSpec &s);

// One wall condition at a grid node: wall velocity w at the closest point, unit normal n towards
// the fluid, whether the node is behind the wall, the tangential fraction (sticky) and whether it
// is imposed (sticky kind) rather than damped; rate > 0 (shear kind): the relaxation rate (1/time)
// of the tangential velocity towards sticky times the wall's, from the wall shear stress.
struct WallConstraint {
  double w[3];
  double n[3];
  double sticky;
  double rate;
  bool behind;
  bool imposed;
  int wall;  // the mesh (wall index) the condition belongs to
};

// Relaxation rate (1/time) of the tangential slip of the fluid within 'depth' of a wall whose
// unresolved viscous layer of thickness delta carries the stress mu v_slip / delta: the law of the
// shear kinds of mesh walls and grid faces (docs/theory/mesh_walls.md).
inline double wall_layer_rate(double nu, double delta, double depth) { return nu / (delta * depth); }

// Fraction of the tangential slip (v_t - f w_t) left after a time h at relaxation rate 'rate': the
// exact solution of dv_t/dt = -rate (v_t - f w_t) over h. The decay law of the shear walls (mesh
// walls and grid faces).
inline double wall_slip_decay(double rate, double h) { return std::exp(-rate * h); }

class WallGeometry {
 public:
  struct Tri {
    double p[3][3];   // node positions
    double w[3][3];   // node velocities
    double n[3];      // unit normal of the winding (not yet oriented)
    double lo[3], hi[3];
    int mesh;         // index of the wall (WallSpec) the triangle belongs to
    long long key;    // e.g. 27 * global triangle ID + periodic image code (the order of application)
    // the normal of the smooth surface the mesh stands for at the corners (cn) and the normal
    // speed along it there (vn) (set_corner_frames; set by set_triangles), used where 'smooth'
    double cn[3][3] = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    double vn[3] = {0.0, 0.0, 0.0};
    bool smooth = false;
  };
  // Closest point of a triangle to a point.
  struct Hit {
    double p[3];      // closest point
    double b[3];      // barycentric weights of p
    double dist2;
    bool face;        // p lies strictly inside the triangle (face region)
  };
  static constexpr int kMaxConstraints = 16;

  // Throws std::invalid_argument if a wall fails check_wall().
  explicit WallGeometry(std::vector<WallSpec> walls = {});

  // Completes t from its node positions p: the unit normal n and the bounding box. False if t is
  // degenerate (zero area), which then must not be added. Inline (below) on purpose: compiled in
  // the loop that fills the triangles, the normals round as they did before the geometry had a
  // file of its own (FMA contraction of the cross product depends on the context).
  static bool finish_tri(Tri &t);
  // Replaces the triangles (finished, t.mesh < number of walls). Queries within 'margin' of the
  // box [box[0..2], box[3..5]] use bins (an empty box, lo > hi in some dimension: no bins, every
  // query scans all triangles). Returns false, and keeps what it has, if the triangles (after
  // sorting), the box and the margin are those of the last call to the bit: walls at rest need no
  // new constraints at the nodes.
  bool set_triangles(std::vector<Tri> tris, const double box[6], double margin);

  // The normal of the smooth surface a mesh of flat triangles stands for, at each corner of each
  // triangle: the angle-weighted mean of the normals of the triangles of the same wall that share
  // the corner's vertex (the same position to the bit) and whose normal lies within kSmoothCos
  // of the triangle's own (an edge sharper than that, such as a lifter bar's, is a real edge).
  // 'all' holds every triangle of every wall once (no periodic images), finished; the corner
  // normals are kept per (wall, triangle ID = key / 27) in the triangle's own frame (normal, first
  // edge, their cross product), so that they follow a rigid motion of the mesh, and set_triangles
  // gives every triangle with such a frame the normal speeds vn of its corners. A rotating
  // tessellated surface of revolution (a drum, a jar) then moves along itself at the grid's
  // closed faces (crosses): the flat facets' own normal motion, omega times the distance from a
  // facet's centre line, is a source of fluid at the scale of the facets that the grid cannot
  // resolve (docs/theory/projection.md, "Mesh walls").
  void set_corner_frames(const std::vector<Tri> &all);
  static constexpr double kSmoothCos = 0.8660;  // 30 degrees

  // Applies the wall condition to the velocity vel of a grid node at x, for every triangle within
  // 'reach' of x on its fluid side, or within 'reach_behind' (default: reach) of x behind it
  // (one-sided meshes only). Both reaches <= margin, else the query scans all triangles. Returns
  // true if touched.
  bool apply(const double x[3], double vel[3], double reach, double reach_behind = -1.0,
             double h = 0.0) const;

  // apply() in two halves, for a node whose velocity is constrained more than once between two
  // set_triangles() calls (the fix's grid update and MUSL remap): collect() writes the constraints
  // apply() would impose at x (at most kMaxConstraints) and returns their number; impose() applies
  // them, in the same order, to vel.
  // near (optional): whether any triangle comes within max(reach, reach_behind) of x (false: no
  // wall condition, contact or crossing can concern anything that close to x).
  // A shear wall acts on the fluid mass within 'reach' of it: rate = nu / (delta reach)
  // (set_kinematic_viscosity() first).
  int collect(const double x[3], double reach, double reach_behind, WallConstraint *out,
              bool *near = nullptr) const;
  // h: the time over which a shear wall's stress acts (the grid update's step); h = 0 applies only
  // its normal condition (a second pass over the same velocities, e.g. the MUSL remap, must not
  // apply the stress again).
  static void impose(const WallConstraint *c, int n, double vel[3], double h = 0.0);
  // Kinematic viscosity of the fluid, for the shear walls.
  void set_kinematic_viscosity(double nu) { nu_ = nu; }
  // Rotation rate |omega| (rad/time) of wall k fitted to the velocities of its triangles' nodes
  // held now (rigid motion w = v0 + omega x (x - c), least squares; 0 without triangles of wall k
  // or for a translating or resting wall), and the wall layer thickness its shear condition uses
  // (delta, or sqrt(2 nu / |omega|) with shear auto: infinite for a wall that does not turn).
  double rotation_rate(int k) const { return k < static_cast<int>(omega_.size()) ? omega_[k] : 0.0; }
  double layer_thickness(int k) const;

  // Nearest triangle face to x within 'reach' (the closest point inside a triangle, not on an edge
  // or vertex only): q = that point, n = unit normal towards x's side (the fluid side of a
  // one-sided mesh; false if x is behind it). For the wall traction of the fix. reach <= margin.
  // wall (optional): the mesh of that triangle.
  bool nearest_face(const double x[3], double reach, double q[3], double n[3], int *wall = nullptr) const;

  // The wall (mesh index) of the nearest triangle within 'reach' of x (-1: none), *dist its distance.
  int nearest_wall(const double x[3], double reach, double *dist) const;

  // The first triangle the ray from x along side e_d (side -1 or +1) meets within 'len': returns its
  // wall (-1: none) and *t the distance to it.
  int ray_wall(const double x[3], int d, int side, double len, double *t) const;

  // Material points. Undoes a crossing: (a) if x_old is given and the segment x_old -> x crosses a
  // triangle, x goes back to x_old's side of it; (b) for one-sided meshes, a point behind a
  // triangle (closest point inside the face, depth < reach) is put back on the fluid side. The
  // corrected point sits 1e-3 * reach off the plane, and its normal velocity relative to the wall
  // is zeroed. Returns true if x was changed.
  // wall (optional): the mesh of the last correction (unchanged if none).
  bool push_back(double x[3], double v[3], double reach, const double *x_old = nullptr, int *wall = nullptr) const;

  // Side votes of the n points x[i] for every one-sided wall (side SIDE_AUTO, SIDE_NORMAL or
  // SIDE_OPPOSITE; not SIDE_BOTH): each point votes with the
  // sign of its normal distance to the closest triangle face within 'reach'. Adds to
  // votes[2 k] (normal side) and votes[2 k + 1] (opposite side), k < walls().
  void side_votes(const double *const *x, int n, double reach, long *votes) const;

  // The pressure projection (docs/theory/projection.md, "Mesh walls").
  // Whether the segment from a to a + len e_d (len > 0) crosses a triangle: its ends lie on
  // different sides of the triangle's plane (one-sided meshes: an end in the plane counts as on the
  // fluid side; two-sided meshes: an end in the plane, the other not, is a crossing, so a node in
  // a two-sided wall is cut off on both sides) and the crossing point inside the triangle (1e-9 in
  // barycentric weights). *w_d: the d component of the wall velocity's normal part, (w . n) n_d,
  // at the crossing (of the first such triangle in the fixed order): a wall moving along itself
  // is no source of fluid (docs/theory/projection.md, "Mesh walls"); on a triangle with corner
  // frames (set_corner_frames) the normal speed w . n is the corners' smooth-surface normal
  // speeds vn interpolated to the crossing. len <= margin, else all triangles are scanned.
  bool crosses(const double a[3], int d, double len, double *w_d) const;
  // Side of x with respect to the nearest triangle within 'reach': -1 behind a one-sided mesh
  // (behind the planes of all equally near triangles; face hits first), +1 in front of one,
  // 0 none within reach or the nearest is two-sided. *dist: the distance to it (reach if none).
  // dist_off (optional, kWallDirs entries): the walls of one-sided meshes within reach that do not
  // lie in one of the planes x_d = c given as (d, c) (the faces of the grid box, behind which the
  // fluid's mirror image stands already), from the same scan: where the nearest of their
  // triangles is a face hit that x is in front of, the distance to the nearest face in each of up
  // to kWallDirs directions (normals within kCos of each other are one direction; the nearest
  // directions), x in a concave corner being in front of several; else (x beyond an edge or a
  // vertex, or behind) the distance to the nearest triangle alone. Unused entries: reach.
  static constexpr int kWallDirs = 3;
  int node_side(const double x[3], double reach, double *dist,
                const std::vector<std::pair<int, double>> *planes = nullptr, double *dist_off = nullptr) const;

  int walls() const { return static_cast<int>(walls_.size()); }
  const WallSpec &wall(int k) const { return walls_[k]; }
  // Fluid side of wall k (a MeshSide other than SIDE_AUTO).
  void set_side(int k, int side) { walls_[k].side = side; }
  // Triangles of the last set_triangles() (sorted by wall, then key).
  int gathered() const { return static_cast<int>(tris_.size()); }
  const std::vector<Tri> &triangles() const { return tris_; }
  // Testing: false = every query scans all triangles (no bins).
  void set_use_bins(bool on) { use_bins_ = on; }

  // Closest point of triangle t to x, with barycentric weights; a point whose projection falls on
  // the triangle's boundary (within 1e-9 in barycentric weights) counts as a face hit.
  static void closest_point(const Tri &t, const double x[3], Hit &h);

 private:
  // collect's steps (wall_constraints.cpp): the candidates nearest first (at most kCand), the hits
  // kept (at most kMax, one per wall direction of a mesh: directions within kCos), the constraints
  static constexpr int kCand = 512, kMax = 16;
  static constexpr double kCos = 0.8660;  // 30 degrees
  struct KeptHits {
    int idx[kMax];
    Hit hits[kMax];
    double dd[kMax][3];   // x - closest point
    double dir[kMax][3];  // direction of the hit (unsigned for faces)
    bool back[kMax];      // behind the triangle's plane (one-sided meshes)
    int nh = 0;
  };
  int nearest_candidates(const double x[3], double reach, const std::vector<int> *cand, int ncand,
                         std::pair<double, int> *cl) const;
  void keep_hits(const double x[3], double reach, double r2, const std::pair<double, int> *cl, int ncl,
                 KeptHits &kept) const;
  int constraints(const KeptHits &kept, double reach, double reach_fluid, double rf2, double rb2,
                  WallConstraint *out) const;
  // push_back's steps (wall_constraints.cpp): one crossing undone, one point out from behind
  bool push_across(double x[3], double v[3], const double *x_old, double off, int *wall) const;
  bool push_from_behind(double x[3], double v[3], double reach, double off, int *wall) const;
  void bins_build(const double box[6]);
  // Candidate triangles for a query ball (x, r); returns null if x lies outside the bins (then
  // every triangle is a candidate).
  const std::vector<int> *candidates(const double x[3]) const;

  std::vector<WallSpec> walls_;
  std::vector<Tri> tris_;
  bool use_bins_ = true;
  double margin_ = 0.0;
  double box_[6] = {0, 0, 0, 0, 0, 0};  // of the last set_triangles
  bool have_set_ = false;
  double nu_ = 0.0;  // kinematic viscosity (shear walls)
  std::vector<double> omega_;  // rotation rate of each wall (set_triangles)
  void fit_rotation();
  // set_corner_frames: per wall and triangle ID, the corner normals' coefficients (normal, first
  // edge, their cross product) of the three corners; normal_speeds() applies them to tris_
  std::unordered_map<long long, std::array<double, 9>> frames_;
  void normal_speeds();
  // uniform bins over [blo_, blo_ + nb_*bsize_]
  double blo_[3] = {0, 0, 0}, bsize_ = 1.0;
  int nb_[3] = {0, 0, 0};
  std::vector<std::vector<int>> bins_;
};

// Small vector helpers of the geometry (inlined into the callers).
namespace geom {
inline double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline void sub3(const double *a, const double *b, double *c) {
  c[0] = a[0] - b[0];
  c[1] = a[1] - b[1];
  c[2] = a[2] - b[2];
}
}  // namespace geom

inline bool WallGeometry::finish_tri(Tri &t) {
  double e1[3], e2[3];
  geom::sub3(t.p[1], t.p[0], e1);
  geom::sub3(t.p[2], t.p[0], e2);
  t.n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  t.n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  t.n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const double a2 = std::sqrt(geom::dot3(t.n, t.n));
  const double l2 = std::max(geom::dot3(e1, e1), geom::dot3(e2, e2));
  if (!(a2 > 1e-12 * l2) || l2 <= 0.0) return false;  // degenerate (zero area) triangle
  for (int d = 0; d < 3; ++d) {
    t.n[d] /= a2;
    t.lo[d] = std::min({t.p[0][d], t.p[1][d], t.p[2][d]});
    t.hi[d] = std::max({t.p[0][d], t.p[1][d], t.p[2][d]});
  }
  return true;
}

}  // namespace mpm
