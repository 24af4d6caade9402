// HDF5 + XDMF time-series writer for MPM output, collective over an MPI communicator.
//
// Per step: <prefix>_<step, 9 digits>.h5 containing
//   /            attributes  time (double), step (int64)
//   /points/xyz  (n, 3)      /points/<field>  (n) or (n, ncomp)
//   /grid/<field> (n2, n1, n0[, ncomp])  with group attributes
//                n, origin, spacing (3 values each, ordered x y z)
// and one index <prefix>.xmf (XDMF 3, Temporal collection) that is rewritten
// atomically (tmp file + rename) after every step. Data sets are referenced by
// file basename, so the output folder can be moved as a whole.
//
// Every rank passes its own points and its own box of grid nodes; the file holds the points of
// rank 0, then those of rank 1, ... With the parallel HDF5 library (MPM_HDF5_PARALLEL, MPI-IO)
// each rank writes its rows of the same data sets; with the serial library rank 0 gathers them
// and writes alone. The layout is the same either way.
#ifndef MPM_HDF5_SERIES_H
#define MPM_HDF5_SERIES_H

#include <mpi.h>

#include <cstddef>
#include <string>
#include <vector>

namespace mpm {

struct Field {
  std::string name;          // HDF5/XDMF name: non-empty, no '/', ':' or '.'/'..'
  int ncomp;                 // components per point/node (>= 1)
  std::vector<double> data;  // n*ncomp values, component fastest
};

struct PointBlock {  // this rank's points
  std::size_t n = 0;
  std::vector<double> xyz;  // 3n
  std::vector<Field> fields;
};

struct GridBlock {  // node-centred; x index fastest, then y, then z
  int n[3];                   // nodes of the whole grid
  double origin[3];
  double spacing[3];
  std::vector<Field> fields;  // this rank's box: data size count0*count1*count2*ncomp
  // This rank's box of nodes (global indices of its first node, node counts); count -1: the whole
  // grid. The boxes of all ranks must tile the grid.
  int lo[3] = {0, 0, 0};
  int count[3] = {-1, -1, -1};
};

class Hdf5Series {
 public:
  // Collective over comm (every rank gives the same prefix). If <prefix>.xmf exists (restart),
  // its steps are kept and new ones appended.
  // Throws std::runtime_error on every rank if the directory of prefix does not exist or the
  // existing .xmf was not written by Hdf5Series.
  explicit Hdf5Series(const std::string &prefix, MPI_Comm comm = MPI_COMM_SELF);

  // Collective: writes the step file, then rank 0 rewrites the .xmf. Entries with step >= `step`
  // are dropped from the index first (replace / abandoned restart branch); their
  // .h5 files are left on disk (the same-step file is overwritten). Every rank gives the same
  // step, time, field names and counts, and a grid or none.
  // Throws std::runtime_error on every rank, with the same message (it names the file), on a
  // failure on any rank; the step file is then absent and the previous .xmf stays intact.
  void write_step(long step, double time, const PointBlock &pts, const GridBlock *grid);

  // Wall time of the last write_step (slowest rank: the call ends with an agreement of all).
  double last_write_seconds() const { return last_seconds_; }

  const std::string &xdmf_path() const { return xmf_path_; }
  std::string step_path(long step) const;  // full path of the step's .h5 file

  struct Entry {
    long step;
    double time;
    std::string file;  // basename of the .h5 file
    std::string xml;   // this step's XDMF block (with marker comments)
  };
  const std::vector<Entry> &entries() const { return entries_; }  // kept on rank 0 only

 private:
  std::string prefix_, base_, xmf_path_;
  MPI_Comm comm_;
  int me_ = 0, nprocs_ = 1;
  double last_seconds_ = 0.0;
  std::vector<Entry> entries_;
  void load_existing();
  void write_xmf() const;
};

}  // namespace mpm

#endif
