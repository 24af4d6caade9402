// The largest pressure of fix mpm/fluid's global output f_ID[10], as a statistic over grid cells:
// the mean pressure of the points in each cell of the background grid, its largest over all cells
// that hold points. A single point whose pressure stands out (a point squeezed among grains on a
// floor) moves its cell's mean by 1/n of its excess only (n points per cell), so the reported
// value follows the pressure field, not the noise of one point. Independent of LIGGGHTS.
#pragma once

#include <mpi.h>

#include <vector>

#include "mpm/grid.h"

namespace mpm {

// Global index of the grid cell holding x: floor((x - origin) / dx) along each dimension, wrapped
// into 0..ncell-1 along a periodic one and clamped into it along the others (a point put back at a
// wall can lie a round-off outside the grid), flattened x fastest.
long long cell_key(const GridSpec &gs, const double x[3]);

// Collective over comm: the largest over the cells of the mean of value[i] over the entries i with
// key[i] == that cell, summed over all ranks (a cell's points may lie on several ranks: each cell's
// sums meet on the rank key % nprocs). -HUGE_VAL if no rank has an entry.
double largest_cell_mean(MPI_Comm comm, const std::vector<long long> &key, const std::vector<double> &value);

}  // namespace mpm
