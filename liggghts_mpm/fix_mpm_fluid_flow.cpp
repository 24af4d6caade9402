/* fix mpm/fluid's inflow and outflow faces, the adapter's part (docs/fix_mpm_fluid.md, "Flow in and
   out"): the points that left through an outflow face (marked mpm::kPointGone by the solver) are
   deleted and the layers of points an inflow face owes (mpm/flow_faces.cpp) are created. Atoms are
   made and deleted only where LIGGGHTS exchanges them (pre_exchange, as fix pour and fix evaporate
   do), on the step after a fluid step that left such work (schedule_flow forces the exchange), and
   at the setup of a run (a restart file written in between holds the marked points and the depth
   owed). The mass created and deleted is summed over the ranks into the solver's state. */

#include "fix_mpm_fluid.h"

#include <mpi.h>

#include <cmath>

#include "atom.h"
#include "atom_vec.h"
#include "domain.h"
#include "update.h"

using namespace LAMMPS_NS;

void FixMpmFluid::setup_pre_exchange() { flow_exchange(); }

void FixMpmFluid::pre_exchange() { flow_exchange(); }

// after a fluid step: an exchange of atoms on the next step if a point left or a layer is due
void FixMpmFluid::schedule_flow() {
  mpm::FluidSolver &s = *solver;
  if (!s.opt.flow_faces()) return;
  int due = s.points_gone() > 0 ? 1 : 0, any = 0;
  for (int f = 0; f < 6; ++f) due = due || s.inflow_layers(f) > 0;
  MPI_Allreduce(&due, &any, 1, MPI_INT, MPI_MAX, world);
  if (any) next_reneighbor = update->ntimestep + 1;
}

void FixMpmFluid::flow_exchange() {
  mpm::FluidSolver &s = *solver;
  if (!s.opt.flow_faces() || !filled) return;
  // the points that left: deleted (the last atom moved into the slot, as LIGGGHTS deletes)
  double mass[2] = {0.0, 0.0}, gmass[2];  // deleted, created (this rank)
  bigint counts[2] = {0, 0}, gcounts[2];
  int i = 0;
  while (i < atom->nlocal) {
    if (is_point(i) && pdata[i][mpm::C_FLAG] == mpm::kPointGone) {
      mass[0] += atom->rmass[i];
      ++counts[0];
      atom->avec->copy(atom->nlocal - 1, i, 1);
      --atom->nlocal;
    } else {
      ++i;
    }
  }
  s.clear_gone();
  // the inflow's layers due, each rank the points inside its subdomain; the same on every rank
  for (int f = 0; f < 6; ++f) {
    const int n = s.inflow_layers(f);
    for (int j = 0; j < n; ++j) {
      const int before = atom->nlocal;
      counts[1] += create_inflow_layer(f, s.inflow_layer_position(f, j));
      for (int k = before; k < atom->nlocal; ++k) mass[1] += atom->rmass[k];
    }
    if (n > 0) s.inflow_created(f, n);
  }
  MPI_Allreduce(mass, gmass, 2, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(counts, gcounts, 2, MPI_LMP_BIGINT, MPI_SUM, world);
  s.state.mass_out += gmass[0];
  s.state.mass_in += gmass[1];
  if (gcounts[0] == 0 && gcounts[1] == 0) return;
  bigint nlocal = atom->nlocal;
  MPI_Allreduce(&nlocal, &atom->natoms, 1, MPI_LMP_BIGINT, MPI_SUM, world);
  if (gcounts[1] > 0) atom->tag_extend();
  if (atom->map_style) {
    atom->nghost = 0;
    atom->map_init();
    atom->map_set();
  }
  vector_step = -1;
}

/* One layer of inflow face f at coordinate pos along its normal: the fill's lattice across the face
   (the fill's points per cell), the points of this rank's subdomain, moving in at the inflow's
   velocity. Returns the number created. */
int FixMpmFluid::create_inflow_layer(int f, double pos) {
  const mpm::Options &o = solver->opt;
  const mpm::GridSpec &gs = o.grid;
  const double *sp = solver->state.spacing;
  const int d = f / 2, e1 = (d + 1) % 3, e2 = (d + 2) % 3;
  const double vol = sp[0] * sp[1] * sp[2];
  if (!(pos >= domain->sublo[d] && pos < domain->subhi[d])) return 0;
  const int n1 = gs.ncell[e1] * o.fill_ppc[e1], n2 = gs.ncell[e2] * o.fill_ppc[e2];
  // the lattice lines inside this subdomain: x = origin + (a + 1/2) s in [sublo, subhi)
  auto first = [&](int e) {
    return std::max(0, static_cast<int>(std::ceil((domain->sublo[e] - gs.origin[e]) / sp[e] - 0.5)) - 1);
  };
  int made = 0;
  double x[3];
  x[d] = pos;
  for (int b = first(e2); b < n2; ++b) {
    x[e2] = gs.origin[e2] + (b + 0.5) * sp[e2];
    if (x[e2] >= domain->subhi[e2]) break;
    if (x[e2] < domain->sublo[e2]) continue;
    for (int a = first(e1); a < n1; ++a) {
      x[e1] = gs.origin[e1] + (a + 0.5) * sp[e1];
      if (x[e1] >= domain->subhi[e1]) break;
      if (x[e1] < domain->sublo[e1]) continue;
      create_point(x, vol);
      const int k = atom->nlocal - 1;
      atom->v[k][d] = o.face_velocity(f);
      ++made;
    }
  }
  return made;
}
