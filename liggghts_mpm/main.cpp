// liggghts_mpm: the LIGGGHTS executable (same command line: -in, -var, -log,
// -echo, -screen, ...) with this project's styles registered before the
// input script is read. Two flags are ours: -h/-help (LIGGGHTS' help plus
// our styles) and -version/--version.
#include <mpi.h>

#include <cstdio>
#include <cstring>
#include <string>
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

// The screen as LIGGGHTS writes to it, passed through to the real screen; a line "ERROR on proc
// N: ..." (LIGGGHTS' error->one, which writes to the screen only and then aborts) is copied into
// the log file as well, so that every error of the run is in both.
struct ScreenTee {
  FILE *screen;
  FILE **logfile;  // LAMMPS::logfile (may change with the 'log' command)
  std::string line;
};

ssize_t tee_write(void *cookie, const char *buf, size_t size) {
  auto *t = static_cast<ScreenTee *>(cookie);
  const size_t n = std::fwrite(buf, 1, size, t->screen);
  for (size_t k = 0; k < size; ++k) {
    t->line.push_back(buf[k]);
    if (buf[k] != '\n') continue;
    if (t->line.rfind("ERROR on proc", 0) == 0 && *t->logfile) {
      std::fputs(t->line.c_str(), *t->logfile);
      std::fflush(*t->logfile);
    }
    t->line.clear();
  }
  return static_cast<ssize_t>(n);
}

int tee_close(void *cookie) {
  auto *t = static_cast<ScreenTee *>(cookie);
  const int rc = t->screen == stdout ? std::fflush(stdout) : std::fclose(t->screen);
  delete t;
  return rc;
}

// LIGGGHTS' error->all and error->one append, one time in five, a "comment from the off" or a "tip
// of the day" after the ERROR line, and they print it from the buffer of a std::string that has
// already been destroyed: a line of garbage in the screen and the log after the error. They do so
// only when the library's version string contains "PUBLIC"; the instance's string (its own buffer)
// is made to spell it "Public" after the banner has been printed (restart files carry that spelling).
void quiet_error_jokes(LAMMPS_NS::LAMMPS *lmp) {
  if (char *at = std::strstr(lmp->universe->version, "PUBLIC")) std::memcpy(at, "Public", 6);
}

}  // namespace

// Every abort of this executable goes through here (the MPI profiling interface: libliggghts'
// calls of MPI_Abort resolve to this definition, which ends in PMPI_Abort). LIGGGHTS prints an
// error to the screen and log file and then aborts without flushing them: when the screen is a pipe
// or a file (batch systems) or for the log file, the message stayed in the stdio buffers and was
// lost. Flushing every output stream first brings it out.
extern "C" int MPI_Abort(MPI_Comm comm, int errorcode) {
  std::fflush(nullptr);
  return PMPI_Abort(comm, errorcode);
}

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
  // '-screen none' leaves the first rank without a screen, and LIGGGHTS 3.8 writes to it
  // unconditionally in places (the STL import of fix mesh/surface, insertion): a segmentation
  // fault. A sink takes its place, behind the tee below, so that an error LIGGGHTS writes to the
  // screen only still reaches the log.
  if (!lmp->screen && lmp->universe->existflag == 0 && lmp->universe->me == 0)
    lmp->screen = std::fopen("/dev/null", "w");
  if (lmp->screen && lmp->logfile) {
    cookie_io_functions_t io = {nullptr, tee_write, nullptr, tee_close};
    auto *tee = new ScreenTee{lmp->screen, &lmp->logfile, std::string()};
    if (FILE *f = fopencookie(tee, "w", io)) {
      std::setvbuf(f, nullptr, _IOLBF, 0);
      lmp->screen = f;
    } else {
      delete tee;
    }
  }
  quiet_error_jokes(lmp);
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
