// Registers this project's styles into a LAMMPS/LIGGGHTS instance built from
// the prebuilt Debian library, which has no plugin mechanism, and lists them
// in the help text.
#pragma once

#include <string>
#include <vector>

namespace LAMMPS_NS { class LAMMPS; }

namespace mpm {
// Adds every style of this project (fix mpm/fluid, ...) to lmp's style maps.
void register_styles(LAMMPS_NS::LAMMPS *lmp);

// Names of the fix styles register_styles adds, in alphabetical order.
std::vector<std::string> fix_style_names();

// LIGGGHTS' own help text (command-line options and the styles compiled into
// the library) followed by this project's styles in the same layout; printed
// to lmp's screen. The library prints its help only while it constructs the
// instance, before our styles exist, so main() strips -h and calls this.
void print_help(LAMMPS_NS::LAMMPS *lmp, const char *version);
}
