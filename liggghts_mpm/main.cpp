// liggghts_mpm: the LIGGGHTS executable (same command line: -in, -var, -log,
// -echo, -screen, ...) with this project's styles registered before the
// input script is read.
#include <mpi.h>

#include "input.h"
#include "lammps.h"

#include "style_registry.h"

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  auto *lmp = new LAMMPS_NS::LAMMPS(argc, argv, MPI_COMM_WORLD);
  mpm::register_styles(lmp);
  lmp->input->file();
  delete lmp;
  MPI_Finalize();
  return 0;
}
