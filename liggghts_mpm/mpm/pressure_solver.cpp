#include "mpm/pressure_solver.h"

#include <HYPRE_struct_ls.h>
#include <HYPRE_utilities.h>

#include <climits>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>
#include <vector>

namespace mpm {

namespace {

// hypre 2.26 wants HYPRE_Init before its first object; once per process.
void hypre_init_once() {
  static bool done = false;
  if (!done) {
    HYPRE_Init();
    done = true;
  }
}

// Symmetric storage: the centre and the couplings to the lower neighbours;
// hypre mirrors them onto the upper ones.
constexpr int kEntries = 4;
int stencil_offsets[kEntries][3] = {{0, 0, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};

}  // namespace

// fn(i, j, k, flat index) over a box of the grid's patch, i fastest (hypre's box order).
template <class Fn>
void for_box(const LocalGrid &grid, const IndexBox &b, Fn &&fn) {
  for (int k = b.lo[2]; k <= b.hi[2]; ++k)
    for (int j = b.lo[1]; j <= b.hi[1]; ++j)
      for (int i = b.lo[0]; i <= b.hi[0]; ++i) fn(i, j, k, grid.index(i, j, k));
}

struct PressureSolver::Hypre {
  IndexBox box;    // the active box the grid was built on (part of the owned box)
  IndexBox owned;  // the owned box at that time
  bool have_box = false;
  HYPRE_StructGrid grid = nullptr;
  HYPRE_StructStencil stencil = nullptr;
  HYPRE_StructMatrix A = nullptr;
  HYPRE_StructVector b = nullptr, x = nullptr;
  HYPRE_StructSolver pcg = nullptr, precond = nullptr;
  std::vector<double> values;  // kEntries per owned node, box order (i fastest)
  bool valid_values = false;
  std::vector<double> bbuf, xbuf;

  void destroy_solver(PressureSettings::Preconditioner kind) {
    if (pcg) HYPRE_StructPCGDestroy(pcg);
    if (precond) {
      if (kind == PressureSettings::Preconditioner::PFMG) HYPRE_StructPFMGDestroy(precond);
      if (kind == PressureSettings::Preconditioner::SMG) HYPRE_StructSMGDestroy(precond);
    }
    pcg = precond = nullptr;
  }
  void destroy_all(PressureSettings::Preconditioner kind) {
    destroy_solver(kind);
    if (A) HYPRE_StructMatrixDestroy(A);
    if (b) HYPRE_StructVectorDestroy(b);
    if (x) HYPRE_StructVectorDestroy(x);
    if (stencil) HYPRE_StructStencilDestroy(stencil);
    if (grid) HYPRE_StructGridDestroy(grid);
    A = nullptr;
    b = x = nullptr;
    stencil = nullptr;
    grid = nullptr;
    valid_values = false;
  }
};

PressureSolver::PressureSolver(LocalGrid &grid, MPI_Comm comm, const PressureSettings &settings,
                               const ProjectionGeometry &geometry)
    : grid_(grid), comm_(comm), settings_(settings), geo_(geometry), h_(new Hypre) {
  if (!(settings.tolerance > 0.0))
    throw std::invalid_argument("pressure solver: tolerance must be > 0");
  if (settings.max_iterations < 1)
    throw std::invalid_argument("pressure solver: max_iterations must be >= 1");
  hypre_init_once();
}

PressureSolver::~PressureSolver() { h_->destroy_all(settings_.preconditioner); }

void PressureSolver::build_grid(const IndexBox &ob) {
  h_->destroy_all(settings_.preconditioner);
  const GridSpec &g = grid_.spec();
  HYPRE_StructGridCreate(comm_, 3, &h_->grid);
  if (!ob.empty()) {
    int lo[3] = {ob.lo[0], ob.lo[1], ob.lo[2]}, hi[3] = {ob.hi[0], ob.hi[1], ob.hi[2]};
    HYPRE_StructGridSetExtents(h_->grid, lo, hi);
  }
  int period[3];
  for (int d = 0; d < 3; ++d) period[d] = g.periodic[d] ? g.ncell[d] : 0;
  HYPRE_StructGridSetPeriodic(h_->grid, period);
  HYPRE_StructGridAssemble(h_->grid);

  HYPRE_StructStencilCreate(3, kEntries, &h_->stencil);
  for (int e = 0; e < kEntries; ++e) HYPRE_StructStencilSetElement(h_->stencil, e, stencil_offsets[e]);

  HYPRE_StructMatrixCreate(comm_, h_->grid, h_->stencil, &h_->A);
  HYPRE_StructMatrixSetSymmetric(h_->A, 1);
  HYPRE_StructMatrixInitialize(h_->A);
  HYPRE_StructVectorCreate(comm_, h_->grid, &h_->b);
  HYPRE_StructVectorInitialize(h_->b);
  HYPRE_StructVectorCreate(comm_, h_->grid, &h_->x);
  HYPRE_StructVectorInitialize(h_->x);

  h_->box = ob;
  h_->owned = grid_.owned();
  h_->have_box = true;
  const std::size_t n = std::size_t(ob.count());
  h_->values.assign(kEntries * n, 0.0);
  h_->bbuf.assign(n, 0.0);
  h_->xbuf.assign(n, 0.0);
}

/* The matrix of -dx^2 L (symmetric positive): row n of a FLUID node has
   sum area_f beta_f over its open faces on the diagonal and -area_f beta_f towards
   each FLUID neighbour; EMPTY neighbours stay on the diagonal only (their value
   goes to the rhs); EMPTY and SOLID rows are the identity. Returns true if the
   values differ from those hypre holds. */
long PressureSolver::node_key(int i, int j, int k) const {
  const GridSpec &g = grid_.spec();
  int idx[3] = {i, j, k};
  long key = 0;
  for (int d = 2; d >= 0; --d) {
    if (g.periodic[d]) idx[d] = ((idx[d] % g.ncell[d]) + g.ncell[d]) % g.ncell[d];
    key = key * (g.node_hi(d) - g.node_lo(d) + 1) + (idx[d] - g.node_lo(d));
  }
  return key;
}

bool PressureSolver::unknown(const NodeLabels &labels, int i, int j, int k, std::size_t n) const {
  if (labels.kind[n] != kFluid) return false;
  const std::vector<double> &c = comp_;
  return c.empty() || c[n] < 0.0 || long(c[n]) != node_key(i, j, k);
}

// the coefficient of the face of n towards m along d: the mean of the two nodes' (solve's beta3)
static inline double face_beta(const double *beta, const double *beta3, std::size_t n, std::size_t m, int d) {
  return beta3 ? 0.5 * (beta3[3 * n + d] + beta3[3 * m + d]) : 0.5 * (beta[n] + beta[m]);
}

bool PressureSolver::assemble_values(const NodeLabels &labels, const double *beta, const double *beta3) {
  std::vector<double> v(h_->values.size(), 0.0);
  std::size_t row = 0;
  for_box(grid_, h_->box, [&](int i, int j, int k, std::size_t n) {
    double *r = &v[kEntries * row++];
    if (!unknown(labels, i, j, k, n)) {
      r[0] = 1.0;
      return;
    }
    for (int d = 0; d < 3; ++d)
      for (int side = -1; side <= 1; side += 2) {
        std::size_t m;
        if (!open_face(grid_, labels, i, j, k, d, side, &m)) continue;
        const double c = geo_.area(d, i, j, k) * face_beta(beta, beta3, n, m, d) * surface_scale(labels, n, m);
        r[0] += c;
        int q[3] = {i, j, k};
        q[d] += side;
        if (side < 0 && unknown(labels, q[0], q[1], q[2], m)) r[1 + d] = -c;
      }
  });
  int changed = (!h_->valid_values || std::memcmp(v.data(), h_->values.data(), v.size() * sizeof(double)) != 0);
  int any = 0;
  MPI_Allreduce(&changed, &any, 1, MPI_INT, MPI_MAX, comm_);
  if (!any) return false;
  h_->values.swap(v);
  const IndexBox &ob = h_->box;
  if (!ob.empty()) {
    int lo[3] = {ob.lo[0], ob.lo[1], ob.lo[2]}, hi[3] = {ob.hi[0], ob.hi[1], ob.hi[2]};
    int entries[kEntries] = {0, 1, 2, 3};
    HYPRE_StructMatrixSetBoxValues(h_->A, lo, hi, kEntries, entries, h_->values.data());
  }
  HYPRE_StructMatrixAssemble(h_->A);
  h_->valid_values = true;
  return true;
}

bool PressureSolver::any_periodic() const {
  const GridSpec &g = grid_.spec();
  return g.periodic[0] || g.periodic[1] || g.periodic[2];
}

void PressureSolver::setup_solver() {
  Hypre &h = *h_;
  h.destroy_solver(settings_.preconditioner);
  HYPRE_StructPCGCreate(comm_, &h.pcg);
  HYPRE_StructPCGSetMaxIter(h.pcg, settings_.max_iterations);
  HYPRE_StructPCGSetTol(h.pcg, settings_.tolerance);
  HYPRE_StructPCGSetTwoNorm(h.pcg, 1);
  HYPRE_StructPCGSetRelChange(h.pcg, 0);
  HYPRE_StructPCGSetLogging(h.pcg, 1);
  switch (settings_.preconditioner) {
    case PressureSettings::Preconditioner::PFMG:
      // One V-cycle with symmetric red-black Gauss-Seidel keeps the preconditioner
      // symmetric, as PCG needs.
      HYPRE_StructPFMGCreate(comm_, &h.precond);
      HYPRE_StructPFMGSetMaxIter(h.precond, 1);
      HYPRE_StructPFMGSetTol(h.precond, 0.0);
      HYPRE_StructPFMGSetZeroGuess(h.precond);
      // Red-black Gauss-Seidel stalls PCG with periodic dimensions (measured: x and y periodic,
      // 8 x 8 x 12 nodes, residual 8e-3 after 200 iterations; Jacobi and weighted Jacobi, SMG and
      // no preconditioner converge): weighted Jacobi (1) there. With it, PFMG's Galerkin coarse
      // operators broke PCG down (a few iterations, then HYPRE_ERROR_CONV at a residual of order
      // 0.1) on fully periodic boxes whose coarsening stops at a long odd direction (4 x 4 x 19,
      // 2 x 2 x 19, 8 x 8 x 19, 4 x 4 x 9 cells; 4 x 4 x 20, 8 x 8 x 8, 6 x 6 x 6 never) when the
      // fluid fraction varies over two decades (test PeriodicBoxOfOddLengthConverges; the
      // fluidized bed of inputs/fluidized_bed at 0.05 m/s): the coarse operators of hypre's
      // non-Galerkin option (7-point stencils, RAP type 1) never did.
      HYPRE_StructPFMGSetRelaxType(h.precond, any_periodic() ? 1 : 2);
      if (any_periodic()) HYPRE_StructPFMGSetRAPType(h.precond, 1);
      HYPRE_StructPFMGSetNumPreRelax(h.precond, 1);
      HYPRE_StructPFMGSetNumPostRelax(h.precond, 1);
      HYPRE_StructPCGSetPrecond(h.pcg, HYPRE_StructPFMGSolve, HYPRE_StructPFMGSetup, h.precond);
      break;
    case PressureSettings::Preconditioner::SMG:
      HYPRE_StructSMGCreate(comm_, &h.precond);
      HYPRE_StructSMGSetMemoryUse(h.precond, 0);
      HYPRE_StructSMGSetMaxIter(h.precond, 1);
      HYPRE_StructSMGSetTol(h.precond, 0.0);
      HYPRE_StructSMGSetZeroGuess(h.precond);
      HYPRE_StructSMGSetNumPreRelax(h.precond, 1);
      HYPRE_StructSMGSetNumPostRelax(h.precond, 1);
      HYPRE_StructPCGSetPrecond(h.pcg, HYPRE_StructSMGSolve, HYPRE_StructSMGSetup, h.precond);
      break;
    case PressureSettings::Preconditioner::None:
      break;
  }
  HYPRE_StructPCGSetup(h.pcg, h.A, h.b, h.x);
}

PressureResult PressureSolver::solve(const NodeLabels &labels_in, const double *beta, const double *rhs,
                                     double *p, const double *p_empty, const double *beta3) {
  PressureResult res;
  const double t0 = MPI_Wtime();
  NodeLabels walled;
  const NodeLabels &labels = wall_in_enclosed(labels_in, walled, res);
  update_active_box(labels);
  prepare_operator(labels, beta, beta3, res);
  const double t1 = MPI_Wtime();
  load_vectors(labels, beta, beta3, rhs, p, p_empty, res);
  run_pcg(res);
  const double t2 = MPI_Wtime();
  res.setup_seconds = res.rebuilt ? t1 - t0 : 0.0;
  res.solve_seconds = t2 - t1;
  if (!(res.relative_residual <= settings_.tolerance)) {
    std::ostringstream os;
    os << "pressure solve did not converge: " << res.iterations << " PCG iterations (max_iterations "
       << settings_.max_iterations << "), relative residual " << res.relative_residual << " (tolerance "
       << settings_.tolerance << ")";
    throw PressureSolveError(os.str(), res.iterations, res.relative_residual);
  }
  store_solution(labels, p, p_empty);
  return res;
}

/* A FLUID node without any open face (walled in by closed faces: seen at the corner nodes of the
   box outside the rotating jar's mesh, docs/validation/jar.md "C4 with the projection") has a zero row: PFMG
   then returns INF, hypre's PCG stops at once with its error flag and leaves the old pressure.
   Such a node takes no part in the solve (an identity row, p = 0, as a SOLID node): no face
   connects it to the rest. Returns labels_in, or walled (a copy with those nodes SOLID) if there
   are any; res.enclosed counts them. */
const NodeLabels &PressureSolver::wall_in_enclosed(const NodeLabels &labels_in, NodeLabels &walled,
                                                   PressureResult &res) const {
  std::vector<std::size_t> enclosed;
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (labels_in.kind[n] != kFluid) return;
    for (int d = 0; d < 3; ++d)
      for (int side = -1; side <= 1; side += 2) {
        std::size_t m;
        if (open_face(grid_, labels_in, i, j, k, d, side, &m)) return;
      }
    enclosed.push_back(n);
  });
  res.enclosed = long(enclosed.size());
  if (enclosed.empty()) return labels_in;
  walled = labels_in;
  for (std::size_t n : enclosed) walled.kind[n] = kSolid;
  return walled;
}

/* The hypre grid covers the active box: the FLUID nodes' bounding box in the owned box (the whole
   owned extent along periodic dimensions), grown by kActiveMargin nodes so that a moving fluid
   does not rebuild it every step. EMPTY and SOLID nodes outside it are identity rows without
   couplings, so leaving them out changes nothing (tests: the same answers). A new decomposition,
   FLUID outside the box or a box more than twice the needed one rebuild it. Collective. */
void PressureSolver::update_active_box(const NodeLabels &labels) {
  Hypre &h = *h_;
  const IndexBox &ob = grid_.owned();
  IndexBox need;
  bool any_fluid = false;
  grid_.for_owned([&](int i, int j, int k, std::size_t n) {
    if (labels.kind[n] != kFluid) return;
    const int idx[3] = {i, j, k};
    for (int d = 0; d < 3; ++d) {
      if (!any_fluid || idx[d] < need.lo[d]) need.lo[d] = idx[d];
      if (!any_fluid || idx[d] > need.hi[d]) need.hi[d] = idx[d];
    }
    any_fluid = true;
  });
  int fl = any_fluid ? 1 : 0, gfl = 0;
  MPI_Allreduce(&fl, &gfl, 1, MPI_INT, MPI_MAX, comm_);
  IndexBox want;  // empty unless FLUID nodes (the whole owned box if there are none anywhere)
  if (!gfl) want = ob;
  if (any_fluid) {
    const GridSpec &gs = grid_.spec();
    for (int d = 0; d < 3; ++d) {
      const bool full = gs.periodic[d] || !settings_.active_box;
      want.lo[d] = full ? ob.lo[d] : std::max(ob.lo[d], need.lo[d] - kActiveMargin);
      want.hi[d] = full ? ob.hi[d] : std::min(ob.hi[d], need.hi[d] + kActiveMargin);
    }
  }
  int moved = !h.have_box;
  for (int d = 0; d < 3 && !moved; ++d) moved = ob.lo[d] != h.owned.lo[d] || ob.hi[d] != h.owned.hi[d];
  if (!moved && any_fluid) {
    for (int d = 0; d < 3; ++d)
      if (h.box.empty() || need.lo[d] < h.box.lo[d] || need.hi[d] > h.box.hi[d]) moved = 1;
  }
  if (!moved && h.box.count() > 2 * want.count() + 64) moved = 1;
  int any_moved = 0;
  MPI_Allreduce(&moved, &any_moved, 1, MPI_INT, MPI_MAX, comm_);
  if (any_moved) build_grid(want);
}

/* Without any EMPTY node the constants are the operator's null space, and so they are for every
   set of FLUID nodes that closed faces seal off from the EMPTY ones (seal_components, sought only
   where closed faces or no EMPTY node exist): per sealed set the rhs is made compatible (its mean
   removed, load_vectors) and its FLUID node of smallest global key is held at 0, which keeps the
   matrix definite (PCG + PFMG stalls on the semidefinite one) without changing the solution of
   the compatible system up to its constant; p is returned with zero mean per set
   (store_solution). Then the matrix, and the preconditioner if it changed. Collective. */
void PressureSolver::prepare_operator(const NodeLabels &labels, const double *beta, const double *beta3,
                                      PressureResult &res) {
  const IndexBox &ob = grid_.owned();
  long counts[3] = {0, 0, 0}, gcounts[3];  // EMPTY nodes, FLUID nodes, FLUID nodes with a closed face
  grid_.for_owned([&](int, int, int, std::size_t n) {
    if (labels.kind[n] == kEmpty) ++counts[0];
    if (labels.kind[n] != kFluid) return;
    ++counts[1];
    if (labels.closed[n]) ++counts[2];
  });
  // the projection's work box (pure fluid, no mesh walls): the owned nodes outside it are EMPTY,
  // but the padding behind the box walls, which is SOLID
  if (grid_.restricted()) {
    const GridSpec &g = grid_.spec();
    counts[0] += g.interior(ob).count() - g.interior(ob.cut(grid_.work())).count();
  }
  MPI_Allreduce(counts, gcounts, 3, MPI_LONG, MPI_SUM, comm_);
  res.singular = gcounts[0] == 0 && gcounts[1] > 0;
  comp_.clear();
  if (res.singular || gcounts[2] > 0) res.sealed = seal_components(labels);
  if (assemble_values(labels, beta, beta3) || !h_->pcg) {
    setup_solver();
    res.rebuilt = true;
  }
}

/* hypre's b (right-hand side of -dx^2 L p = -dx^2 rhs, EMPTY neighbours' values moved over; per
   sealed set made compatible, its pinned node 0) and x (the first guess p) on the active box.
   Collective (sealed sets). */
void PressureSolver::load_vectors(const NodeLabels &labels, const double *beta, const double *beta3, const double *rhs,
                                  const double *p, const double *p_empty, PressureResult &res) {
  Hypre &h = *h_;
  const IndexBox &ab = h.box;
  const double dx2 = grid_.spec().dx * grid_.spec().dx;
  std::map<long, std::pair<double, long>> bsums;  // sealed sets: rhs sum and count
  std::size_t row = 0;
  for_box(grid_, ab, [&](int i, int j, int k, std::size_t n) {
    double &b = h.bbuf[row];
    double &x = h.xbuf[row];
    ++row;
    b = x = 0.0;
    if (labels.kind[n] != kFluid) return;
    b = -dx2 * rhs[n];
    if (p_empty)
      for (int d = 0; d < 3; ++d)
        for (int side = -1; side <= 1; side += 2) {
          std::size_t m;
          if (open_face(grid_, labels, i, j, k, d, side, &m) && labels.kind[m] == kEmpty)
            b += geo_.area(d, i, j, k) * face_beta(beta, beta3, n, m, d) * surface_scale(labels, n, m) * p_empty[m];
        }
    if (!comp_.empty() && comp_[n] >= 0.0) {
      auto &e = bsums[long(comp_[n])];
      e.first += b;
      ++e.second;
    }
    x = p[n];
  });
  if (!comp_.empty()) {
    const auto sums = component_sums(bsums);
    row = 0;
    for_box(grid_, ab, [&](int i, int j, int k, std::size_t n) {
      double &b = h.bbuf[row], &x = h.xbuf[row];
      ++row;
      if (labels.kind[n] != kFluid || comp_[n] < 0.0) return;
      const auto &e = sums.at(long(comp_[n]));
      b -= e.first / double(e.second);
      if (!unknown(labels, i, j, k, n)) b = x = 0.0;  // the pinned node
    });
    double removed = 0.0;
    for (const auto &e : sums) removed += std::fabs(e.second.first);
    res.rhs_mean_removed = res.singular ? -sums.begin()->second.first / double(sums.begin()->second.second) / dx2
                                        : removed / dx2;
    res.sealed_sets = long(sums.size());
  }
}

/* PCG on the loaded vectors; the solution back into xbuf. Throws PressureSolveError if hypre
   flags anything but a slow convergence. */
void PressureSolver::run_pcg(PressureResult &res) {
  Hypre &h = *h_;
  const IndexBox &ab = h.box;
  if (!ab.empty()) {
    int lo[3] = {ab.lo[0], ab.lo[1], ab.lo[2]}, hi[3] = {ab.hi[0], ab.hi[1], ab.hi[2]};
    HYPRE_StructVectorSetBoxValues(h.b, lo, hi, h.bbuf.data());
    HYPRE_StructVectorSetBoxValues(h.x, lo, hi, h.xbuf.data());
  }
  HYPRE_StructVectorAssemble(h.b);
  HYPRE_StructVectorAssemble(h.x);
  HYPRE_ClearAllErrors();
  HYPRE_StructPCGSolve(h.pcg, h.A, h.b, h.x);
  HYPRE_StructPCGGetNumIterations(h.pcg, &res.iterations);
  HYPRE_StructPCGGetFinalRelativeResidualNorm(h.pcg, &res.relative_residual);
  // A non-converged PCG sets HYPRE_ERROR_CONV, which the residual test of solve reports. Any other
  // flag (INF or NaN met in the solve: PCG returns at once, leaving x and a stale residual) is
  // not a solution either.
  const int herr = HYPRE_GetError() & ~HYPRE_ERROR_CONV;
  HYPRE_ClearAllErrors();
  if (herr) {
    std::ostringstream os;
    os << "pressure solve failed: hypre error flag " << herr << " (INF or NaN in the matrix, the "
       << "right-hand side or the preconditioner) after " << res.iterations << " PCG iterations";
    throw PressureSolveError(os.str(), res.iterations, std::numeric_limits<double>::quiet_NaN());
  }
  if (!ab.empty()) {
    int lo[3] = {ab.lo[0], ab.lo[1], ab.lo[2]}, hi[3] = {ab.hi[0], ab.hi[1], ab.hi[2]};
    HYPRE_StructVectorGetBoxValues(h.x, lo, hi, h.xbuf.data());
  }
}

/* p at the owned nodes from the solution (FLUID), p_empty or 0 (EMPTY), 0 (SOLID); zero mean per
   sealed set; halos forwarded. Collective. */
void PressureSolver::store_solution(const NodeLabels &labels, double *p, const double *p_empty) {
  Hypre &h = *h_;
  std::map<long, std::pair<double, long>> psums;  // sealed sets: p sum and count
  grid_.for_owned([&](int, int, int, std::size_t n) {
    if (labels.kind[n] != kFluid) p[n] = (labels.kind[n] == kEmpty && p_empty) ? p_empty[n] : 0.0;
  });
  std::size_t row = 0;
  for_box(grid_, h.box, [&](int, int, int, std::size_t n) {
    const double x = h.xbuf[row++];
    if (labels.kind[n] == kFluid) {
      p[n] = x;
      if (!comp_.empty() && comp_[n] >= 0.0) {
        auto &e = psums[long(comp_[n])];
        e.first += x;
        ++e.second;
      }
    }
  });
  if (!comp_.empty()) {
    const auto sums = component_sums(psums);
    grid_.for_owned([&](int, int, int, std::size_t n) {
      if (labels.kind[n] != kFluid || comp_[n] < 0.0) return;
      const auto &e = sums.at(long(comp_[n]));
      p[n] -= e.first / double(e.second);
    });
  }
  grid_.forward(p, 1);
}

}  // namespace mpm
