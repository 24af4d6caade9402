// The pressure projection's volume correction (a drift of the points' positions) and the
// pressures it reports: the acceleration pressure, the time average, the largest nodal pressure
// (docs/theory/projection.md).
#include "mpm/projection.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "mpm/error.h"
#include "mpm/grid_fields.h"
#include "mpm/projection_ops.h"

namespace mpm {

namespace {
// volume correction: the error |phi - 1| it leaves alone. A point lattice moving with a fluid
// samples phi = sum S V / volume with an error of a few per cent that comes and goes with the
// flow; corrected, it moved the surface of a standing wave of 2 % of the depth: amplitude over
// three periods 0.84 of its start with no band, 1.003 with 0.02, 0.953 with 0.05 (0.953 without
// any correction); the sloshing tank's volume after 10 s 1.007 / 1.009 / 1.018 of the start
// (docs/theory/projection.md, "Volume drift and `volume_correction`")
constexpr double kVolumeBand = 0.02;
}  // namespace

/* Volume correction (keyword volume_correction k, docs/theory/projection.md "Volume drift"). The
   points hold their volume V = m / (theta rho0), but the approximate projection makes the nodal
   velocities divergence-free only up to its approximation error, so the point cloud drifts: where
   the flow converges the points crowd, elsewhere they open gaps (F2 dam break, MPM16 apic, 2 s:
   3 to 5 % of the held volume overlapping, the fluid's volume on the grid 3.4 % below the held
   one). The points' volume on the grid, phi_n = sum_p S_np V_p / (dx^3 volume(n)), is 1 where
   they fill the space evenly (exactly, at rest, for a regular fill); the shares the B-spline gives
   to the padding nodes behind a box wall count at their mirror node inside (as the coupling folds
   the grains' volume). The source of the correction's own solve (volume_drift) removes the
   share a = min(k M h, 1) of the error e = phi - 1 (beyond kVolumeBand) on every M-th step
   (volume_correction_every): the drift w it gives has
       D(w) = volume(n) theta_n a e_n / h,
   i.e. rhs_n -= volume(n) theta_n a e_n / h^2: crowded points (e > 0) are pushed apart, and gaps
   (e < 0) drawn together, but the latter only where no EMPTY node is among the 26 neighbours
   (deep_inside): under the free surface phi falls from 1 to 0 over 1.5 cells and is no error;
   beside mesh walls phi is read against the fill an even fill gives there (expected_fill).
   Measured: correcting compression alone removed it better but opened gaps, the fluid's volume
   on the grid growing by 2-8 % (docs/theory/projection.md). The density-error source of the pressure
   equation of Kugelstadt, Longva, Thuerey & Bender (2021), "Implicit density projection for
   volume conserving liquids", IEEE TVCG 27(4), applied as they do to the positions, with the
   projection's operator. */
void Projection::add_volume_correction(const double *pvol, const double *theta, double h, double a) {
  const GridSpec &gs = opt_.grid;
  vol_.assign(pvol, pvol + grid_.size());
  grid_.forward(vol_.data(), 1);  // the padding nodes' shares, wherever they are owned
  const double dx = gs.dx, dx3 = dx * dx * dx;
  const int np = std::max({opt_.fill_ppc[0], opt_.fill_ppc[1], opt_.fill_ppc[2]});
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (lab_.kind[n] != kFluid || near_flow_face(i, j, k)) return;
    const double sum = mirror_sum(vol_, i, j, k);
    const double cv = geo_.volume(i, j, k);
    // the part of the error beyond the band kVolumeBand: what the points' own sampling of a
    // moving fluid gives is left alone; beside a mesh wall, crowding and gaps are read against
    // the fill a lattice at rest there can have (expected_fill) in place of 1
    double crowd = 1.0, gap = 1.0;
    if (mesh_) expected_fill(i, j, k, n, np, &crowd, &gap);
    const double fill = sum / (dx3 * cv);
    double e = fill / crowd - 1.0;
    if (e > kVolumeBand) {
      e -= kVolumeBand;
    } else {
      e = fill / gap - 1.0;
      e = e < -kVolumeBand ? e + kVolumeBand : 0.0;
    }
    // a partly filled node under the surface
    if (e < 0.0 && !deep_inside(i, j, k)) return;
    const double th = theta ? theta[n] : 1.0;
    rhs_[n] -= cv * th * a * e / (h * h);
  });
}

/* Within two nodes of an inflow or outflow face phi follows the phase of the points' lattice as it
   moves through the face (no mirror image of the fluid in front of an inflow or beyond an outflow):
   no error there. Counted, it drew the points of a column fed from below at U = 0.05 m/s back
   towards the inflow at 0.018 m/s (a uniform drift from the inflow to the outflow's p = 0), and
   near the outflow alone it moved the top layers 2-5 % faster than U (a layer left at step 95
   instead of 101); left out at both, every layer moves at U (test mpm_case.flow_faces_balance). */
bool Projection::near_flow_face(int i, int j, int k) const {
  const GridSpec &gs = opt_.grid;
  const int idx[3] = {i, j, k};
  for (int d = 0; d < 3; ++d) {
    if (gs.periodic[d]) continue;
    if (opt_.face[2 * d].flow() && idx[d] <= 2) return true;
    if (opt_.face[2 * d + 1].flow() && idx[d] >= gs.ncell[d] - 2) return true;
  }
  return false;
}

/* The volume correction as a drift of the points' positions (Kugelstadt et al. 2021 correct
   the positions too): the solve of the projection's operator with the volume error alone as its
   source gives the potential q, and w = -(dt / rho) grad q is the velocity whose divergence
   removes the fraction a of the error this step. The points move by dt w on top of the fluid's
   velocity; w never enters their velocity, so the correction neither adds momentum nor energy
   (as a source in the velocity's own solve it entered the points' velocity, which FLIP keeps;
   docs/theory/projection.md "Volume drift and `volume_correction`"). Zero first guess:
   the drift of a step is a function of that step's state only (restart, np 2 = np 1). */
void Projection::volume_drift(const double *pvol, const double *theta, double h, double share, long step) {
  const std::size_t n = grid_.size();
  rhs_.assign(n, 0.0);
  add_volume_correction(pvol, theta, h, share);
  q_.assign(n, 0.0);
  grad_q_.assign(3 * n, 0.0);
  drift_.assign(3 * n, 0.0);
  solve_rhs(q_.data(), step, "the volume correction's solve");
  grid_.forward(q_.data(), 1);
  pressure_gradient(grid_, lab_, q_.data(), grad_q_.data(), theta_now_);
  grid_.for_owned([&](int, int, int, std::size_t m) {
    if (lab_.kind[m] == kSolid) return;
    for (int d = 0; d < 3; ++d) drift_[3 * m + d] = -h * inv_rho_[m] * grad_q_[3 * m + d];
  });
  grid_.forward(drift_.data(), 3);
}

/* Beside a mesh wall the share of the shape function behind the triangle holds no points and has
   no mirror image, so the fill of a node s cells in front of the wall is F(s) (continuum_fill) for
   an even fill up to the wall, not 1. A lattice of points seeded or moving beside the wall ends
   within half a spacing b = 1 / (2 np) cells of where an even fill would: at rest the fill lies
   between F(s - b) and F(s + b). Crowding is read against F(s + b), gaps against F(s - b), each
   as the product over the nearest walls in up to kWallDirs directions (on the edge of a closed
   box of mesh walls a node holds 0.5 x 0.5 of its cell; read against one wall's F(-b) = 0.318 it
   counted as a gap, and the water in the box sank 2.5 mm in 0.6 s). Counted as gaps
   with 1 in place of F, the missing share moved columns at rest beside vertical / 30 / 60 degree
   walls at 8.4e-3 / 1.0e-2 / 6.0e-2 m/s after 1 s with k = 10 (test mpm_case.projection_mesh_rest);
   read from 1.5 + b cells off the wall only, the flow along a turning jar's mantle emptied the
   half cell there and the level at rest rose by 7-9 % (docs/theory/projection.md, "Beside mesh
   walls"). Within one node of a box face the crowding is read
   against 1 (mirror_sum folds the image of the fluid behind the face there, and with it a share
   that a wall at an angle to the face leaves out: beside a 30 degree wall the corner node on the
   floor read 0.985 against F(s + b) = 0.939, and the drift broke the column's hydrostatic rows by
   0.25 rho g dz). */
void Projection::expected_fill(int i, int j, int k, std::size_t n, int np, double *crowd, double *gap) const {
  const double *s = &wall_dist_[WallGeometry::kWallDirs * n], b = 0.5 / np;
  if (s[0] >= kWallFar) return;
  double fc = 1.0, fg = 1.0;
  for (int q = 0; q < WallGeometry::kWallDirs && s[q] < kWallFar; ++q) {
    fc *= continuum_fill(s[q] + b, opt_.shape);
    fg *= continuum_fill(s[q] - b, opt_.shape);
  }
  *gap = fg;
  const GridSpec &gs = opt_.grid;
  const int idx[3] = {i, j, k};
  for (int d = 0; d < 3; ++d)
    if (!gs.periodic[d] && (idx[d] <= 1 || idx[d] >= gs.ncell[d] - 1)) return;
  *crowd = fc;
}

// no EMPTY node among the 26 neighbours: phi is within the band kVolumeBand of 1 there for a
// regular fill (under the surface phi falls from 1 to 0 over 1.5 cells: one node below the last
// FLUID one it is F(1) = 0.979 for the quadratic B-spline). With two nodes instead, a tank 5 cells
// deep had almost no node where gaps were closed, only crowding was corrected, and the water's
// volume grew by 1-3 % over 10 s of sloshing (20 cells along 1 m, stopped at 9.5 / 10 / 10.5 /
// 11 s: 1.034 / 1.020 / 1.025 / 1.021; now 1.004 / 1.000 / 1.000 / 1.003)
bool Projection::deep_inside(int i, int j, int k) const {
  for (int c = -1; c <= 1; ++c)
    for (int b = -1; b <= 1; ++b)
      for (int a = -1; a <= 1; ++a)
        if (grid_.in_patch(i + a, j + b, k + c) && lab_.kind[grid_.index(i + a, j + b, k + c)] == kEmpty) return false;
  return true;
}


/* pressure_output acceleration (docs/theory/projection.md, "The pressure the points carry"). The
   projection's p is the Lagrange multiplier that makes this step's velocity divergence-free: it
   removes whatever divergence the step's u* holds, the transfer's as well (FLIP and APIC do not
   give back on the grid the divergence-free velocity they took from it), in one step h, so that
   part of it is of order rho |du| dx / h and grows without bound as h shrinks (C3, F2 dam break,
   docs/validation/tank.md). The pressure of the incompressible Navier-Stokes equations is instead fixed by
   the velocity field and the forces alone: with Du/Dt = a_f - grad p / rho and div u = 0,
       div(beta grad p) = div(theta (a_f - (u . grad) u)),   no normal acceleration at walls,
   p = 0 at the free surface. Here u is the projected velocity, a_f the grid forces per mass of the
   step (gravity, viscosity, drag: (u* - u_old) / h, with grid damping c (1 + h c) u* in place of u*,
   and the damping's - c u), (u . grad) u by central differences
   between FLUID nodes (one-sided next to a non-FLUID node). The same operator and labels as the
   projection: at rest it is the projection's hydrostatic pressure. Not in it: d(theta)/dt of moving
   grains, the acceleration of walls. */
void Projection::acceleration_pressure(const double *vel, const double *theta, double h, const double *p2g,
                                      double mmin, long step) {
  const double inv2dx = 0.5 / opt_.grid.dx, invdx = 1.0 / opt_.grid.dx, c = opt_.damping;
  const long s[3] = {1, static_cast<long>(grid_.stride_y()), static_cast<long>(grid_.stride_z())};
  grid_.for_owned([&](int, int, int, std::size_t n) {
    double *a = &acc_[3 * n];
    if (lab_.kind[n] != kFluid) {
      a[0] = a[1] = a[2] = 0.0;
      return;
    }
    const double *rec = vel + VelRec::N * n;
    // V_NEW still holds u*: the forces of the step per mass
    for (int d = 0; d < 3; ++d) a[d] = (rec[VelRec::V_NEW + d] - rec[VelRec::V_OLD + d]) / h;
    const double *u = &u_[3 * n];
    if (c > 0.0)  // damped u* = (u_old + h f / m) / (1 + h c): the forces f / m and the damping's - c u
      for (int d = 0; d < 3; ++d) a[d] = ((1.0 + h * c) * rec[VelRec::V_NEW + d] - rec[VelRec::V_OLD + d]) / h - c * u[d];
    for (int e = 0; e < 3; ++e) {  // - u_e d/dx_e u
      const std::size_t lo = n - s[e], hi = n + s[e];
      const bool fl = lab_.kind[lo] == kFluid, fh = lab_.kind[hi] == kFluid;
      if (!fl && !fh) continue;
      for (int d = 0; d < 3; ++d) {
        const double du = fl && fh ? (u_[3 * hi + d] - u_[3 * lo + d]) * inv2dx
                                   : fh ? (u_[3 * hi + d] - u[d]) * invdx : (u[d] - u_[3 * lo + d]) * invdx;
        a[d] -= u[e] * du;
      }
    }
  });
  grid_.forward(acc_.data(), 3);
  acceleration_rhs(grid_, lab_, geo_, acc_.data(), theta, rhs_.data());
  // (with theta / rho0 in every direction, also where the projection's solve has the exact
  // exchange's coefficients: the pressure of the acceleration of the fluid as it is)
  solve_rhs(p_acc_.data(), step, "the solve for the pressure of the acceleration (keyword 'pressure_output' or 'grain_pressure' acceleration)");
  // behind mesh walls extrapolated linearly with its own gradient, as the multiplier (at rest
  // beside a 30 degree wall one pressure per row of points to 2e-11 rho g dx; with the mean of the
  // neighbours behind the wall instead, 0.27 rho g dx)
  // grain_pressure acceleration: the grains feel its gradient, formed as the multiplier's (the
  // surface layers of the ghost-fluid surface included)
  const bool grains = opt_.grain_pressure_acceleration;
  if (mesh_ || grains) form_gradient(p_acc_, grad_acc_, p2g, mmin, grains, false);
  extend_for_points(p_acc_, grad_acc_, p2g, mmin, p_acc_ext_, grains ? &grad_acc_ext_ : nullptr);
  if (grains && theta && !mesh_) mirror_to_padding(grad_acc_, grad_acc_ext_);
}

/* The pressure a sensor of finite response time reads (keyword pressure_average tau). Under the
   projection an impact or a transfer event that must change the velocity within one fluid step h
   gives a pressure of order rho |du| dx / h for that step: the pressure impulse (its integral over
   time) converges as h shrinks, the single-step peak does not (docs/validation/tank.md). The exponential
   average pa += (1 - exp(-h / tau)) (p - pa) responds to an impulse I with I / tau, independent of
   h, and to a steady pressure with that pressure. Nodes hold a fixed place, as a wall sensor. */
void Projection::average_pressure(double h) {
  const double tau = opt_.pressure_average;
  if (tau > 0.0) {
    const double a = have_avg_ ? -std::expm1(-h / tau) : 1.0;  // the first solve starts the average
    const std::vector<double> &p = opt_.pressure_acceleration ? p_acc_ : p_;
    // every owned node, work box or not: the average decays where the fluid has gone
    grid_.for_owned_all([&](int, int, int, std::size_t n) { p_avg_[n] += a * (p[n] - p_avg_[n]); });
    have_avg_ = true;
  }
  largest_pressure();
}

void Projection::largest_pressure() {
  const std::vector<double> &a = have_avg_ ? p_avg_ : opt_.pressure_acceleration ? p_acc_ : p_;
  double mx = -HUGE_VAL;
  grid_.for_owned_all([&](int, int, int, std::size_t n) { mx = std::max(mx, a[n]); });
  p_avg_max_ = mx;
}

}  // namespace mpm
