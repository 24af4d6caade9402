// Boundary conditions of the fluid: grid faces (keyword boundary), the gate, mesh walls, the
// (8-23) wall traction and putting back points that crossed a wall. One component, used by the
// grid update and the MUSL remap (node velocities), P2G (traction) and the advection (points).
#pragma once
#include <cstddef>
#include <vector>

#include "mpm/grid.h"
#include "mpm/options.h"
#include "mpm/stencil.h"
#include "mpm/wall_geometry.h"

namespace mpm {

// (8-23) at a grid face for the quadratic B-spline: the first node inside the wall has the shape
// function 1/8 on it, so it carries 1/8 of the wall's push p V / dx of a point of the next cell
// (dir = +1 at the low face, -1 at the high one; inv = 1 / dx).
inline double face_traction_push(int dir, double p, double V, double inv) { return dir * 0.125 * p * V * inv; }

class Boundaries {
 public:
  void setup(const Options *opt, const LocalGrid *grid) {
    opt_ = opt;
    grid_ = grid;
  }
  // the mesh walls (none: null); the host moves their triangles, then calls walls_moved()
  void set_walls(const WallGeometry *w) { walls_ = w; }
  bool has_walls() const { return walls_ != nullptr; }
  const WallGeometry *walls() const { return walls_; }
  // after the mesh walls moved (once per fluid step): node constraints are collected anew
  void walls_moved();

  // Velocity of node (i, j, k) after the momentum update; h: the update's time step (the stress
  // of shear walls acts over it).
  // m > 0 with record_loads on: the momentum each mesh-wall condition gives the node's mass m,
  // m (v after - v before), is added to its wall's load (owned nodes only, so each counts once).
  void apply(double *vel, int i, int j, int k, double h, double m = 0.0);
  // (8-23) of one point (P2G, after its own scatter so that each node sums in point order):
  // grid faces and mesh walls, into the force rows of the P2G records.
  void add_traction(const Stencil &ps, const double *xp, double V, double p, double *p2g) {
    if (near_grid_face(ps)) add_face_traction(ps, xp, V, p, p2g);
    if (walls_) add_mesh_traction(xp, V, p, p2g);
  }
  // False only if the point of stencil ps is more than a cell from every grid face that gets a
  // traction (add_face_traction): its quadratic B-spline base node b = floor(xi + 1/2) - 1 is 0 or
  // less for xi < 1 and ncell - 2 or more for xi > ncell - 1.
  bool near_grid_face(const Stencil &ps) const {
    const GridSpec &gs = opt_->grid;
    for (int d = 0; d < 3; ++d)
      if (!gs.periodic[d] && gs.ncell[d] >= 2 && (ps.base[d] < 1 || ps.base[d] > gs.ncell[d] - 3)) return true;
    return false;
  }
  // A point moved from xold to x: put back on the fluid side of a mesh wall, a grid face or the
  // closed gate. Returns the number of corrections.
  // m > 0 with record_loads on: the momentum a mesh wall gives the point, m (v after - v before),
  // is added to that wall's load.
  // gone (not null): set when the point left through an outflow face (placed on its inner side,
  // velocity along it 0, not counted as a correction)
  int put_back(double x[3], double v[3], const double xold[3], double m = 0.0, bool *gone = nullptr);

  // Wall loads (mesh_wall ... loads yes; docs/theory/mesh_walls.md, "Force and torque on a mesh"):
  // the momentum the mesh walls give the fluid, per wall 6 values (impulse, and its moment about
  // the wall's reference point), summed from record_loads(h) until take_loads. h: the sub-step of
  // the (8-23) traction, a force. Off (no cost) until record_loads is called.
  // With grid damping c a velocity change dv made after the update's division by s = 1 + h c is
  // the impulse m s dv (s u_new = u_old + h (f + f_wall) / m: the damping acts on the final
  // velocity, not on the wall's share), so apply records m s dv (load_scale: s).
  void record_loads(double h);
  bool recording() const { return rec_on_; }
  double load_scale() const { return rec_s_; }
  // adds the impulse J that wall k gives the fluid at x (nothing for a wall without loads)
  void add_impulse(int k, const double *x, const double *J);
  // the normal (towards the fluid) of the first mesh-wall condition of node (i, j, k); false: none
  bool node_normal(int i, int j, int k, double n[3]) {
    if (!walls_) return false;
    const std::size_t c = node_walls(i, j, k);
    if (count_[c] == 0) return false;
    for (int d = 0; d < 3; ++d) n[d] = cache_[first_[c]].n[d];
    return true;
  }
  // The mesh wall that takes an impulse along d of sign 'sign' at x (node (i, j, k); cached per
  // wall position): the boundary the grid line through x along d meets first on either side, a
  // triangle or a grid face (non-periodic); on a tie the one on the side the impulse points away
  // from. -1: a grid face, or none.
  int line_wall(int i, int j, int k, const double x[3], int d, double sign);
  // adds the sums since record_loads to out (6 per wall) and zeroes them
  void take_loads(std::vector<double> &out);

 private:
  void add_face_traction(const Stencil &ps, const double *xp, double V, double p, double *p2g);
  void add_mesh_traction(const double *xp, double V, double p, double *p2g);
  std::size_t node_walls(int i, int j, int k);
  bool near_wall(const double *x);

  const Options *opt_ = nullptr;
  const LocalGrid *grid_ = nullptr;
  const WallGeometry *walls_ = nullptr;
  // per node: the mesh-wall constraints of the current wall positions (entries first_ .. + count_
  // of cache_, collected at the node's first use after a move: stamp_ == epoch_)
  std::vector<WallConstraint> cache_;
  long epoch_ = 0;
  std::vector<long> stamp_;
  std::vector<int> first_, count_;
  std::vector<char> near_;
  bool rec_on_ = false;
  double rec_h_ = 0.0;
  double rec_s_ = 1.0;
  std::vector<double> rec_;
  std::vector<long> ln_stamp_;
  std::vector<int> ln_;      // per node and d: wall below, wall above (-1 grid face / none)
  std::vector<double> lt_;   // their distances
};

}  // namespace mpm
