// Serial HDF5 + XDMF time-series writer for MPM output (call on one rank only).
//
// Per step: <prefix>_<step, 9 digits>.h5 containing
//   /            attributes  time (double), step (int64)
//   /points/xyz  (n, 3)      /points/<field>  (n) or (n, ncomp)
//   /grid/<field> (n2, n1, n0[, ncomp])  with group attributes
//                n, origin, spacing (3 values each, ordered x y z)
// and one index <prefix>.xmf (XDMF 3, Temporal collection) that is rewritten
// atomically (tmp file + rename) after every step. Data sets are referenced by
// file basename, so the output folder can be moved as a whole.
#ifndef MPM_HDF5_SERIES_H
#define MPM_HDF5_SERIES_H

#include <cstddef>
#include <string>
#include <vector>

namespace mpm {

struct Field {
  std::string name;          // HDF5/XDMF name: non-empty, no '/', ':' or '.'/'..'
  int ncomp;                 // components per point/node (>= 1)
  std::vector<double> data;  // n*ncomp values, component fastest
};

struct PointBlock {
  std::size_t n = 0;
  std::vector<double> xyz;  // 3n
  std::vector<Field> fields;
};

struct GridBlock {  // node-centred; x index fastest, then y, then z
  int n[3];
  double origin[3];
  double spacing[3];
  std::vector<Field> fields;  // data size n0*n1*n2*ncomp
};

class Hdf5Series {
 public:
  // If <prefix>.xmf exists (restart), its steps are kept and new ones appended.
  // Throws std::runtime_error if the directory of prefix does not exist or the
  // existing .xmf was not written by Hdf5Series.
  explicit Hdf5Series(const std::string &prefix);

  // Writes the step file, then rewrites the .xmf. Entries with step >= `step`
  // are dropped from the index first (replace / abandoned restart branch); their
  // .h5 files are left on disk (the same-step file is overwritten).
  // Throws std::runtime_error (message names the file) on any failure; the
  // previous .xmf stays intact in that case.
  void write_step(long step, double time, const PointBlock &pts, const GridBlock *grid);

  const std::string &xdmf_path() const { return xmf_path_; }
  std::string step_path(long step) const;  // full path of the step's .h5 file

  struct Entry {
    long step;
    double time;
    std::string file;  // basename of the .h5 file
    std::string xml;   // this step's XDMF block (with marker comments)
  };
  const std::vector<Entry> &entries() const { return entries_; }

 private:
  std::string prefix_, base_, xmf_path_;
  std::vector<Entry> entries_;
  void load_existing();
  void write_xmf() const;
};

}  // namespace mpm

#endif
