#include "style_registry.h"

#include <map>
#include <string>

#include "fix.h"
#include "lammps.h"
#include "modify.h"

#include "fix_balance_mpm.h"
#include "fix_mpm_fluid.h"

using namespace LAMMPS_NS;

namespace {

// Modify keeps its map from style names to creator functions private. An
// explicit template instantiation may name a private member (C++17
// [temp.explicit]/12), and the friend function it defines hands out the
// pointer-to-member; no LIGGGHTS source is patched or copied.
typedef Fix *(*FixCreatorFn)(LAMMPS *, int, char **);
typedef std::map<std::string, FixCreatorFn> *Modify::*FixMapMember;

FixMapMember modify_fix_map();

template <FixMapMember M>
struct FixMapAccess {
  friend FixMapMember modify_fix_map() { return M; }
};
template struct FixMapAccess<&Modify::fix_map>;

template <class T>
Fix *create_fix(LAMMPS *lmp, int narg, char **arg) {
  return new T(lmp, narg, arg);
}

}  // namespace

void mpm::register_styles(LAMMPS *lmp) {
  std::map<std::string, FixCreatorFn> &fixes = *(lmp->modify->*modify_fix_map());
  fixes["mpm/fluid"] = &create_fix<FixMpmFluid>;
  fixes["balance/mpm"] = &create_fix<FixBalanceMpm>;
}
