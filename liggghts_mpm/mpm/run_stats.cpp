#include "mpm/run_stats.h"

#include <sys/resource.h>

#include <sstream>

namespace mpm {

namespace {

// min, mean and max of v over the ranks of comm, written "min/mean/max"
std::string spread(MPI_Comm comm, double v) {
  int n = 1;
  MPI_Comm_size(comm, &n);
  double mx[2] = {v, -v}, g[2], sum = 0.0;
  MPI_Allreduce(mx, g, 2, MPI_DOUBLE, MPI_MAX, comm);
  MPI_Allreduce(&v, &sum, 1, MPI_DOUBLE, MPI_SUM, comm);
  std::ostringstream os;
  os.precision(6);
  os << -g[1] << "/" << sum / n << "/" << g[0];
  return os.str();
}

}  // namespace

std::string run_stats_lines(MPI_Comm comm, const LocalGrid &g, const RunStatsStart &start, long points) {
  int nprocs = 1;
  MPI_Comm_size(comm, &nprocs);
  const LocalGrid::ExchangeCounts &c = g.exchange_counts(), &s = start.counts;
  const long nx = c.exchanges - s.exchanges;
  const double per = nx > 0 ? 1.0 / double(nx) : 0.0;
  // sums over the ranks: every message and byte sent is received once
  long long mine[4] = {c.msgs_sent - s.msgs_sent, c.msgs_recv - s.msgs_recv, c.bytes_sent - s.bytes_sent,
                       c.bytes_recv - s.bytes_recv},
            tot[4];
  MPI_Allreduce(mine, tot, 4, MPI_LONG_LONG, MPI_SUM, comm);
  const double wait = g.wait_seconds() - start.wait;
  std::ostringstream os;
  os.precision(6);
  os << "fix mpm/fluid: halo exchanges in this run (min/mean/max over " << nprocs << " ranks): exchanges "
     << spread(comm, double(nx)) << "; per exchange: messages sent " << spread(comm, double(mine[0]) * per)
     << ", bytes sent " << spread(comm, double(mine[2]) * per) << ", wait " << spread(comm, wait * per)
     << " s; all ranks: messages sent " << tot[0] << " received " << tot[1] << ", bytes sent " << tot[2]
     << " received " << tot[3] << "\n";
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  double kib = double(ru.ru_maxrss), mem[2];  // Linux: KiB
  MPI_Allreduce(&kib, &mem[0], 1, MPI_DOUBLE, MPI_MAX, comm);
  MPI_Allreduce(&kib, &mem[1], 1, MPI_DOUBLE, MPI_SUM, comm);
  os << "fix mpm/fluid: work per rank (min/mean/max over " << nprocs << " ranks): points " << spread(comm, double(points))
     << ", owned nodes " << spread(comm, double(g.owned().count())) << ", patch nodes "
     << spread(comm, double(g.patch().count())) << "; peak memory (ru_maxrss) max " << mem[0] / 1024.0
     << " MiB per rank, sum " << mem[1] / 1024.0 << " MiB\n";
  return os.str();
}

}  // namespace mpm
