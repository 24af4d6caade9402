// Strict argument parsers; see args.h for what each accepts.
#include "mpm/args.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace mpm {

namespace {

// The characters of a decimal number (strtod alone would also take spaces, hex, inf and nan).
bool decimal_chars(const char *s, const char *allowed) {
  if (!s || !*s) return false;
  for (const char *c = s; *c; ++c)
    if (!std::strchr(allowed, *c)) return false;
  return true;
}

}  // namespace

bool parse_double(const char *s, double &v) {
  if (!decimal_chars(s, "0123456789+-.eE")) return false;
  char *end = nullptr;
  errno = 0;
  const double x = std::strtod(s, &end);
  // ERANGE: overflow to +-HUGE_VAL or underflow to 0 or a subnormal number
  if (end == s || *end != '\0' || errno == ERANGE || !std::isfinite(x)) return false;
  v = x;
  return true;
}

bool parse_int64(const char *s, std::int64_t &v) {
  if (!decimal_chars(s, "0123456789+-")) return false;
  char *end = nullptr;
  errno = 0;
  const long long x = std::strtoll(s, &end, 10);
  if (end == s || *end != '\0' || errno == ERANGE) return false;
  v = static_cast<std::int64_t>(x);
  return true;
}

bool parse_int(const char *s, int &v, int lo, int hi) {
  std::int64_t x = 0;
  if (!parse_int64(s, x) || x < lo || x > hi) return false;
  v = static_cast<int>(x);
  return true;
}

bool parse_yesno(const char *s, bool &v) {
  if (!s) return false;
  if (std::strcmp(s, "yes") == 0) {
    v = true;
    return true;
  }
  if (std::strcmp(s, "no") == 0) {
    v = false;
    return true;
  }
  return false;
}

int axis_of(const char *s) {
  if (!s || !s[0] || s[1]) return -1;
  if (s[0] == 'x') return 0;
  if (s[0] == 'y') return 1;
  if (s[0] == 'z') return 2;
  return -1;
}

}  // namespace mpm
