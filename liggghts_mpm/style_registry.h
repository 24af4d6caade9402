// Registers this project's styles into a LAMMPS/LIGGGHTS instance built from
// the prebuilt Debian library, which has no plugin mechanism.
#pragma once

namespace LAMMPS_NS { class LAMMPS; }

namespace mpm {
// Adds every style of this project (fix mpm/fluid, ...) to lmp's style maps.
void register_styles(LAMMPS_NS::LAMMPS *lmp);
}
