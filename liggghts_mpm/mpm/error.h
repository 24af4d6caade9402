// The solver's one error mechanism: it throws, the LIGGGHTS adapter translates.
//   mpm::Error       every rank finds it (input checks, time-step limits: collective decisions);
//                    the adapter calls error->all.
//   mpm::LocalError  one rank finds it (a point left the grid, a velocity became NaN); the other
//                    ranks do not know, so the adapter prints, flushes and aborts MPI.
#pragma once
#include <stdexcept>
#include <string>

namespace mpm {

struct Error : std::runtime_error {
  explicit Error(const std::string &msg) : std::runtime_error(msg) {}
};

struct LocalError : std::runtime_error {
  explicit LocalError(const std::string &msg) : std::runtime_error(msg) {}
};

}  // namespace mpm
