// The checks of fix mpm/fluid's settings after its keywords are read (options_checks.cpp); used by
// the parser and fix_modify (options.cpp).
#pragma once
#include <string>
#include <vector>

#include "mpm/options.h"

namespace mpm {

// A keyword given (seen) that another choice makes inert: an error naming it and the reason;
// command: "" (the fix command) or "fix_modify ".
void check_inert(const Options &o, const std::vector<std::string> &seen, const char *command);
// keyword superficial_velocity: its arguments from a.iarg (the keyword) on, for the fix command and
// fix_modify (modify_drive: the axis of the fix command only; returns the words used). Throw mpm::Error.
void parse_drive(Options &o, Args &a);
int modify_drive(Options &o, int narg, char **arg);
// keyword superficial_velocity on a periodic axis and no gate across it. Throws mpm::Error.
void check_drive(const Options &o);
// fix_modify boundary: no face became or stopped being an inflow or outflow face (before: the
// settings before it); else o = before and mpm::Error naming the face.
void check_flow_change(const Options &before, Options &o);
// parse_options after its keywords (seen; given: cell, density, bulk): the settings that follow
// from them, the grid fitted to the bounds and the checks. Throws mpm::Error.
void finish_options(Options &o, const std::vector<std::string> &seen, const bool given[3], const ParseEnv &env);

}  // namespace mpm
