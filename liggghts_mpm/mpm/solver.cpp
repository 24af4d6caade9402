// The solver's step (substep) and the phases that are neither transfer (transfer.cpp) nor
// coupling (coupling.cpp): shape functions, grid update, stress update, advection.
#include "mpm/solver.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <sstream>

#include "mpm/error.h"
#include "mpm/projection.h"

namespace mpm {

FluidSolver::FluidSolver(const Options &o, MPI_Comm comm) : opt(o), comm_(comm), pressure_(PressureModel::make(opt)), coup_(CouplingModel::make(opt)) {
  MPI_Comm_rank(comm_, &me_);
  MPI_Comm_size(comm_, &nprocs_);
  bc.setup(&opt, &grid_);
}

FluidSolver::~FluidSolver() = default;

std::string FluidSolver::check_points() {
  int bad = 0, anybad = 0;
  for (int i = 0; i < pts.nlocal; ++i)
    if (is_point(i) && pts.state[i][C_FLAG] != 1.0) bad = 1;
  MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_MAX, comm_);
  if (anybad)
    throw Error("Fix mpm/fluid: the fix group contains atoms that are not material points of this fix "
                "(use a group of the fill type only)");
  if (!opt.coupled) return "";
  double dmax = 0.0, gd = 0.0;
  int overlap = 0, go = 0;
  for (int i = 0; i < pts.nlocal; ++i) {
    if (!(pts.mask[i] & pts.grain_bit)) continue;
    if (is_point(i)) overlap = 1;
    dmax = std::max(dmax, 2.0 * pts.radius[i]);
  }
  MPI_Allreduce(&dmax, &gd, 1, MPI_DOUBLE, MPI_MAX, comm_);
  MPI_Allreduce(&overlap, &go, 1, MPI_INT, MPI_MAX, comm_);
  if (go) throw Error("Fix mpm/fluid: keyword 'couple' expects a grain group without material points");
  if (!(gd > opt.grid.dx)) return "";
  std::ostringstream os;
  os << "Fix mpm/fluid: keyword 'cell' (" << opt.grid.dx << ") is smaller than the largest grain of group '"
     << opt.couple_group << "' (diameter " << gd << "); the volume fraction (8-11) needs cells that hold grains";
  if (!opt.cell_check) return os.str();
  os << " (keyword 'cell_check no' overrides)";
  throw Error(os.str());
}

double FluidSolver::init_point(const double x[3], double vol, double *s) const {
  const Eos &eos = opt.eos;
  double rho = eos.rho0, p = 0.0;
  if (opt.hydrostatic) {
    p = std::max(0.0, eos.rho0 * opt.hydro_g * (opt.hydro_surface - x[opt.hydro_axis]));
    rho = pressure_->density(eos, p);  // projection: incompressible
  }
  // The point keeps the reference mass; a pre-compressed point is smaller.
  const double m = eos.rho0 * vol;
  std::fill(s, s + NCOL, 0.0);
  s[C_VOL] = m / rho;
  s[C_RHO] = rho;
  s[C_P] = p;
  s[C_THETA] = 1.0;
  s[C_FLAG] = 1.0;
  return m;
}

void FluidSolver::setup_grid(const double sublo[3], const double subhi[3], double skin, bool mesh_walls) {
  // The halo (docs/design.md, "The halo"): a point lies at most `skin` outside its rank's subdomain
  // (the host re-neighbours once a point moved more than skin/2; the other half is the room for
  // what it moves within one fluid step), its stencil reaches stencil_reach() node layers beyond
  // the owned nodes, and with mesh walls the traction at a point's nearest wall point reads the
  // stencil of that point, up to one node beyond the point's own.
  int reach[2];
  stencil_reach(opt.shape, skin / opt.grid.dx, reach);
  const int beyond = mesh_walls ? 1 : 0;
  const int halo[2] = {reach[0] + beyond, reach[1] + beyond};
  shape_ctx_.skin = skin;
  for (int d = 0; d < 3; ++d) shape_ctx_.sub_lo[d] = sublo[d], shape_ctx_.sub_hi[d] = subhi[d];
  // projection: the last solve goes on into the new patch (ProjectionPressure::enter_patch)
  pressure_->leave_patch();
  grid_.setup(opt.grid, comm_, sublo, subhi, halo);
  {
    const GridSpec &gs = opt.grid;
    ShapeCtx &c = shape_ctx_;
    c.inv = 1.0 / gs.dx;
    for (int d = 0; d < 3; ++d) {
      c.origin[d] = gs.origin[d];
      c.ncell[d] = gs.ncell[d];
      c.periodic[d] = gs.periodic[d];
      // the guard of shape_at: a stencil grown by the layers read beyond it stays in the patch
      // (at a non-periodic face the patch ends with the grid's padding, which no stencil passes)
      const IndexBox &pb = grid_.patch();
      const bool lo_face = !gs.periodic[d] && pb.lo[d] == gs.node_lo(d);
      const bool hi_face = !gs.periodic[d] && pb.hi[d] == gs.node_hi(d);
      c.lo[d] = pb.lo[d] + (lo_face ? 0 : beyond);
      c.hi[d] = pb.hi[d] - (hi_face ? 0 : beyond);
    }
  }
  g_.assign(grid_.size(), opt.musl, !pressure_->incompressible(), opt.coupled, opt.grad_p == GradP::Fit);
  bc.walls_moved();  // the nodes' mesh-wall constraints are indexed by the patch
  // the sparse grid covers the fluid's own phases, also with couple and with the projection: the
  // coupling reads the fluid's arrays (zero outside the active blocks, as on the dense grid) and
  // writes only its own, which its phases sweep on the whole patch; the projection writes the
  // fluid's velocity only where there is mass, and sweeps its own arrays on the work box
  // (projection_work_box; pure fluid without mesh walls) or the whole patch (docs/validation/performance.md,
  // "Sparse grid")
  sparse_ = opt.sparse;
  if (sparse_) blocks_.setup(grid_);
  pressure_->enter_patch(grid_, comm_, opt, state);
  grid_ready_ = true;
}

ProjectionState FluidSolver::projection_state() { return pressure_->restart_state(opt, comm_, state); }

void FluidSolver::step() {
  const double h = opt.fluid_every * clock.dt / state.nsub;
  coup_->begin_step(*this);
  // the volume correction (projection) of this fluid step, due on its first sub-step
  const double vc_time = pressure_->volume_correction_due(opt, clock, state);
  if (opt.every_auto) state.grain_tau = HUGE_VAL;  // this step's, for the next choice of N (couple_kernel)
  const bool samples = samples_on();
  if (walls_with_loads()) bc.record_loads(h);
  if (samples) begin_samples();
  if (opt.drive.active) drive_force();
  for (int s = 0; s < state.nsub; ++s) substep(h, s == 0 ? vc_time : 0.0);
  if (samples) end_samples();
  if (opt.drive.active) drive_correct(opt.fluid_every * clock.dt);
  inflow_advance(opt.fluid_every * clock.dt);
  coup_->end_step(*this);
}

// GrainCoupling::end_step: the fluid force on the grains (mean over the sub-steps) kept in the
// state rows
void FluidSolver::store_grain_force() {
  for (int k = 0; k < pts.nlocal; ++k) {
    if (!is_grain(k)) continue;
    for (int d = 0; d < 3; ++d) pts.state[k][C_FGRAIN + d] = coup_->grain_force[3 * k + d];
  }
}

// One sub-step of chapter 8, phase by phase.
void FluidSolver::substep(double h, double vc_time) {
  timed(io_.time_fluid, [&] { compute_shapes(); });
  coup_->fraction(*this, io_.time_couple);
  timed(io_.time_fluid, [&] { particles_to_grid(); });
  coup_->exchange(*this, h, io_.time_couple);
  timed(io_.time_fluid, [&] {
    update_grid(h, vc_time);
    if (samples_on()) sample_pressure(h);
    point_pressure();
    grid_to_particles();
    if (opt.musl) remap_velocity_musl(h);
    update_stress(h);
    advance_positions(h);
  });
}

void FluidSolver::compute_shapes() {
  const int nlocal = pts.nlocal;
  if (static_cast<int>(pw_.shapes.size()) < nlocal) {
    pw_.shapes.resize(nlocal);
    pw_.vpic.resize(3 * static_cast<std::size_t>(nlocal));
  }
  // the velocity gradient apart from the state rows: APIC only (their affine record holds C there);
  // FLIP and PIC keep it in the affine record (grad_in_state)
  if (opt.transfer == Transfer::Apic && pw_.velgrad.size() < 9 * static_cast<std::size_t>(nlocal))
    pw_.velgrad.resize(9 * static_cast<std::size_t>(nlocal));
  pw_.plist.clear();
  double **x = pts.x;
  const GridSpec &gs = opt.grid;
  for (int d = 0; d < 3; ++d) {
    pw_.base_lo[d] = INT_MAX;
    pw_.base_hi[d] = INT_MIN;
  }
  // sparse grid: the blocks are marked here, in the pass that computes the stencils
  // (mark_active_blocks)
  static_assert(ActiveBlocks::kSize >= 4, "the grown stencil (bspline2: 5 nodes) spans two blocks at most");
  if (sparse_) blocks_.begin();
  const bool sparse = sparse_;
  const IndexBox &pb = grid_.patch();
  const int lo0 = pb.lo[0], lo1 = pb.lo[1], lo2 = pb.lo[2];
  const bool quad = opt.shape == ShapeKind::QuadraticBSpline;
  for (int i = 0; i < nlocal; ++i) {
    if (!is_point(i)) continue;
    pw_.plist.push_back(i);
    check_point(i);
    if (quad ? shape_at<true>(x[i], pw_.shapes[i]) : shape_at<false>(x[i], pw_.shapes[i])) {
      const int *b = pw_.shapes[i].base;
      for (int d = 0; d < 3; ++d) {
        pw_.base_lo[d] = std::min(pw_.base_lo[d], b[d]);
        pw_.base_hi[d] = std::max(pw_.base_hi[d], b[d]);
      }
      if (sparse) blocks_.mark_from(std::max(b[0] - 1, lo0), std::max(b[1] - 1, lo1), std::max(b[2] - 1, lo2));
    } else {
      std::ostringstream os;
      os << "Fix mpm/fluid: material point " << pts.tag[i] << " at (" << x[i][0] << ", " << x[i][1] << ", "
         << x[i][2] << ") left the grid [" << gs.origin[0] << ", " << gs.upper(0) << "] x [" << gs.origin[1]
         << ", " << gs.upper(1) << "] x [" << gs.origin[2] << ", " << gs.upper(2) << "] at step " << clock.step
         << " (enlarge 'grid' or check for an unstable run)";
      throw LocalError(os.str());
    }
  }
  if (sparse_) mark_active_blocks();
}

/* The blocks the points' stencils reach, grown by one node on each side: that covers the cell
   record of the anti-locking average (the cell's low node, clamped at the upper face), the grid-face
   traction (inside the stencil) and the mesh-wall traction (the stencil of the nearest wall point,
   less than a cell away: its base within one node of the point's). Blocks that drop out are
   cleared, so that every node outside the active blocks is zero. */
void FluidSolver::mark_active_blocks() {
  // the points' blocks were marked in compute_shapes' pass (begin, one mark_from per point)
  blocks_.finish();
  grid_.zero_boxes(g_.p2g, P2gRec::N, blocks_.retired());
  grid_.zero_boxes(g_.vel, VelRec::N, blocks_.retired());
  grid_.zero_boxes(g_.aux, AuxRec::N, blocks_.retired());
  grid_.zero_boxes(g_.cell, CellRec::N, blocks_.retired());
}

void FluidSolver::clear_nodes(std::vector<double> &a, int stride) {
  if (!sparse_) {
    std::fill(a.begin(), a.end(), 0.0);
    return;
  }
  grid_.zero_boxes(a, stride, blocks_.boxes());
}

long FluidSolver::nonzero_outside_active() const {
  if (!sparse_) return 0;
  long bad = 0;
  auto count = [&](const std::vector<double> &a, int stride) {
    if (a.empty()) return;
    grid_.for_box(grid_.patch(), [&](int i, int j, int k, std::size_t n) {
      if (blocks_.active(i, j, k)) return;
      for (int c = 0; c < stride; ++c) bad += a[stride * n + c] != 0.0;
    });
  };
  count(g_.p2g, P2gRec::N);
  count(g_.vel, VelRec::N);
  count(g_.aux, AuxRec::N);
  count(g_.cell, CellRec::N);
  return bad;
}

// What the step reads of point i (position, velocity, mass) is finite, the mass positive.
const char *FluidSolver::first_bad(const double *x, const double *v, const double *radius, double mass) {
  if (!(std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]))) return "position";
  if (!(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]))) return "velocity";
  if (radius && !(std::isfinite(*radius) && *radius > 0.0)) return "radius";
  if (!(std::isfinite(mass) && mass > 0.0)) return "mass";
  return nullptr;
}

void FluidSolver::bad_point(int i) const {
  const double *x = pts.x[i], *v = pts.v[i];
  const char *what = first_bad(x, v, nullptr, pts.rmass[i]);
  if (!what) return;
  std::ostringstream os;
  os << "Fix mpm/fluid: the " << what << " of material point " << pts.tag[i] << " is not finite"
     << (what[0] == 'm' ? " and positive" : "") << " at step " << clock.step << " (x = (" << x[0] << ", " << x[1]
     << ", " << x[2] << "), v = (" << v[0] << ", " << v[1] << ", " << v[2] << "), mass " << pts.rmass[i]
     << "); the run became unstable (reduce the timestep)";
  throw LocalError(os.str());
}

// Weights and gradients of the nodes around x; false if x is outside the grid.
bool FluidSolver::shape_of(const double *x, Stencil &ps) {
  return opt.shape == ShapeKind::QuadraticBSpline ? shape_at<true>(x, ps) : shape_at<false>(x, ps);
}

// (shape_functions.h's shape_eval for one kind, the weights and gradients written straight into
// the stencil; the same operations, so the same values)
template <bool QUAD>
bool FluidSolver::shape_at(const double *x, Stencil &ps) const {
  const ShapeCtx &c = shape_ctx_;
  const double inv = c.inv;
  constexpr int ns = QUAD ? 3 : 2;
  for (int d = 0; d < 3; ++d) {
    const double xi = (x[d] - c.origin[d]) * inv;
    if (!c.periodic[d] && (xi < 0.0 || xi > c.ncell[d])) return false;
    Shape1D s;
    if (QUAD)
      shape_bspline2(xi, s);
    else
      shape_linear(xi, s);
    ps.base[d] = s.base;
    for (int a = 0; a < 3; ++a) {
      ps.w[d][a] = s.w[a];
      ps.dw[d][a] = s.dw[a] * inv;
    }
    if (s.base < c.lo[d] || s.base + ns - 1 > c.hi[d]) outside_patch(x);
  }
  ps.n0 = grid_.index(ps.base[0], ps.base[1], ps.base[2]);
  return true;
}

void FluidSolver::outside_patch(const double *x) const {
  const ShapeCtx &c = shape_ctx_;
  std::ostringstream os;
  os << "Fix mpm/fluid: atom at (" << x[0] << ", " << x[1] << ", " << x[2] << ") is farther than the neighbor skin ("
     << shape_ctx_.skin << ") outside the subdomain [" << shape_ctx_.sub_lo[0] << ", " << shape_ctx_.sub_hi[0] << "] x [" << shape_ctx_.sub_lo[1] << ", "
     << shape_ctx_.sub_hi[1] << "] x [" << shape_ctx_.sub_lo[2] << ", " << shape_ctx_.sub_hi[2] << "] of rank " << me_
     << ": its stencil leaves the rank's grid patch (stencil nodes " << c.lo[0] << ".." << c.hi[0] << " x " << c.lo[1]
     << ".." << c.hi[1] << " x " << c.lo[2] << ".." << c.hi[2]
     << "); it moved too far between re-neighbourings (use neigh_modify every 1 check yes, or a larger "
        "neighbor skin)";
  throw LocalError(os.str());
}

/* grid momentum update (8-35), velocity (8-36), boundary conditions: the pressure model's
   (EosPressure: the nodes' conditions; ProjectionPressure: u*, then the projection) */
void FluidSolver::update_grid(double h, double vc_time) {
  pressure_->update_grid(*this, h, vc_time);
  grid_.forward(g_.vel.data(), VelRec::N);
}

// update_grid's sweep over the nodes; node_bc: the boundary conditions at each node (eos; the
// projection's u* has none, its wall conditions come with the projection, Projection::project)
void FluidSolver::grid_velocity(double h, bool node_bc) {
  const double mmin = mass_min();
  const double *rx = coup_->fluid_force(g_);  // the drag exchange's force on the fluid (couple)
  for_owned_nodes([&](int i, int j, int k, std::size_t n) {
    const double *g = &g_.p2g[P2gRec::N * n];
    double *gv = &g_.vel[VelRec::N * n];
    for (int c = 0; c < VelRec::N; ++c) gv[c] = 0.0;
    // Nearly empty node at the free surface: its velocity would be a ratio of two
    // round-off-sized numbers; it carries no information.
    if (g[P2gRec::M] <= mmin || g[P2gRec::M] <= 0.0) return;
    const double inv = 1.0 / g[P2gRec::M];
    double vnew[3];
    for (int d = 0; d < 3; ++d) {
      gv[VelRec::V_OLD + d] = g[P2gRec::MV + d] * inv;
      const double f = g[P2gRec::F + d] + (rx ? rx[3 * n + d] : 0.0);
      // damping is implicit in time so that any rate is stable
      vnew[d] = (gv[VelRec::V_OLD + d] + h * f * inv) / (1.0 + h * opt.damping);
    }
    if (node_bc) bc.apply(vnew, i, j, k, h, g[P2gRec::M]);
    for (int d = 0; d < 3; ++d) gv[VelRec::V_NEW + d] = vnew[d];
  });
}

// ProjectionPressure::update_grid: the projection of u* (its volume correction when due)
void FluidSolver::project_velocity(Projection &proj, std::vector<double> &pvol, double h, double vc_time) {
  const bool vc = vc_time > 0.0;
  if (vc) point_volume_to_grid(pvol);
  IndexBox work;
  const double *theta = coup_->node_theta(g_);
  const bool sparse_proj = sparse_ && !theta && !bc.walls();
  if (sparse_proj) work = projection_work_box();
  proj.project(g_.vel.data(), g_.p2g.data(), mass_min(), theta, h, bc, clock.step,
               vc ? pvol.data() : nullptr, sparse_proj ? &work : nullptr, vc_time);
}

/* The projection's work box (sparse grid, pure fluid without mesh walls): the bounding box of the
   stencils of all points of all ranks (every node that can hold fluid mass, also the owned nodes
   that get their mass from another rank's points), grown by Projection::kWorkMargin nodes, cut to
   the patch; the whole patch along periodic dimensions. Empty when there are no points. */
IndexBox FluidSolver::projection_work_box() {
  int loc[6], glob[6];
  for (int d = 0; d < 3; ++d) {
    loc[d] = pw_.base_lo[d];
    loc[3 + d] = -pw_.base_hi[d] - (support(opt.shape) - 1);  // the stencil's top node, negated
    if (pw_.base_hi[d] == INT_MIN) loc[3 + d] = INT_MAX;      // no points here
  }
  MPI_Allreduce(loc, glob, 6, MPI_INT, MPI_MIN, comm_);
  const IndexBox &pb = grid_.patch();
  IndexBox w;
  if (glob[0] == INT_MAX) return w;  // no points anywhere: empty
  for (int d = 0; d < 3; ++d) {
    if (opt.grid.periodic[d]) {
      w.lo[d] = pb.lo[d];
      w.hi[d] = pb.hi[d];
      continue;
    }
    w.lo[d] = glob[d] - Projection::kWorkMargin;
    w.hi[d] = -glob[3 + d] + Projection::kWorkMargin;
  }
  return w.cut(pb);
}

/* The nodal pressure gradient couple_kernel's grad_p weak path reads: with the projection the
   discrete gradient of the last solve, the one the fluid felt, read where the solve keeps it (not
   copied: the whole patch's array each sub-step); else grad_p weak's own array
   (weak_pressure_gradient) */
const double *FluidSolver::grain_gradient() const {
  const std::vector<double> &g = pressure_->reaction_in_solve() ? pressure_->solve()->gradient() : g_.gw;
  return g.size() == 3 * grid_.size() ? g.data() : nullptr;
}

/* projection + volume_correction: the points' volume on the grid, sum S V with V = m / (theta
   rho0) (the volume a point holds, with this sub-step's theta), owned nodes after the reverse sum */
void FluidSolver::point_volume_to_grid(std::vector<double> &pvol) {
  pvol.assign(grid_.size(), 0.0);
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  with_stencil(opt.shape, [&](auto ns) {
    for (const int i : pw_.plist) {
      const double V = pts.rmass[i] / (pts.state[i][C_THETA] * opt.rho0);
      for_stencil<decltype(ns)::value>(pw_.shapes[i], sy, sz, [&](std::size_t n, int, int, int, double w, double,
                                                               double, double) { pvol[n] += w * V; });
    }
  });
  grid_.reverse_sum(pvol.data(), 1);
}

void FluidSolver::point_pressure() { pressure_->point_pressure(*this); }

/* projection: the points' pressure (state column C_P, for output and f_ID[10]) interpolated
   from the nodal pressure p of the solve */
void FluidSolver::interpolate_pressure(const std::vector<double> &p) {
  const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
  with_stencil(opt.shape, [&](auto ns) {
    for (const int i : pw_.plist) {
      double sum = 0.0;
      for_stencil<decltype(ns)::value>(pw_.shapes[i], sy, sz, [&](std::size_t n, int, int, int, double w, double,
                                                               double, double) { sum += w * p[n]; });
      pts.state[i][C_P] = sum;
    }
  });
}

/* Continuity (7-21) as a volume update, equation of state (7-23) or Tait, Navier-Poisson (7-24).
   Anti-locking: the dilatation rate is averaged over each grid cell and the cell's pressure
   follows from the cell's mean density, so all points of a cell carry one pressure (Mast et al.
   2012). theta_only: the fluid fraction changed, the volume did not (refresh_pressure). */
void FluidSolver::update_stress(double h, bool theta_only) { pressure_->update_stress(*this, h, theta_only); }

// incompressible (ProjectionPressure): density rho0 and the volume m / (theta rho0) held (the
// points' number per cell measures the volume drift, docs/theory/projection.md); the pressure is
// the solve's
void FluidSolver::incompressible_stress(bool theta_only) {
  for (const int i : pw_.plist) {
    double *s = pts.state[i];
    s[C_RHO] = opt.rho0;
    s[C_VOL] = pts.rmass[i] / (s[C_THETA] * opt.rho0);
    if (theta_only) continue;
    const double *L = velgrad(i);
    const double Lm[3][3] = {{L[0], L[1], L[2]}, {L[3], L[4], L[5]}, {L[6], L[7], L[8]}};
    newtonian_deviatoric_stress(opt.viscosity, Lm, s + C_TAU);
  }
}

// EosPressure: the equation of state's pressure of each point, from its cell's density
void FluidSolver::eos_stress(double h, bool theta_only) {
  const int nlocal = pts.nlocal;
  const double *rmass = pts.rmass;
  // anti-locking: the cell sums, after MUSL already taken in its gradient pass (musl_gradient),
  // else here
  if (theta_only || !pw_.cells_summed) {
    if (pw_.pcell.size() < static_cast<std::size_t>(nlocal)) pw_.pcell.resize(nlocal);
    clear_nodes(g_.cell, CellRec::N);
    for (int i = 0; i < nlocal; ++i) {
      if (!is_point(i)) continue;
      sum_cell(i, theta_only ? nullptr : velgrad(i));
    }
  }
  pw_.cells_summed = false;
  grid_.reverse_sum(g_.cell.data(), CellRec::N);
  grid_.forward(g_.cell.data(), CellRec::N);
  for (int i = 0; i < nlocal; ++i) {
    if (!is_point(i)) continue;
    double *s = pts.state[i];
    // theta_only: velgrad belongs to the last step's atom order then and is not read
    const double *L = theta_only ? nullptr : velgrad(i);
    // the cell's mean dilatation and density (anti-locking): the point's own J and volume follow
    // the cell's, its pressure is the cell's
    const double *c = &g_.cell[CellRec::N * pw_.pcell[i]];
    const double div = c[CellRec::VDIV] / c[CellRec::V];
    const double rho_cell = c[CellRec::M] / (c[CellRec::THV] * (1.0 + h * div));
    double p = opt.eos.pressure(rho_cell);
    const double J = 1.0 + h * div;
    s[C_VOL] *= J;
    s[C_RHO] = rmass[i] / (s[C_THETA] * s[C_VOL]);
    // Liquid cannot carry tension beyond its cavitation pressure: without the cut a stretched
    // surface layer would hold itself together (and to walls).
    p = std::max(p, opt.pmin);
    if (!(J > 0.0) || !std::isfinite(p)) {
      std::ostringstream os;
      os << "Fix mpm/fluid: material point " << pts.tag[i] << " was compressed to a non-positive volume at step "
         << clock.step << "; the fluid became unstable (reduce the timestep)";
      throw LocalError(os.str());
    }
    s[C_P] = p;
    if (theta_only) continue;
    const double Lm[3][3] = {{L[0], L[1], L[2]}, {L[3], L[4], L[5]}, {L[6], L[7], L[8]}};
    newtonian_deviatoric_stress(opt.viscosity, Lm, s + C_TAU);
  }
}

/* position update (8-41) with the grid velocity; a point that crossed a wall (or the closed gate)
   by less than a cell is put back on the fluid side */
void FluidSolver::advance_positions(double h) {
  double **x = pts.x, **v = pts.v;
  // without mesh walls and gate, a point inside the grid's box along every non-periodic dimension
  // has nothing to be put back from (Boundaries::put_back would change nothing): tested here
  const GridSpec &gs = opt.grid;
  const bool box_only = !bc.has_walls() && !opt.gate.active;
  double lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = gs.periodic[d] ? -HUGE_VAL : gs.origin[d];
    hi[d] = gs.periodic[d] ? HUGE_VAL : gs.upper(d);
  }
  // the volume correction's drift (Projection::volume_drift): positions only
  const std::vector<double> *drift = pressure_->volume_drift();
  if (drift && !drift->empty()) {
    const double *w = drift->data();
    const std::size_t sy = grid_.stride_y(), sz = grid_.stride_z();
    with_stencil(opt.shape, [&](auto ns) {
      for (const int i : pw_.plist)
        for_stencil<decltype(ns)::value>(pw_.shapes[i], sy, sz, [&](std::size_t n, int, int, int, double s, double, double, double) {
          for (int d = 0; d < 3; ++d) pw_.vpic[3 * i + d] += s * w[3 * n + d];
        });
    });
  }
  for (int i = 0; i < pts.nlocal; ++i) {
    if (!is_point(i)) continue;
    double *xi = x[i];
    const double xold[3] = {xi[0], xi[1], xi[2]};
    for (int d = 0; d < 3; ++d) xi[d] += h * pw_.vpic[3 * i + d];
    if (box_only && xi[0] >= lo[0] && xi[0] <= hi[0] && xi[1] >= lo[1] && xi[1] <= hi[1] && xi[2] >= lo[2] &&
        xi[2] <= hi[2])
      continue;
    bool gone = false;
    state.n_clamped += bc.put_back(xi, v[i], xold, pts.rmass[i], &gone);
    if (gone) {
      // left through an outflow face: no longer fluid (is_point), removed by the host
      pts.state[i][C_FLAG] = kPointGone;
      for (int d = 0; d < 3; ++d) v[i][d] = 0.0;
      ++pw_.gone;
    }
  }
}

std::size_t FluidSolver::memory_bytes() const {
  std::size_t bytes = (g_.p2g.size() + g_.vel.size() + g_.cell.size() + g_.aux.size()) * sizeof(double);
  bytes += pw_.shapes.size() * sizeof(Stencil) + (pw_.vpic.size() + pw_.velgrad.size()) * sizeof(double);
  return bytes;
}

}  // namespace mpm
