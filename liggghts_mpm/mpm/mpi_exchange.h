// Records of doubles sent to every rank and received from every rank (MPI_Alltoallv), for the
// exchanges that route data to the rank that owns it (mesh wall triangles, cell sums).
#pragma once
#include <mpi.h>

#include <algorithm>
#include <vector>

namespace mpm {

// out[q]: the values this rank sends to rank q (out.size() = the number of ranks of comm).
// Returns the values of all ranks received by this one, in rank order; rtot: their count.
// Collective over comm.
inline std::vector<double> exchange_records(MPI_Comm comm, const std::vector<std::vector<double>> &out, int &rtot) {
  const int nprocs = static_cast<int>(out.size());
  std::vector<int> scount(nprocs), rcount(nprocs), sdisp(nprocs), rdisp(nprocs);
  for (int q = 0; q < nprocs; ++q) scount[q] = static_cast<int>(out[q].size());
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, comm);
  int stot = 0;
  rtot = 0;
  for (int q = 0; q < nprocs; ++q) {
    sdisp[q] = stot;
    rdisp[q] = rtot;
    stot += scount[q];
    rtot += rcount[q];
  }
  std::vector<double> sbuf(std::max(stot, 1)), rbuf(std::max(rtot, 1));
  for (int q = 0; q < nprocs; ++q) std::copy(out[q].begin(), out[q].end(), sbuf.begin() + sdisp[q]);
  MPI_Alltoallv(sbuf.data(), scount.data(), sdisp.data(), MPI_DOUBLE, rbuf.data(), rcount.data(), rdisp.data(),
                MPI_DOUBLE, comm);
  return rbuf;
}

}  // namespace mpm
