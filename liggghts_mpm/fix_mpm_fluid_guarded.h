// FixMpmFluid::guarded, the one place where the solver's errors become LIGGGHTS errors; a template,
// so both adapter files (fix_mpm_fluid.cpp, fix_mpm_fluid_points.cpp) include its definition.
#pragma once
#include <new>

#include "error.h"
#include "fix_mpm_fluid.h"
#include "mpm/error.h"

namespace LAMMPS_NS {

/* The solver's errors: mpm::Error is found by every rank (error->all); mpm::LocalError by one,
   which cannot wait for the others. error->one aborts without flushing stdio, so the message would
   be lost when the screen is a pipe or a file: print and flush first, then abort. */
template <class Fn>
void FixMpmFluid::guarded(Fn &&fn) {
  try {
    fn();
  } catch (const mpm::LocalError &e) {
    fail_one(e.what());
  } catch (const mpm::Error &e) {
    error->all(FLERR, e.what());
  } catch (const std::bad_alloc &) {
    fail_one("Fix mpm/fluid: out of memory on this rank (grid or points too large for the machine: a larger 'cell' or "
             "fewer points per cell)");
  }
}

}  // namespace LAMMPS_NS
