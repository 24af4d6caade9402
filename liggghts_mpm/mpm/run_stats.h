// The halo exchanges, the work and the memory of each rank over one run, summarised on every rank
// (min, mean and max over the ranks) for fix mpm/fluid's end-of-run lines: what the strong-scaling
// model of docs/scaling.md reads (tools/scaling.py parses the lines).
#pragma once
#include <mpi.h>

#include <string>

#include "mpm/grid.h"

namespace mpm {

// This rank's counters at the start of a run.
struct RunStatsStart {
  LocalGrid::ExchangeCounts counts;
  double wait = 0.0;
};

inline RunStatsStart run_stats_start(const LocalGrid &g) { return {g.exchange_counts(), g.wait_seconds()}; }

// Collective over comm. The two lines (each ending in a newline) of the run since start: the
// exchanges (count; per exchange and rank: messages and bytes sent, wait; sums over the ranks of
// the messages and bytes sent and received) and the work and memory per rank (points, owned and
// patch nodes of the grid as it is now, peak resident memory ru_maxrss: max and sum over ranks).
std::string run_stats_lines(MPI_Comm comm, const LocalGrid &g, const RunStatsStart &start, long points);

}  // namespace mpm
