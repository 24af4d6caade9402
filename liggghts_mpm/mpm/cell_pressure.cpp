// The largest cell-mean point pressure (f_ID[10]); see cell_pressure.h.
#include "mpm/cell_pressure.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "mpm/mpi_exchange.h"

namespace mpm {

long long cell_key(const GridSpec &gs, const double x[3]) {
  long long c[3];
  for (int d = 0; d < 3; ++d) {
    long long k = static_cast<long long>(std::floor((x[d] - gs.origin[d]) / gs.dx));
    const long long n = gs.ncell[d];
    if (gs.periodic[d])
      k = ((k % n) + n) % n;
    else
      k = std::min(std::max(k, 0LL), n - 1);
    c[d] = k;
  }
  return (c[2] * gs.ncell[1] + c[1]) * gs.ncell[0] + c[0];
}

double largest_cell_mean(MPI_Comm comm, const std::vector<long long> &key, const std::vector<double> &value) {
  int nprocs = 1;
  MPI_Comm_size(comm, &nprocs);
  // this rank's sums per cell
  std::unordered_map<long long, std::pair<double, double>> mine;  // key -> (sum, count)
  for (std::size_t i = 0; i < key.size(); ++i) {
    auto &s = mine[key[i]];
    s.first += value[i];
    s.second += 1.0;
  }
  // to the rank key % nprocs: records (key, sum, count) as three doubles (keys < 2^53)
  std::vector<std::vector<double>> out(nprocs);
  for (const auto &e : mine) {
    std::vector<double> &o = out[static_cast<int>(e.first % nprocs)];
    o.push_back(static_cast<double>(e.first));
    o.push_back(e.second.first);
    o.push_back(e.second.second);
  }
  int rtot = 0;
  const std::vector<double> rbuf = exchange_records(comm, out, rtot);
  std::unordered_map<long long, std::pair<double, double>> cells;
  for (int at = 0; at + 3 <= rtot; at += 3) {
    auto &s = cells[static_cast<long long>(rbuf[at])];
    s.first += rbuf[at + 1];
    s.second += rbuf[at + 2];
  }
  double best = -HUGE_VAL, all = -HUGE_VAL;
  for (const auto &e : cells) best = std::max(best, e.second.first / e.second.second);
  MPI_Allreduce(&best, &all, 1, MPI_DOUBLE, MPI_MAX, comm);
  return all;
}

}  // namespace mpm
