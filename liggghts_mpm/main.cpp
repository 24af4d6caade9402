// liggghts_mpm: the LIGGGHTS executable (same command line: -in, -var, -log,
// -echo, -screen, ...) with this project's styles registered before the
// input script is read. Two flags are ours: -h/-help (LIGGGHTS' help plus
// our styles) and -version/--version.
#include <mpi.h>

#include <cstdio>
#include <cstring>
#include <vector>

#include "input.h"
#include "lammps.h"
#include "universe.h"

#include "style_registry.h"

#ifndef LIGGGHTS_MPM_VERSION
#error "LIGGGHTS_MPM_VERSION is set by CMake from project(... VERSION ...)"
#endif

namespace {

bool is_any(const char *arg, std::initializer_list<const char *> names) {
  for (const char *n : names)
    if (std::strcmp(arg, n) == 0) return true;
  return false;
}

}  // namespace

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  bool help = false, version = false;
  // The arguments LIGGGHTS sees: ours removed. A value of -var or -in that
  // happens to read "-h" is taken for the flag, as LIGGGHTS itself does.
  std::vector<char *> args;
  for (int i = 0; i < argc; ++i) {
    if (i > 0 && is_any(argv[i], {"-h", "-help", "--help"})) {
      help = true;
    } else if (i > 0 && is_any(argv[i], {"-version", "--version"})) {
      version = true;
    } else {
      args.push_back(argv[i]);
    }
  }

  if (version) {
    // A quiet instance (no banner, no log file) only to read the library's
    // version string.
    char log[] = "-log", screen[] = "-screen", none[] = "none", nocite[] = "-nocite";
    char *quiet[] = {argv[0], log, none, screen, none, nocite};
    auto *lmp = new LAMMPS_NS::LAMMPS(6, quiet, MPI_COMM_WORLD);
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0) {
      std::printf("liggghts_mpm %s\nLIGGGHTS (%s)\n", LIGGGHTS_MPM_VERSION, lmp->universe->version);
      std::fflush(stdout);
    }
    delete lmp;
    MPI_Finalize();
    return 0;
  }

  if (help) {
    // No log file for a help request.
    char log[] = "-log", none[] = "none";
    args.push_back(log);
    args.push_back(none);
  }
  args.push_back(nullptr);
  auto *lmp = new LAMMPS_NS::LAMMPS(int(args.size()) - 1, args.data(), MPI_COMM_WORLD);
  mpm::register_styles(lmp);
  if (help) {
    if (lmp->universe->me == 0) mpm::print_help(lmp, LIGGGHTS_MPM_VERSION);
  } else {
    lmp->input->file();
  }
  delete lmp;
  MPI_Finalize();
  return 0;
}
