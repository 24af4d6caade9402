#include "fix_balance_mpm.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <utility>

#include "atom.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "fix_mpm_fluid.h"
#include "group.h"
#include "irregular.h"
#include "modify.h"
#include "mpm/args.h"
#include "neighbor.h"
#include "update.h"

using namespace LAMMPS_NS;
using mpm::parse_double;
using mpm::parse_int;

// LIGGGHTS' fractional cut positions of processor-grid dimension d
static double *split_of(Comm *comm, int d) { return d == 0 ? comm->xsplit : d == 1 ? comm->ysplit : comm->zsplit; }

/* ----------------------------------------------------------------------
   fix ID group-ID balance/mpm dim x|y|z [x|y|z [x|y|z]] [every N] [weight group-ID w]... [volume w] [thresh t]
       [measured yes|no]
------------------------------------------------------------------------- */

FixBalanceMpm::FixBalanceMpm(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg) {
  int iarg = 3;
  std::vector<std::string> seen;
  while (iarg < narg) {
    const char *kw = arg[iarg];
    const char *v = iarg + 1 < narg ? arg[iarg + 1] : nullptr;
    // a keyword given again replaces its value (weight: one group each)
    if (strcmp(kw, "weight") != 0 && std::find(seen.begin(), seen.end(), kw) != seen.end() && comm->me == 0)
      error->warning(FLERR, (std::string("Fix balance/mpm: keyword '") + kw +
                             "' given more than once; the last value is used").c_str());
    seen.push_back(kw);
    if (strcmp(kw, "dim") == 0) {
      iarg = parse_dims(narg, arg, iarg + 1);
    } else if (strcmp(kw, "every") == 0) {
      if (!v || !parse_int(v, every_, 0)) bad_arg(kw, "a number of steps >= 0", v);
      iarg += 2;
    } else if (strcmp(kw, "thresh") == 0) {
      if (!v || !parse_double(v, thresh_) || thresh_ < 1.0) bad_arg(kw, "an imbalance factor >= 1", v);
      iarg += 2;
    } else if (strcmp(kw, "weight") == 0) {
      if (!v) bad_arg(kw, "a group ID and a weight", v);
      const int ig = group->find(v);
      if (ig < 0) bad_arg(kw, "an existing group ID", v);
      const char *w = iarg + 2 < narg ? arg[iarg + 2] : nullptr;
      double wv = 0.0;
      if (!w || !parse_double(w, wv) || wv < 0.0) bad_arg("weight", "a weight >= 0 after the group ID", w);
      wgroup_bits_.push_back(group->bitmask[ig]);
      wvalues_.push_back(wv);
      iarg += 3;
    } else if (strcmp(kw, "measured") == 0) {
      if (!v || (strcmp(v, "yes") != 0 && strcmp(v, "no") != 0)) bad_arg(kw, "yes or no", v);
      measured_ = strcmp(v, "yes") == 0;
      iarg += 2;
    } else if (strcmp(kw, "volume") == 0) {
      if (!v || !parse_double(v, wvol_) || wvol_ < 0.0) bad_arg(kw, "a weight per unit volume >= 0", v);
      iarg += 2;
    } else {
      error->all(FLERR, (std::string("Fix balance/mpm: unknown keyword '") + kw +
                         "' (expected dim, every, weight, volume, thresh or measured)").c_str());
    }
  }
  if (dims_.empty()) error->all(FLERR, "Fix balance/mpm: keyword 'dim' (x, y or z) is required");
  if (domain->triclinic) error->all(FLERR, "Fix balance/mpm: needs an orthogonal box");
  for (int d : dims_)
    if (d == 2 && domain->dimension == 2) error->all(FLERR, "Fix balance/mpm: keyword 'dim' is z in a 2d run");

  box_change_domain = 1;
  if (every_ > 0) force_reneighbor = 1;
  next_reneighbor = -1;

  size_vector = 3;
  for (int d : dims_) {
    const int P = comm->procgrid[d];
    const double *split = split_of(comm, d);
    std::vector<double> cut(P + 1);
    for (int k = 0; k <= P; ++k) cut[k] = domain->boxlo[d] + domain->prd[d] * split[k];
    cut_.push_back(cut);
    size_vector += P + 1;
  }
  vector_flag = 1;
  global_freq = 1;
  extvector = 0;
}

/* ----------------------------------------------------------------------
   Keyword dim: its first value is required; every further one-letter word
   is another dimension (all other keywords are longer words). Each of x, y,
   z at most once.
------------------------------------------------------------------------- */

int FixBalanceMpm::parse_dims(int narg, char **arg, int iarg) {
  dims_.clear();
  std::string given;
  while (iarg < narg && (dims_.empty() || strlen(arg[iarg]) == 1)) {
    const char *v = arg[iarg];
    const int d = mpm::axis_of(v);
    if (d < 0) bad_arg("dim", "x, y or z", v);
    given += (given.empty() ? "" : " ") + std::string(v);
    if (std::find(dims_.begin(), dims_.end(), d) != dims_.end())
      bad_arg("dim", "one to three distinct dimensions x, y or z (each at most once)", given.c_str());
    dims_.push_back(d);
    ++iarg;
  }
  if (dims_.empty()) bad_arg("dim", "x, y or z", nullptr);
  return iarg;
}

void FixBalanceMpm::bad_arg(const char *keyword, const char *expected, const char *given) {
  std::string msg = std::string("Fix balance/mpm: keyword '") + keyword + "' expects " + expected +
                    ", got " + (given ? std::string("'") + given + "'" : std::string("nothing"));
  error->all(FLERR, msg.c_str());
}

int FixBalanceMpm::setmask() { return FixConst::PRE_EXCHANGE; }

// measured yes scales the weights by the work fix mpm/fluid measured: without one it would do nothing
void FixBalanceMpm::init() {
  if (measured_ && fluid_fixes().empty())
    error->all(FLERR, "Fix balance/mpm: keyword 'measured yes' scales the weights by the work of fix mpm/fluid, "
                      "and no fix mpm/fluid is defined; remove it or define the fluid fix");
}

// The keywords are set in the fix command only: fix_modify names the word it cannot change.
int FixBalanceMpm::modify_param(int narg, char **arg) {
  error->all(FLERR, (std::string("Fix balance/mpm: fix_modify cannot change keyword '") + arg[0] +
                     "' (the keywords dim, every, weight, volume, thresh and measured are set in the fix command)")
                        .c_str());
  return 0;
}


double FixBalanceMpm::base_weight(int i) const {
  const int mask = atom->mask[i];
  double w = (mask & groupbit) ? 1.0 : 0.0;
  for (std::size_t g = 0; g < wgroup_bits_.size(); ++g)
    if (mask & wgroup_bits_[g]) w = wvalues_[g];
  return w;
}

double FixBalanceMpm::weight(int i) const { return scale_ * base_weight(i); }

// the fix mpm/fluid instances of the run
std::vector<FixMpmFluid *> FixBalanceMpm::fluid_fixes() const {
  std::vector<FixMpmFluid *> out;
  for (int m = 0; m < modify->nfix; ++m)
    if (strcmp(modify->fix[m]->style, "mpm/fluid") == 0) out.push_back(static_cast<FixMpmFluid *>(modify->fix[m]));
  return out;
}

/* Keyword measured: the work of fix mpm/fluid on each rank since the last balance (its wall time
   less the waits for halo messages, FixMpmFluid::busy_seconds) over the rank's weight of atoms,
   relative to the same ratio of all ranks, scales the weights of the rank's atoms: the cuts then
   move by the work measured, which counts what point counts miss (grid nodes, the free surface
   and the pressure solve of the projection, walls). Without a measurement (the first balance, a
   rank without work or without atoms) the scale is 1. */
void FixBalanceMpm::measure() {
  double busy = 0.0;
  for (const FixMpmFluid *f : fluid_fixes()) busy += f->busy_seconds();
  const double d = busy - busy_last_;
  busy_last_ = busy;
  double w = 0.0;
  for (int i = 0; i < atom->nlocal; ++i) w += base_weight(i);
  double loc[3] = {d, w, -d}, tot[3];
  MPI_Allreduce(loc, tot, 2, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(loc + 2, tot + 2, 1, MPI_DOUBLE, MPI_MAX, world);  // -(smallest work)
  int ok = have_busy_ && -tot[2] > 0.0 && w > 0.0 && tot[0] > 0.0 && tot[1] > 0.0, all = 0;
  MPI_Allreduce(&ok, &all, 1, MPI_INT, MPI_MIN, world);
  scaled_ = all != 0;
  scale_ = scaled_ ? (d / w) / (tot[0] / tot[1]) : 1.0;
  have_busy_ = true;
}

/* ----------------------------------------------------------------------
   max / mean of the weight in the subdomains of the rank grid whose cuts
   along the listed dims are 'cuts' (the other dims' cuts as they are), the
   atoms where they are now.
------------------------------------------------------------------------- */

double FixBalanceMpm::grid_imbalance(const std::vector<std::vector<double>> &cuts) const {
  std::vector<double> c3[3];
  for (int d = 0; d < 3; ++d) {
    const int P = comm->procgrid[d];
    const double *split = split_of(comm, d);
    c3[d].resize(P + 1);
    for (int k = 0; k < P; ++k) c3[d][k] = domain->boxlo[d] + domain->prd[d] * split[k];
    c3[d][P] = domain->boxhi[d];
  }
  for (std::size_t m = 0; m < dims_.size(); ++m) c3[dims_[m]] = cuts[m];
  const int P0 = comm->procgrid[0], P1 = comm->procgrid[1], n = P0 * P1 * comm->procgrid[2];
  std::vector<double> mine(n, 0.0), all(n, 0.0);
  double **x = atom->x;
  for (int i = 0; i < atom->nlocal; ++i) {
    int k[3];
    for (int d = 0; d < 3; ++d)
      k[d] = static_cast<int>(std::upper_bound(c3[d].begin() + 1, c3[d].end() - 1, x[i][d]) - (c3[d].begin() + 1));
    mine[(k[2] * P1 + k[1]) * P0 + k[0]] += weight(i);
  }
  if (comm->me == 0)
    for (int c = 0; c < n; ++c) {
      const int k[3] = {c % P0, (c / P0) % P1, c / (P0 * P1)};
      const double lo[3] = {c3[0][k[0]], c3[1][k[1]], c3[2][k[2]]};
      const double hi[3] = {c3[0][k[0] + 1], c3[1][k[1] + 1], c3[2][k[2] + 1]};
      mine[c] += box_volume_weight(lo, hi);
    }
  MPI_Allreduce(mine.data(), all.data(), n, MPI_DOUBLE, MPI_SUM, world);
  double mx = 0.0, sum = 0.0;
  for (double v : all) mx = std::max(mx, v), sum += v;
  return sum > 0.0 ? mx / (sum / n) : 1.0;
}

// Weight of the box volume below coordinate c along dim, over the whole cross-section (keyword volume).
double FixBalanceMpm::volume_below(int dim, double c) const {
  if (wvol_ <= 0.0) return 0.0;
  double area = 1.0;
  for (int d = 0; d < domain->dimension; ++d)
    if (d != dim) area *= domain->prd[d];
  const double lo = domain->boxlo[dim], hi = domain->boxhi[dim];
  return wvol_ * area * (std::min(std::max(c, lo), hi) - lo);
}

// Weight of the volume of the box lo..hi (inside the simulation box; keyword volume), computed as
// volume_below's difference along the first listed dim.
double FixBalanceMpm::box_volume_weight(const double *lo, const double *hi) const {
  if (wvol_ <= 0.0) return 0.0;
  const int d0 = dims_[0];
  double area = 1.0;
  for (int d = 0; d < domain->dimension; ++d)
    if (d != d0) area *= hi[d] - lo[d];
  const double blo = domain->boxlo[d0], bhi = domain->boxhi[d0];
  auto below = [&](double c) { return wvol_ * area * (std::min(std::max(c, blo), bhi) - blo); };
  return below(hi[d0]) - below(lo[d0]);
}

double FixBalanceMpm::imbalance() const {
  double mine = box_volume_weight(domain->sublo, domain->subhi);
  for (int i = 0; i < atom->nlocal; ++i) mine += weight(i);
  double mx = 0.0, sum = 0.0;
  MPI_Allreduce(&mine, &mx, 1, MPI_DOUBLE, MPI_MAX, world);
  MPI_Allreduce(&mine, &sum, 1, MPI_DOUBLE, MPI_SUM, world);
  return sum > 0.0 ? mx / (sum / comm->nprocs) : 1.0;
}

int FixBalanceMpm::max_slabs() const {
  int P = 1;
  for (int d : dims_) P = std::max(P, comm->procgrid[d]);
  return P;
}

/* ----------------------------------------------------------------------
   find_cuts' last step: cut k+1 (k = 0..P-2) from the bisection's upper
   bracket b[k], the plane c[k] that crosses the target, the weights below and
   including it (w2g[2k], w2g[2k+1]) and the planes before and after it (prev,
   next); then strictly increasing, inside the box [lo, hi].
------------------------------------------------------------------------- */

static void place_cuts(std::vector<double> &cut, const std::vector<double> &b, const std::vector<double> &c,
                       const std::vector<double> &w2g, const std::vector<double> &prev,
                       const std::vector<double> &next, double total, bool volume, double lo, double hi) {
  const int P = static_cast<int>(cut.size()) - 1, nc = P - 1;
  const double len = hi - lo;
  for (int k = 0; k < nc; ++k) {
    const double target = total * (k + 1) / P;
    double x;
    if (!std::isfinite(c[k])) {
      x = b[k];
    } else if (volume && b[k] - c[k] > 1e-6 * len) {
      x = b[k];  // the target is crossed by the volume's weight between two planes of atoms
    } else if (std::fabs(w2g[2 * k] - target) <= std::fabs(w2g[2 * k + 1] - target)) {
      x = 0.5 * ((std::isfinite(prev[k]) ? prev[k] : lo) + c[k]);  // plane goes to the upper slab
    } else {
      x = 0.5 * (c[k] + (std::isfinite(next[k]) ? next[k] : hi));  // plane stays in the lower slab
    }
    cut[k + 1] = x;
  }
  // strictly increasing, inside the box
  const double minw = 1e-6 * len;
  for (int k = 1; k < P; ++k) cut[k] = std::min(std::max(cut[k], cut[k - 1] + minw), hi - (P - k) * minw);
}

/* ----------------------------------------------------------------------
   Cut k (1..P-1) along dim goes where the weight below it is k/P of the
   total (the marginal weight: summed over the other dims). The
   weight below a coordinate is a step function (atoms sit on planes, e.g. the
   lattice of material points), so the target is bracketed by bisection on
   the coordinate (one vector MPI_Allreduce per step, all cuts at once), then
   the cut is put halfway between the plane that crosses the target and its
   neighbour on the side that comes closer to the target.
------------------------------------------------------------------------- */

void FixBalanceMpm::find_cuts(int dim, std::vector<double> &cut) {
  const int P = comm->procgrid[dim], nc = P - 1;
  const double lo = domain->boxlo[dim], hi = domain->boxhi[dim], len = hi - lo;
  const double inf = std::numeric_limits<double>::infinity();
  if (P < 2) {  // one slab: nothing to place
    cut = {lo, hi};
    return;
  }

  std::vector<std::pair<double, double>> cw;
  for (int i = 0; i < atom->nlocal; ++i) {
    const double w = weight(i);
    if (w > 0.0) cw.emplace_back(atom->x[i][dim], w);
  }
  std::sort(cw.begin(), cw.end());
  std::vector<double> xs(cw.size()), pre(cw.size() + 1, 0.0);
  for (std::size_t n = 0; n < cw.size(); ++n) {
    xs[n] = cw[n].first;
    pre[n + 1] = pre[n] + cw[n].second;
  }
  auto below = [&](double c) { return pre[std::lower_bound(xs.begin(), xs.end(), c) - xs.begin()]; };
  auto last_below = [&](double c) {  // largest local coordinate < c, or -inf
    auto it = std::lower_bound(xs.begin(), xs.end(), c);
    return it == xs.begin() ? -inf : *(it - 1);
  };
  auto first_at = [&](double c) {  // smallest local coordinate >= c, or +inf
    auto it = std::lower_bound(xs.begin(), xs.end(), c);
    return it == xs.end() ? inf : *it;
  };

  double total = 0.0;
  MPI_Allreduce(&pre.back(), &total, 1, MPI_DOUBLE, MPI_SUM, world);
  total += volume_below(dim, hi);
  // the volume's weight is added once, by rank 0, to the collective sums
  const double vol_share = comm->me == 0 ? 1.0 : 0.0;
  auto below_all = [&](double c) { return below(c) + vol_share * volume_below(dim, c); };  // this rank's share
  cut.assign(P + 1, 0.0);
  cut[0] = lo;
  cut[P] = hi;
  if (total <= 0.0) {  // nothing to balance: uniform slabs
    for (int k = 1; k < P; ++k) cut[k] = lo + len * k / P;
    return;
  }

  // bisection: W(< a_k) < T_k <= W(< b_k)
  std::vector<double> a(nc, lo), b(nc, hi + 1e-9 * len), loc(nc), glob(nc);
  for (int it = 0; it < 64; ++it) {
    for (int k = 0; k < nc; ++k) {
      const double mid = 0.5 * (a[k] + b[k]);
      loc[k] = below_all(mid);
    }
    MPI_Allreduce(loc.data(), glob.data(), nc, MPI_DOUBLE, MPI_SUM, world);
    for (int k = 0; k < nc; ++k) {
      const double mid = 0.5 * (a[k] + b[k]), target = total * (k + 1) / P;
      (glob[k] < target ? a[k] : b[k]) = mid;
    }
  }
  // c_k: the plane that crosses the target (largest coordinate < b_k)
  std::vector<double> c(nc);
  for (int k = 0; k < nc; ++k) loc[k] = last_below(b[k]);
  MPI_Allreduce(loc.data(), c.data(), nc, MPI_DOUBLE, MPI_MAX, world);
  // weights below and including the plane, the planes before and after it
  std::vector<double> w2(2 * nc), w2g(2 * nc), prev(nc), next(nc);
  for (int k = 0; k < nc; ++k) {
    w2[2 * k] = std::isfinite(c[k]) ? below_all(c[k]) : 0.0;
    w2[2 * k + 1] = below_all(b[k]);
    loc[k] = std::isfinite(c[k]) ? last_below(c[k]) : -inf;
  }
  MPI_Allreduce(w2.data(), w2g.data(), 2 * nc, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(loc.data(), prev.data(), nc, MPI_DOUBLE, MPI_MAX, world);
  for (int k = 0; k < nc; ++k) loc[k] = first_at(b[k]);
  MPI_Allreduce(loc.data(), next.data(), nc, MPI_DOUBLE, MPI_MIN, world);

  place_cuts(cut, b, c, w2g, prev, next, total, wvol_ > 0.0, lo, hi);
}

/* ----------------------------------------------------------------------
   The cuts are found from the total weight times up to P (find_cuts), so
   that product must stay finite: atoms and volume may each bring half of
   DBL_MAX / P (P the largest processor count of the listed dims). Checked at every balance, as the number of atoms of a run is
   known only at its setup (and may change between balances).
------------------------------------------------------------------------- */

void FixBalanceMpm::check_weights() {
  const int P = max_slabs();
  const double limit = std::numeric_limits<double>::max() / (2.0 * P);
  const double natoms = static_cast<double>(atom->natoms);
  for (double w : wvalues_)
    if (natoms > 0.0 && !(w * natoms <= limit)) {
      std::ostringstream m;
      m << "Fix balance/mpm: keyword 'weight' expects a weight per atom (dimensionless, the fix group's "
           "atoms weigh 1) in [0, "
        << limit / natoms << "] for the " << atom->natoms << " atoms and " << P
        << (P == 1 ? " slab" : " slabs") << " of this run (the total weight times the slabs must stay finite), got " << w;
      error->all(FLERR, m.str().c_str());
    }
  double volume = 1.0;
  for (int d = 0; d < domain->dimension; ++d) volume *= domain->prd[d];
  if (!(wvol_ * volume <= limit)) {
    std::ostringstream m;
    m << "Fix balance/mpm: keyword 'volume' expects a weight per unit volume (1/length^3) in [0, "
      << limit / volume << "] for the box volume " << volume << " and " << P
      << (P == 1 ? " slab" : " slabs") << " of this run (the total weight times the slabs must stay finite), got " << wvol_;
    error->all(FLERR, m.str().c_str());
  }
}

void FixBalanceMpm::balance() {
  check_weights();  // on one rank too: the input is as wrong there
  if (max_slabs() < 2) return;
  if (measured_) measure();
  imb_before_ = imbalance();
  if (thresh_ > 1.0 && imb_before_ <= thresh_) {
    imb_after_ = imb_before_;
    return;
  }
  // each listed dim by its marginal weight: independent of the other dims' cuts
  std::vector<std::vector<double>> cuts(dims_.size());
  for (std::size_t m = 0; m < dims_.size(); ++m) find_cuts(dims_[m], cuts[m]);
  // measured: the atoms that change rank would take the new rank's scale; the imbalance of the new
  // cuts is that of the measured weights where the atoms are now
  if (scaled_) imb_after_ = grid_imbalance(cuts);
  apply_cuts(cuts);
  if (!scaled_) imb_after_ = imbalance();
  ++nbalance_;
  print_line();
}

void FixBalanceMpm::apply_cuts(const std::vector<std::vector<double>> &cuts) {
  for (std::size_t m = 0; m < dims_.size(); ++m) {
    const int d = dims_[m], P = comm->procgrid[d];
    double *split = split_of(comm, d);
    const double lo = domain->boxlo[d], len = domain->prd[d];
    split[0] = 0.0;
    split[P] = 1.0;
    for (int k = 1; k < P; ++k) split[k] = (cuts[m][k] - lo) / len;
    for (int k = 0; k <= P; ++k) cut_[m][k] = lo + len * split[k];
  }
  comm->uniform = 0;
  domain->set_local_box();

  // atoms to their new owners (possibly several ranks away), then the
  // communication pattern and the neighbour bins of the new subdomains
  domain->pbc();
  Irregular irregular(lmp);
  irregular.migrate_atoms();
  comm->setup();
  if (neighbor->style) neighbor->setup_bins();
  // fix mpm/fluid builds its grid patch from the subdomain: inside a run it builds it again at
  // its next step (at the setup of a run it builds it after this anyway)
  for (FixMpmFluid *f : fluid_fixes()) f->subdomain_changed();
}

void FixBalanceMpm::print_line() const {
  if (comm->me != 0) return;
  std::ostringstream os;
  os.precision(6);
  os << "fix balance/mpm: step " << update->ntimestep << ", cuts in ";
  for (std::size_t m = 0; m < dims_.size(); ++m) {
    os << (m ? ", in " : "") << char('x' + dims_[m]) << ":";
    for (double x : cut_[m]) os << " " << x;
  }
  os.precision(4);
  os << (scaled_ ? " (measured imbalance " : " (imbalance ") << imb_before_ << " -> " << imb_after_ << ")\n";
  if (screen) fputs(os.str().c_str(), screen);
  if (logfile) fputs(os.str().c_str(), logfile);
}

void FixBalanceMpm::setup_pre_exchange() {
  balance();
  if (every_ > 0) next_reneighbor = (update->ntimestep / every_ + 1) * every_;
}

void FixBalanceMpm::pre_exchange() {
  if (every_ <= 0 || update->ntimestep < next_reneighbor) return;
  balance();
  next_reneighbor = (update->ntimestep / every_ + 1) * every_;
}

double FixBalanceMpm::compute_vector(int n) {
  if (n == 0) return imb_after_;
  if (n == 1) return imb_before_;
  if (n == 2) return nbalance_;
  int k = n - 3;  // the cuts of the listed dims, one list after another
  for (const std::vector<double> &c : cut_) {
    if (k < static_cast<int>(c.size())) return c[k];
    k -= static_cast<int>(c.size());
  }
  return 0.0;
}
