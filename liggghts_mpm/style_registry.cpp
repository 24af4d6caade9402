#include "style_registry.h"

#include <cstdio>
#include <cstring>
#include <map>
#include <string>

#include "fix.h"
#include "lammps.h"
#include "modify.h"

#include "fix_balance_mpm.h"
#include "fix_mpm_fluid.h"
#include "restart_guard.h"

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

// LAMMPS::help() is private too; the same explicit instantiation gives its
// pointer-to-member.
typedef void (LAMMPS::*HelpMember)();

HelpMember lammps_help();

template <HelpMember M>
struct HelpAccess {
  friend HelpMember lammps_help() { return M; }
};
template struct HelpAccess<&LAMMPS::help>;

template <class T>
Fix *create_fix(LAMMPS *lmp, int narg, char **arg) {
  return new T(lmp, narg, arg);
}

// Every fix style of this project: the one list registration and help use.
struct FixStyle {
  const char *name;
  FixCreatorFn create;
};
const FixStyle kFixStyles[] = {
    {"balance/mpm", &create_fix<FixBalanceMpm>},
    {"mpm/fluid", &create_fix<FixMpmFluid>},
};

}  // namespace

void mpm::register_styles(LAMMPS *lmp) {
  std::map<std::string, FixCreatorFn> &fixes = *(lmp->modify->*modify_fix_map());
  for (const FixStyle &s : kFixStyles) fixes[s.name] = s.create;
  mpm::register_restart_command(lmp);  // write_restart: the file complete or absent
}

std::vector<std::string> mpm::fix_style_names() {
  std::vector<std::string> names;
  for (const FixStyle &s : kFixStyles) names.push_back(s.name);
  return names;
}

void mpm::print_help(LAMMPS *lmp, const char *version) {
  (lmp->*lammps_help())();
  FILE *out = lmp->screen;
  if (!out) return;
  // LIGGGHTS' layout: a '* ... styles' heading, then the names in columns of
  // 32 characters, five to a line.
  std::fprintf(out, "\n* Fix styles added by liggghts_mpm %s (pages: docs/fix_<name, / as _>.md):\n\n", version);
  int column = 0;
  for (const FixStyle &s : kFixStyles) {
    const int width = std::strlen(s.name) < 32 ? 32 : 64;
    if (column + width > 160) {
      std::fprintf(out, "\n");
      column = 0;
    }
    std::fprintf(out, "%-*s", width, s.name);
    column += width;
  }
  std::fprintf(out, "\n\n");
  std::fflush(out);
}
