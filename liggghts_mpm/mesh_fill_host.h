// fill ... inside mesh-ID [outside mesh-ID ...]: the triangles of the named LIGGGHTS meshes
// (fix mesh/surface) gathered on every rank, checked closed, and the mask of the fill's lattice
// (mpm/mesh_fill.h).
#pragma once

#include <string>
#include <vector>

#include "mpm/mesh_fill.h"
#include "mpm/options.h"

namespace LAMMPS_NS {
class LAMMPS;
}

namespace mpm {

// Collective. The triangles of the fix mesh/surface 'id' (all of them, on every rank); throws
// mpm::Error naming the keyword ('fill inside' or 'fill outside') and the ID if there is no such
// fix, it is no triangle mesh or the mesh is not closed.
std::vector<Tri9> gather_closed_mesh(LAMMPS_NS::LAMMPS *lmp, const std::string &id, const char *keyword);

// Collective. The lattice points to fill: inside o.fill_inside (if given), outside every mesh of
// o.fill_outside, and at least gap from each of their triangles (mesh_fill_mask).
std::vector<char> fill_mesh_mask(LAMMPS_NS::LAMMPS *lmp, const Options &o, const FillLattice &lat, double gap);

// Collective. The IDs of the meshes that are walls of the grains (a fix wall/gran made their
// neighbour list) but not of the fluid (not in fluid_walls), and whose triangles inside the grid
// (glo..ghi; a triangle on or beyond a face of it is the grid face's to hold) have a bounding box
// within reach of the box lo..hi (the points' bounds over all ranks; lo > hi without points).
std::vector<std::string> grain_walls_beside_fluid(LAMMPS_NS::LAMMPS *lmp, const std::vector<std::string> &fluid_walls,
                                                  const double lo[3], const double hi[3], const double glo[3],
                                                  const double ghi[3], double reach);

}  // namespace mpm
