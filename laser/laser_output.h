// Output of laser_drill: summary.json (nlohmann-json), CSV tables and the
// HDF5 time series (frames streamed as they come). Every file is written under
// a temporary name in the output folder, checked, and renamed into place at
// the end, summary.json last: a summary.json proves the files beside it.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "laser_model.h"
#include "laser_params.h"

namespace laser {

// Error while writing output: the message names the file.
struct WriteError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The output folder of one run. The constructor checks it before anything is
// computed (a directory or creatable, empty unless overwrite, not locked by
// another run; UsageError naming --out otherwise), creates it and takes the
// lock file. Files are staged as "<name>.part" and renamed by commit(). The
// destructor removes staged files and the lock, and the folder if it created
// it and it is empty, so a failed run leaves nothing behind.
class OutputDir {
 public:
  OutputDir(const std::string& dir, bool overwrite);
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  // Streams frames into a staged profiles.h5 (a new file on every call: the
  // time-step policy may restart the reported run).
  std::unique_ptr<FrameSink> profiles_sink();
  void write_tables(const Config& cfg, const Result& r);
  // Writes summary.json last and renames everything into place.
  void commit(const std::string& summary);
  // Files an earlier run of laser_drill writes into its folder.
  static const std::vector<std::string>& output_names();
  // Temporary path of NAME, renamed to NAME by commit().
  std::string stage(const std::string& name);
  const std::string& path() const { return dir_; }

 private:
  std::string dir_;
  bool created_ = false;
  int lock_fd_ = -1;
  std::vector<std::string> staged_;
};

std::string summary_json(const Config& cfg, const Result& r, double wall_time_s);
// Figures 3.7/3.8: corrected-conduction gradients against s = (tau - tau_m)/tau_m.
void write_conduction_table(OutputDir& out);

}  // namespace laser
