// Strict parsers of command arguments, shared by the fixes (fix mpm/fluid, fix balance/mpm).
// Independent of LIGGGHTS: each returns false on bad input and leaves the error message (command,
// keyword, unit, range, what was given) to the caller.
//
// Refused everywhere: an empty string, leading or trailing spaces, trailing characters of any kind,
// and hexadecimal ("0x10", "0x1p3"). Numbers are never wrapped or clipped: a value that does not fit
// is refused, not reduced modulo 2^32 or rounded to 0 or infinity.
#pragma once

#include <climits>
#include <cstdint>

namespace mpm {

// A finite decimal number, e.g. "1", "-2.5", "+.5", "5.", "1e-3", "2E+6". Refused besides the
// above: "nan", "inf", "infinity", values that overflow ("1e999") or underflow to zero or to a
// subnormal number ("1e-400", "1e-310").
bool parse_double(const char *s, double &v);

// A base-10 integer with an optional sign, e.g. "42", "-7", "+3", "007" (= 7). Refused besides the
// above: a decimal point or exponent ("1.0", "1e3") and values outside [-2^63, 2^63 - 1].
bool parse_int64(const char *s, std::int64_t &v);

// parse_int64 within [lo, hi] (an int): "4294967298" is refused (it would wrap to 2), as are
// values outside the caller's range.
bool parse_int(const char *s, int &v, int lo = INT_MIN, int hi = INT_MAX);

// "yes" or "no" exactly.
bool parse_yesno(const char *s, bool &v);

// "x", "y" or "z" -> 0, 1, 2; anything else (including null) -> -1.
int axis_of(const char *s);

}  // namespace mpm
