// Restart files complete or absent. LIGGGHTS writes restart files with stdio and checks no write:
// on a full disk or past a file-size limit it left a truncated file and said nothing. Here the file
// LIGGGHTS writes (on rank 0) is a FIFO; a thread of rank 0 copies what arrives into
// 'file'.partial, checking every write, and the copy is renamed to 'file' only when all of it was
// written (the file's size on disk equal to the bytes received). Otherwise the partial copy is
// removed, an older file of the same name is left as it was, and the run stops with an error
// naming the file and the cause (docs/fix_mpm_fluid.md, Restrictions).
//
// Covered: the write_restart command (replaced by write_restart_command) and the files of the
// restart command while a fix mpm/fluid is defined (it redirects them: PeriodicRestarts). File
// names with '%' (one file per process) are written by LIGGGHTS unchecked.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lmptype.h"

namespace LAMMPS_NS {
class LAMMPS;
}

namespace mpm {

// One file taken through a FIFO on rank 0 (on other ranks: inactive, finish() returns "").
class FifoCopy {
 public:
  FifoCopy(const std::string &file, const std::string &fifo, bool rank0);
  ~FifoCopy();
  FifoCopy(const FifoCopy &) = delete;
  FifoCopy &operator=(const FifoCopy &) = delete;
  // After the writer is done (or never opened the FIFO): "" when the file is in place, else the
  // cause. nothing_is_error: a writer that never opened the FIFO is an error (else: no file, "").
  std::string finish(bool nothing_is_error);
  const std::string &file() const { return file_; }

 private:
  struct State;
  std::string file_;
  std::unique_ptr<State> st_;
};

// Collective over lmp->world: runs write(path), a LIGGGHTS restart writer whose rank 0 opens path,
// with path a FIFO copied into 'file'; error->all when the file could not be written completely.
void write_restart_checked(LAMMPS_NS::LAMMPS *lmp, const std::string &file,
                           const std::function<void(char *path)> &write);

// The write_restart command as LIGGGHTS', its file written through write_restart_checked.
void write_restart_command(LAMMPS_NS::LAMMPS *lmp, int narg, char **arg);

// Registers write_restart_command as the command write_restart.
void register_restart_command(LAMMPS_NS::LAMMPS *lmp);

// The files of the restart command. arm(): called at the end of a step before LIGGGHTS' output
// (a fix's end_of_step): the files due at this step are redirected to FIFOs. settle(): after that
// output (the next step, the end of the run): the files renamed into place or removed, error->all
// on failure (collective). One per process (one LAMMPS instance): periodic_restarts().
class PeriodicRestarts {
 public:
  void arm(LAMMPS_NS::LAMMPS *lmp);
  void settle(LAMMPS_NS::LAMMPS *lmp);
  ~PeriodicRestarts();

 private:
  LAMMPS_NS::bigint step_ = -1;
  char *saved_[3] = {nullptr, nullptr, nullptr};  // Output's restart1, restart2a, restart2b
  char *ours_[3] = {nullptr, nullptr, nullptr};
  std::vector<std::unique_ptr<FifoCopy>> copies_;
  LAMMPS_NS::LAMMPS *lmp_ = nullptr;
  void restore();
};
PeriodicRestarts &periodic_restarts();

}  // namespace mpm
