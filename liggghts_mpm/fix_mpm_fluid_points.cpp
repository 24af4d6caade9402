/* fix mpm/fluid, the adapter's part that makes the material points LIGGGHTS atoms: the fill
   (with the memory estimate before it), the exclusion of the points from every pair style, the
   checks of the fix group, and the mesh_wall keyword (its meshes are LIGGGHTS fixes). The rest
   of the adapter: fix_mpm_fluid.cpp; docs/design.md. */

#include "fix_mpm_fluid.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "atom.h"
#include "atom_vec.h"
#include "comm.h"
#include "domain.h"
#include "error.h"
#include "fix_property_atom.h"
#include "group.h"
#include "memory.h"
#include "modify.h"
#include "neighbor.h"
#include "region.h"
#include "update.h"

#include "mpm/error.h"
#include "mesh_fill_host.h"
#include "fix_mpm_fluid_guarded.h"

using namespace LAMMPS_NS;
using namespace FixConst;
using mpm::NCOL;


/* mesh_wall fix-ID kind [value] [side s] [loads yes|no] [reference_point x y z] (the meshes are LIGGGHTS fixes; docs/theory/mesh_walls.md) */
int FixMpmFluid::parse_mesh_wall(int narg, char **arg, int iarg) {
  using mpm::bad_arg;
  using mpm::parse_double;
  const mpm::Args a{narg, arg, iarg};
  a.need(2, "mesh_wall", "a fix ID and noslip | freeslip | partial f | sticky f | shear delta|auto f");
  mpm::MeshWallSpec ms;
  ms.fix_id = arg[iarg + 1];
  ms.side = mpm::SIDE_AUTO;
  const char *k = arg[iarg + 2];
  iarg += 3;
  if (strcmp(k, "noslip") == 0) ms.kind = mpm::WALL_NOSLIP;
  else if (strcmp(k, "freeslip") == 0) ms.kind = mpm::WALL_FREESLIP;
  else if (strcmp(k, "partial") == 0 || strcmp(k, "sticky") == 0) {
    const bool sticky_kind = strcmp(k, "sticky") == 0;
    const char *kwname = sticky_kind ? "mesh_wall sticky" : "mesh_wall partial";
    if (iarg >= narg) bad_arg(kwname, "a sticky fraction", nullptr);
    ms.kind = sticky_kind ? mpm::WALL_STICKY : mpm::WALL_PARTIAL;
    if (!parse_double(arg[iarg], ms.sticky)) bad_arg(kwname, "a sticky fraction in [0,1]", arg[iarg]);
    ++iarg;
  } else if (strcmp(k, "shear") == 0) {
    // wall shear stress mu (f w_t - v_t) / delta: an unresolved viscous layer of thickness delta
    if (iarg + 1 >= narg)
      bad_arg("mesh_wall shear", "a wall layer thickness delta (length) or 'auto', and a fraction f in [0,1]", nullptr);
    ms.kind = mpm::WALL_SHEAR;
    // shear auto f: the Stokes layer sqrt(2 nu / omega) of the mesh's rotation rate omega
    if (strcmp(arg[iarg], "auto") == 0)
      ms.delta_auto = true;
    else if (!parse_double(arg[iarg], ms.delta) || !(ms.delta > 0.0))
      bad_arg("mesh_wall shear", "a positive wall layer thickness delta (length) or 'auto'", arg[iarg]);
    if (!parse_double(arg[iarg + 1], ms.sticky) || ms.sticky < 0.0 || ms.sticky > 1.0)
      bad_arg("mesh_wall shear", "a fraction f in [0,1] of the wall's tangential velocity", arg[iarg + 1]);
    iarg += 2;
  } else bad_arg("mesh_wall", "noslip, freeslip, partial f, sticky f or shear delta f", k);
  // optional, in any order: side s, loads yes|no, reference_point x y z
  bool ref_given = false;
  for (int opt = 0; opt < 3; ++opt) {
    if (iarg + 1 < narg && strcmp(arg[iarg], "side") == 0) {
      const char *sd = arg[iarg + 1];
      if (strcmp(sd, "auto") == 0) ms.side = mpm::SIDE_AUTO;
      else if (strcmp(sd, "normal") == 0) ms.side = mpm::SIDE_NORMAL;
      else if (strcmp(sd, "opposite") == 0) ms.side = mpm::SIDE_OPPOSITE;
      else if (strcmp(sd, "both") == 0) ms.side = mpm::SIDE_BOTH;
      else bad_arg("mesh_wall side", "auto, normal, opposite or both", sd);
      iarg += 2;
    }
    if (iarg < narg && strcmp(arg[iarg], "loads") == 0) {
      const char *v = iarg + 1 < narg ? arg[iarg + 1] : nullptr;
      if (!v || (strcmp(v, "yes") != 0 && strcmp(v, "no") != 0))
        bad_arg("mesh_wall loads", "yes or no (the fluid's force and torque on the wall as f_ID[20..])", v);
      ms.loads = strcmp(v, "yes") == 0;
      iarg += 2;
    }
    const int before = iarg;
    iarg = mpm::parse_reference_point(narg, arg, iarg, ms.ref);
    ref_given = ref_given || iarg != before;
  }
  // the torque's reference point is inert without the loads
  if (ref_given && !ms.loads)
    throw mpm::Error("Fix mpm/fluid: keyword 'mesh_wall reference_point' of mesh_wall " + ms.fix_id +
                     " needs 'loads yes' (the wall's loads are off, so the reference point of its torque has no use)");
  mesh_specs.push_back(ms);
  return iarg;
}

/* ---------------------------------------------------------------------- */

void FixMpmFluid::post_create() {
  // After a read_restart the points exist already (recent_restart is set
  // when our global state came from the restart file).
  if (!recent_restart && !solver->opt.fill_region.empty()) fill_points();
  if (!recent_restart) point_type = solver->opt.fill_type;
  exclude_points_from_pairs();
  // The fluid force on each grain as the per-atom vector 'dragforce', the
  // property/atom convention of LIGGGHTS/CFDEM (reused if the input made it).
  if (solver->opt.coupled) {
    const char *args[] = {"dragforce", "all", "property/atom", "dragforce", "vector", "yes", "no", "no",
                          "0", "0", "0"};
    fix_dragforce = static_cast<FixPropertyAtom *>(
        modify->find_fix_property("dragforce", "property/atom", "vector", 3, 0, style, false));
    if (!fix_dragforce) fix_dragforce = modify->add_fix_property_atom(11, const_cast<char **>(args), style);
  }
}

/* The material points are the fluid, not grains: no pair style may act on them (a granular pair
   style would make a water column pile up like sand). Same as the input lines 'neigh_modify
   exclude type T t' for every type t; lines the input already has only repeat an exclusion. */
void FixMpmFluid::exclude_points_from_pairs() {
  if (point_type < 1 || point_type > atom->ntypes) return;
  const std::string T = std::to_string(point_type);
  for (int t = 1; t <= atom->ntypes; ++t) {
    const std::string ts = std::to_string(t);
    char *args[4] = {const_cast<char *>("exclude"), const_cast<char *>("type"), const_cast<char *>(T.c_str()),
                     const_cast<char *>(ts.c_str())};
    neighbor->modify_params(4, args);
  }
  print("fix mpm/fluid: material points (type " + T + ") excluded from pair interactions (neigh_modify exclude type " +
        T + " 1.." + std::to_string(atom->ntypes) + ")\n");
}

/* The memory this process may use: the machine's physical memory, or the container's limit
   (cgroup v2 memory.max, cgroup v1 memory.limit_in_bytes) where that is smaller. 0 if unknown. */
static double usable_memory_bytes() {
  double mem = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGESIZE));
  for (const char *path : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream in(path);
    double limit = 0.0;
    if (in >> limit && limit > 0.0 && (mem <= 0.0 || limit < mem)) mem = limit;  // "max" fails to parse: no limit
  }
  return mem;
}

// the region's bounding box: ext[0] the low bounds, ext[1] the high ones (x, y, z; an unbounded
// side is LIGGGHTS' INF, 1e20). Meaningful where region->bboxflag.
static void region_extent(const Region *region, double ext[2][3]) {
  ext[0][0] = region->extent_xlo, ext[0][1] = region->extent_ylo, ext[0][2] = region->extent_zlo;
  ext[1][0] = region->extent_xhi, ext[1][1] = region->extent_yhi, ext[1][2] = region->extent_zhi;
}

/* Before creating the points: an upper estimate of their number (the cells of the grid within the
   region's bounding box, times the points per cell) against half of the machine's physical memory,
   so that 'cell 0.002' in a 1 m box stops with a message instead of dying in the allocator. */
void FixMpmFluid::check_fill_memory(Region *region, const int lo[3], const int hi[3]) {
  const mpm::Options &o = solver->opt;
  const mpm::GridSpec &gs = o.grid;
  double ncells = 1.0, ext[2][3];
  if (region->bboxflag) region_extent(region, ext);
  for (int d = 0; d < 3; ++d) {
    double a = lo[d], b = hi[d];
    if (region->bboxflag) {
      a = std::max(a, std::floor((ext[0][d] - gs.origin[d]) / gs.dx));
      b = std::min(b, std::floor((ext[1][d] - gs.origin[d]) / gs.dx));
    }
    ncells *= std::max(0.0, b - a + 1.0);
  }
  double npts = ncells * o.fill_ppc[0] * o.fill_ppc[1] * o.fill_ppc[2], total = 0.0, most = 0.0;
  MPI_Allreduce(&npts, &total, 1, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(&npts, &most, 1, MPI_DOUBLE, MPI_MAX, world);
  // LIGGGHTS counts a rank's atoms in an int, whatever the memory
  if (most > static_cast<double>(std::numeric_limits<int>::max())) {
    std::ostringstream os;
    os.precision(3);
    os << "Fix mpm/fluid: keyword 'fill' would create up to " << most << " material points on one rank (keyword 'cell' "
       << gs.dx << ", " << o.fill_ppc[0] << "x" << o.fill_ppc[1] << "x" << o.fill_ppc[2]
       << " per cell), more than LIGGGHTS' 2147483647 atoms per rank; use a larger cell, fewer points per cell or more ranks";
    error->all(FLERR, os.str().c_str());
  }
  // bytes per point: LIGGGHTS' per-atom arrays (sphere style, neighbour bins) and the fix's state
  // and shape records, about 1 kB; the ranks of one node share its memory
  const double per_point = 1024.0;
  const double mem = usable_memory_bytes();
  if (mem > 0.0 && total * per_point > 0.5 * mem) {
    std::ostringstream os;
    os.precision(3);
    os << "Fix mpm/fluid: keyword 'fill' would create up to " << total << " material points (keyword 'cell' " << gs.dx
       << ", " << o.fill_ppc[0] << "x" << o.fill_ppc[1] << "x" << o.fill_ppc[2] << " per cell), about "
       << total * per_point / 1e9 << " GB, more than half of this machine's " << mem / 1e9
       << " GB; use a larger cell or fewer points per cell";
    error->all(FLERR, os.str().c_str());
  }
}

/* The fill creates points in the grid's cells only: a region whose finite bounds reach beyond a
   non-periodic face of the grid is cut there (an unbounded side, INF, is not named), and the
   water has less volume than the region. A warning names the region, the axis and both extents. */
void FixMpmFluid::warn_fill_beyond_grid(Region *region) {
  if (!region->bboxflag || comm->me != 0) return;
  const mpm::GridSpec &gs = solver->opt.grid;
  const double big = 1e19;  // LIGGGHTS' INF bound is 1e20
  double ext[2][3];
  region_extent(region, ext);
  const double tol = 1e-9 * gs.dx;
  for (int d = 0; d < 3; ++d) {
    if (gs.periodic[d]) continue;
    const bool below = ext[0][d] > -big && ext[0][d] < gs.origin[d] - tol;
    const bool above = ext[1][d] < big && ext[1][d] > gs.upper(d) + tol;
    if (!below && !above) continue;
    std::ostringstream os;
    os << "Fix mpm/fluid: the fill region '" << solver->opt.fill_region << "' reaches beyond the grid along "
       << "xyz"[d] << " (the region " << ext[0][d] << " .. " << ext[1][d] << " m, the grid " << gs.origin[d] << " .. "
       << gs.upper(d) << " m): points are created inside the grid only";
    error->warning(FLERR, os.str().c_str());
  }
}

void FixMpmFluid::fill_points() {
  const mpm::Options &o = solver->opt;
  const mpm::GridSpec &gs = o.grid;
  // checked here, not at parse time: after read_restart no region is needed
  const int iregion = domain->find_region(o.fill_region.c_str());
  if (iregion < 0) guarded([&] { mpm::bad_arg("fill", "an existing region ID", o.fill_region.c_str()); });
  Region *region = domain->regions[iregion];
  const double dx = gs.dx;
  double *spacing = solver->state.spacing;
  double vol = dx * dx * dx;
  for (int d = 0; d < 3; ++d) {
    spacing[d] = dx / o.fill_ppc[d];
    vol /= o.fill_ppc[d];
  }
  const int nlocal_before = atom->nlocal;
  int lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::max(0, static_cast<int>(std::floor((domain->sublo[d] - gs.origin[d]) / dx)) - 1);
    hi[d] = std::min(gs.ncell[d] - 1, static_cast<int>(std::floor((domain->subhi[d] - gs.origin[d]) / dx)) + 1);
  }
  check_fill_memory(region, lo, hi);
  warn_fill_beyond_grid(region);
  // fill ... inside/outside meshes: the lattice points inside the container and outside the
  // others (mesh_fill_host.h), as a region's fill takes those inside the region: the points'
  // volume is then the inside's to the lattice's sampling. A point within a thousandth of a
  // spacing of a triangle is neither inside nor outside and is left out.
  const bool meshes = !o.fill_inside.empty() || !o.fill_outside.empty();
  mpm::FillLattice lat;
  std::vector<char> keep;
  if (meshes) {
    for (int d = 0; d < 3; ++d) {
      lat.first[d] = gs.origin[d] + 0.5 * spacing[d];
      lat.s[d] = spacing[d];
      lat.lo[d] = lo[d] * o.fill_ppc[d];
      lat.hi[d] = (hi[d] + 1) * o.fill_ppc[d] - 1;
    }
    const double gap = 1e-3 * std::min(spacing[0], std::min(spacing[1], spacing[2]));
    guarded([&] { keep = mpm::fill_mesh_mask(lmp, o, lat, gap); });
  }
  double x[3];
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i)
        for (int c = 0; c < o.fill_ppc[2]; ++c)
          for (int b = 0; b < o.fill_ppc[1]; ++b)
            for (int a = 0; a < o.fill_ppc[0]; ++a) {
              const int cell[3] = {i, j, k}, sub[3] = {a, b, c};
              for (int d = 0; d < 3; ++d) x[d] = gs.origin[d] + cell[d] * dx + (sub[d] + 0.5) * spacing[d];
              if (!region->match(x[0], x[1], x[2])) continue;
              if (meshes && !keep[lat.index(i * o.fill_ppc[0] + a, j * o.fill_ppc[1] + b, k * o.fill_ppc[2] + c)])
                continue;
              bool mine = true;
              for (int d = 0; d < 3; ++d) mine = mine && x[d] >= domain->sublo[d] && x[d] < domain->subhi[d];
              if (!mine) continue;
              create_point(x, vol);
            }
  finish_fill(nlocal_before, vol);
}

/* One material point at x of volume vol, at rest, in the fix's group (the other fixes' per-atom
   arrays set as for any new atom), of radius 0. */
void FixMpmFluid::create_point(const double *x, double vol) {
  const mpm::Options &o = solver->opt;
  atom->avec->create_atom(o.fill_type, const_cast<double *>(x));
  const int n = atom->nlocal - 1;
  for (int m = 0; m < modify->nfix; ++m) {
    Fix *f = modify->fix[m];
    if (f && f->create_attribute && f != this) {
      f->pre_set_arrays();
      f->set_arrays(n);
    }
  }
  atom->mask[n] |= groupbit;
  atom->v[n][0] = atom->v[n][1] = atom->v[n][2] = 0.0;
  atom->rmass[n] = solver->init_point(x, vol, pdata[n]);
  atom->radius[n] = 0.0;  // no LIGGGHTS contact: see FixMpmFluid::setup
  if (atom->density_flag && atom->density) atom->density[n] = o.eos.rho0;
}

/* After fill_points created its points: the global count (none is an error), tags, the atom map,
   the reference point mass and the note on the screen and in the log. */
void FixMpmFluid::finish_fill(int nlocal_before, double vol) {
  const mpm::Options &o = solver->opt;
  const mpm::GridSpec &gs = o.grid;
  bigint nnew = atom->nlocal - nlocal_before, nall = 0;
  MPI_Allreduce(&nnew, &nall, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  if (nall == 0) error->all(FLERR, "Fix mpm/fluid: keyword 'fill' created no material points (region empty?)");
  bigint nlocal = atom->nlocal;
  MPI_Allreduce(&nlocal, &atom->natoms, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  atom->tag_extend();
  if (atom->map_style) {
    atom->nghost = 0;
    atom->map_init();
    atom->map_set();
  }
  solver->state.point_mass_ref = o.eos.rho0 * vol;
  filled = true;
  std::ostringstream os;
  os << "fix mpm/fluid: created " << nall << " material points (" << o.fill_ppc[0] << "x" << o.fill_ppc[1] << "x"
     << o.fill_ppc[2] << " per cell of " << gs.dx << "), grid " << gs.ncell[0] << "x" << gs.ncell[1] << "x"
     << gs.ncell[2] << " cells\n";
  print(os.str());
}

/* The fix's group holds its material points only, and no other atom has their type (the
   exclusion from the pair styles is by type). Checked before the integrators, so that grains in
   the group are named as such, not as atoms some integrator also moves. */
void FixMpmFluid::check_group_atoms() {
  bigint loc[3] = {0, 0, 0}, glob[3];  // group atoms of other types; of the points' type without state; type shared
  for (int i = 0; i < atom->nlocal; ++i) {
    const bool same_type = atom->type[i] == point_type;
    if (is_point(i)) {
      if (pdata[i][mpm::C_FLAG] != 1.0 && pdata[i][mpm::C_FLAG] != mpm::kPointGone) ++loc[same_type ? 1 : 0];
    } else if (same_type)
      ++loc[2];
  }
  MPI_Allreduce(loc, glob, 3, MPI_LMP_BIGINT, MPI_SUM, world);
  const std::string G = std::string("group '") + group->names[igroup] + "'";
  const std::string T = std::to_string(point_type);
  std::ostringstream os;
  if (glob[0] > 0)
    os << "Fix mpm/fluid: " << G << " of the fix holds " << glob[0] << " atoms of other types than the material points' type "
       << T << " (grains?); give the fix a group of the fill type only (e.g. 'group fluid type " << T << "')";
  else if (glob[1] > 0)
    os << "Fix mpm/fluid: " << glob[1] << " atoms of " << G << " have the material points' type " << T
       << " but no state of this fix (ID '" << id << "'): the restart file is truncated or was written without this fix "
       << "(or with another fix ID), or another command created atoms of type " << T;
  else if (glob[2] > 0)
    os << "Fix mpm/fluid: " << glob[2] << " atoms of type " << T << " are outside " << G
       << " of the fix: grains must not share the type of the material points (give them another atom type)";
  if (!os.str().empty()) error->all(FLERR, os.str().c_str());
}

/* Checks at a run's setup of what a scene seldom means, each a warning once per fix:
   - a mesh that walls the grains (fix wall/gran) but not the fluid lets the water through it (a
     drum or tank whose mesh_wall was left out), named when its bounds come within a cell of the
     points' (first setup);
   - another fix mpm/fluid whose grid overlaps this one's is a second fluid that this one passes
     through (first setup);
   - atoms of finite radius that are neither points nor in the couple group (all of them without
     couple) within the points' bounds feel no fluid force, and the fluid does not feel them
     (couple left out, or given a smaller group); checked at every setup until it warns, so that
     grains inserted in an earlier run are seen. */
void FixMpmFluid::warn_unheld() {
  if (grain_walls_checked && overlap_checked && uncoupled_warned) return;
  const mpm::GridSpec &g = solver->opt.grid;
  // the points' bounds over all ranks, box[d] = -lo[d], box[3 + d] = hi[d] (one reduction for the
  // checks below)
  double box[6] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (int i = 0; i < atom->nlocal; ++i)
    if (is_point(i))
      for (int d = 0; d < 3; ++d) {
        box[d] = std::max(box[d], -atom->x[i][d]);
        box[3 + d] = std::max(box[3 + d], atom->x[i][d]);
      }
  MPI_Allreduce(MPI_IN_PLACE, box, 6, MPI_DOUBLE, MPI_MAX, world);
  const double lo[3] = {-box[0], -box[1], -box[2]}, hi[3] = {box[3], box[4], box[5]};
  if (!grain_walls_checked) {
    grain_walls_checked = true;
    std::vector<std::string> fluid;
    for (const mpm::MeshWallSpec &w : mesh_specs) fluid.push_back(w.fix_id);
    double glo[3], ghi[3];
    for (int d = 0; d < 3; ++d) {
      glo[d] = g.periodic[d] ? -HUGE_VAL : g.origin[d];
      ghi[d] = g.periodic[d] ? HUGE_VAL : g.upper(d);
    }
    const std::vector<std::string> ids = mpm::grain_walls_beside_fluid(lmp, fluid, lo, hi, glo, ghi, g.dx);
    if (comm->me == 0)
      for (const std::string &id : ids) {
        const std::string msg = "Fix mpm/fluid: the mesh of fix " + id + " is a wall of the grains (fix wall/gran) but " +
                                "not of the fluid, and the water reaches it: the water passes through it. Give " +
                                "'mesh_wall " + id + " ...' to fix mpm/fluid if it should hold the water";
        error->warning(FLERR, msg.c_str());
      }
  }
  // another fix mpm/fluid whose grid overlaps this one's: two fluids that pass through each other
  // (each fix is a fluid of its own; the later fix in the input warns)
  if (!overlap_checked) {
    overlap_checked = true;
    for (int f = 0; f < modify->nfix && modify->fix[f] != this; ++f) {
      auto *o = dynamic_cast<FixMpmFluid *>(modify->fix[f]);
      if (!o || !o->solver) continue;
      const mpm::GridSpec &h = o->solver->opt.grid;
      bool overlap = true;
      for (int d = 0; d < 3; ++d) overlap = overlap && g.origin[d] < h.upper(d) && h.origin[d] < g.upper(d);
      if (!overlap || comm->me != 0) continue;
      const std::string msg = std::string("Fix mpm/fluid: the grids of fix ") + o->id + " and fix " + id +
                              " overlap: each fix is a fluid of its own, and the two pass through each other " +
                              "(a mixture of fluids is not modelled)";
      error->warning(FLERR, msg.c_str());
    }
  }
  if (uncoupled_warned) return;
  long mine = 0, all = 0;
  for (int i = 0; i < atom->nlocal; ++i) {
    // (radius 0: a point, also of another fix mpm/fluid)
    if (is_point(i) || (atom->mask[i] & couple_groupbit) || !(atom->radius[i] > 0.0)) continue;
    bool in = true;
    for (int d = 0; d < 3 && in; ++d) in = atom->x[i][d] >= lo[d] && atom->x[i][d] <= hi[d];
    mine += in;
  }
  MPI_Allreduce(&mine, &all, 1, MPI_LONG, MPI_SUM, world);
  if (all == 0) return;
  uncoupled_warned = true;
  if (comm->me != 0) return;
  std::ostringstream os;
  os << "Fix mpm/fluid: " << all << (all == 1 ? " atom that is no material point lies" : " atoms that are no material points lie")
     << " within the points' bounds and " << (all == 1 ? "is " : "are ")
     << (couple_groupbit ? "not in the couple group '" + solver->opt.couple_group + "'" : std::string("not coupled (no keyword 'couple')"))
     << ": they feel no fluid force and the fluid does not feel them. Give 'couple GROUP' with their group for "
     << "two-way coupling";
  error->warning(FLERR, os.str().c_str());
}
