#include "laser_params.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <algorithm>
#include <map>
#include <sstream>

namespace laser {

const char* to_string(FlowModel m) {
  switch (m) {
    case FlowModel::Conduction: return "conduction";
    case FlowModel::Rising: return "rising";
    case FlowModel::RisingFall: return "risingfall";
    case FlowModel::Boundary: return "boundary";
  }
  return "?";
}
const char* to_string(SolidModel m) {
  switch (m) {
    case SolidModel::Exact: return "exact";
    case SolidModel::Shifted: return "shifted";
    case SolidModel::Stefan: return "stefan";
  }
  return "?";
}

std::vector<std::string> material_presets() { return {"superalloy"}; }

namespace {

enum class Kind { Real, Int, Text, Flag, Choice, Special };

struct Option {
  std::string name;    // without the leading --
  std::string unit;
  std::string help;
  Kind kind;
  double lo = 0, hi = 0;  // Real/Int: valid range
  bool lo_open = true, hi_open = true;
  std::string choices;    // Choice: '|' separated
  std::function<void(Config&, const std::string&)> set;
  std::function<std::string(const Config&)> get;
};

const double kInf = HUGE_VAL;

std::string fmt(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

std::string range_text(const Option& o) {
  std::string s = o.lo_open ? "(" : "[";
  s += fmt(o.lo) + ", " + (o.hi == kInf ? std::string("inf") : fmt(o.hi)) + (o.hi_open ? ")" : "]");
  return s;
}

Option real(const std::string& n, const std::string& unit, double lo, double hi, bool lo_open,
            bool hi_open, const std::string& help, double Config::*field) {
  Option o{n, unit, help, Kind::Real, lo, hi, lo_open, hi_open, "", nullptr, nullptr};
  o.set = [field](Config& c, const std::string& v) { c.*field = std::strtod(v.c_str(), nullptr); };
  o.get = [field](const Config& c) { return fmt(c.*field); };
  return o;
}
Option matreal(const std::string& n, const std::string& unit, const std::string& help,
               double Material::*field) {
  Option o{n, unit, help, Kind::Real, 0.0, kInf, true, true, "", nullptr, nullptr};
  o.set = [field](Config& c, const std::string& v) {
    c.mat.*field = std::strtod(v.c_str(), nullptr);
  };
  o.get = [field](const Config& c) { return fmt(c.mat.*field); };
  return o;
}
Option flag(const std::string& n, const std::string& help, bool Config::*field, bool value) {
  Option o{n, "", help, Kind::Flag, 0, 0, true, true, "", nullptr, nullptr};
  o.set = [field, value](Config& c, const std::string& v) {
    c.*field = (v == "false" || v == "0" || v == "no") ? !value : value;
  };
  o.get = [field, value](const Config& c) { return c.*field == value ? "on" : "off"; };
  return o;
}

const std::vector<Option>& options() {
  static const std::vector<Option> table = [] {
    std::vector<Option> t;
    t.push_back(real("intensity", "W/m2", 0, kInf, true, true,
                     "laser intensity at the beam centre, I0 in (3-21)", &Config::I0));
    t.push_back(real("pulse", "s", 0, kInf, true, true, "pulse length t_p", &Config::tp));
    t.push_back(real("radius", "m", 0, kInf, true, true, "beam radius R in (3-21)", &Config::R));
    {
      Option o{"model", "", "melt flow model", Kind::Choice, 0, 0, true, true,
               "conduction|rising|risingfall|boundary", nullptr, nullptr};
      o.set = [](Config& c, const std::string& v) {
        if (v == "conduction") c.model = FlowModel::Conduction;
        else if (v == "rising") c.model = FlowModel::Rising;
        else if (v == "risingfall") c.model = FlowModel::RisingFall;
        else c.model = FlowModel::Boundary;
      };
      o.get = [](const Config& c) { return std::string(to_string(c.model)); };
      t.push_back(o);
    }
    t.push_back(real("m", "-", 1, kInf, true, true,
                     "index of the rising profile u = A zeta xi^(1/m) (4-17)", &Config::m));
    t.push_back(real("xi-p", "-", 0, kInf, true, true,
                     "peak position of the rising-fall profile u = A xi zeta exp(-xi/xi_p) (4-22)",
                     &Config::xi_p));
    {
      Option o{"solid", "", "solid conduction after onset: exact = (3-29)-(3-34), shifted = (3-35)/(3-36), stefan = (3-30) alone",
               Kind::Choice, 0, 0, true, true, "exact|shifted|stefan", nullptr, nullptr};
      o.set = [](Config& c, const std::string& v) {
        c.solid = v == "exact" ? SolidModel::Exact
                  : v == "shifted" ? SolidModel::Shifted : SolidModel::Stefan;
      };
      o.get = [](const Config& c) { return std::string(to_string(c.solid)); };
      t.push_back(o);
    }
    t.push_back(real("shift", "tau_m", 0, kInf, true, true,
                     "backward shift of the Stefan solution for --solid shifted (3-36: 3 tau_0 = 3/(4 pi))",
                     &Config::shift));
    t.push_back(flag("no-curvature", "switch off the curvature factor (3-37)", &Config::curvature, false));
    t.push_back(flag("no-moving-origin", "switch off the moving-origin term in (3-39)/(3-40)",
                     &Config::moving_origin, false));
    {
      Option o{"melt-update", "", "melt thickness update: explicit = (4-14) as in the text, implicit = backward Euler in g",
               Kind::Choice, 0, 0, true, true, "explicit|implicit", nullptr, nullptr};
      o.set = [](Config& c, const std::string& v) { c.implicit_melt = v == "implicit"; };
      o.get = [](const Config& c) { return std::string(c.implicit_melt ? "implicit" : "explicit"); };
      t.push_back(o);
    }
    t.push_back(real("dxi", "-", 0, 0.5, true, false, "radial grid spacing d(xi) = dr/R", &Config::dxi));
    t.push_back(real("xi-max", "-", 0, 10, false, false,
                     "outer end of the grid (0: just beyond the last node that melts)", &Config::xi_max));
    t.push_back(real("dt", "s", 0, kInf, true, true, "time step (dimensional; default 0 = 5e-7 * min(1, (7.5e10/I0)^2))", &Config::dt));
    t.push_back(real("dtau", "-", 0, kInf, true, true,
                     "time step in tau = t alpha_l / R^2 (overrides --dt)", &Config::dtau));
    {
      Option o{"frames", "-", "number of profile frames in profiles.h5", Kind::Int, 2, 1e6, false, false,
               "", nullptr, nullptr};
      o.set = [](Config& c, const std::string& v) { c.frames = std::atoi(v.c_str()); };
      o.get = [](const Config& c) { return std::to_string(c.frames); };
      t.push_back(o);
    }
    {
      Option o{"out", "", "output directory", Kind::Text, 0, 0, true, true, "", nullptr, nullptr};
      o.set = [](Config& c, const std::string& v) { c.out = v; };
      o.get = [](const Config& c) { return c.out; };
      t.push_back(o);
    }
    t.push_back(flag("quiet", "no progress output on stderr", &Config::quiet, true));
    {
      Option o{"material", "", "material preset (Table 5.1)", Kind::Choice, 0, 0, true, true,
               "superalloy", nullptr, nullptr};
      o.set = [](Config& c, const std::string& v) { c.material = v; c.mat = Material{}; };
      o.get = [](const Config& c) { return c.material; };
      t.push_back(o);
    }
    t.push_back(matreal("hls", "J/kg", "latent heat of melting h_ls", &Material::hls));
    t.push_back(matreal("hlv", "J/kg", "latent heat of vaporization h_lv", &Material::hlv));
    t.push_back(matreal("rho", "kg/m3", "density (solid and melt)", &Material::rho));
    t.push_back(matreal("molar-mass", "kg/mol", "vapour molar mass M", &Material::M));
    t.push_back(matreal("T-initial", "K", "initial temperature T_i", &Material::Ti));
    t.push_back(matreal("T-melt", "K", "melting temperature T_m", &Material::Tm));
    t.push_back(matreal("T-sat0", "K", "saturation temperature at p0, T_sat0", &Material::Tsat0));
    t.push_back(matreal("p0", "Pa", "reference pressure of T_sat0", &Material::p0));
    t.push_back(matreal("k-liquid", "W/(m K)", "thermal conductivity of the melt k_l", &Material::kl));
    t.push_back(matreal("k-solid", "W/(m K)", "thermal conductivity of the solid k_s", &Material::ks));
    t.push_back(matreal("cp-liquid", "J/(kg K)", "specific heat of the melt c_pl", &Material::cpl));
    t.push_back(matreal("cp-solid", "J/(kg K)", "specific heat of the solid c_ps", &Material::cps));
    t.push_back(matreal("pr", "-", "Prandtl number of the melt nu/alpha_l", &Material::Pr));
    return t;
  }();
  return table;
}

const Option* find_option(const std::string& name) {
  for (const auto& o : options())
    if (o.name == name) return &o;
  return nullptr;
}

// Checks the text of a value against the option's type and range, then sets it.
void apply(Config& c, const Option& o, const std::string& value, const std::string& where) {
  const std::string opt = "--" + o.name;
  if (o.kind == Kind::Real || o.kind == Kind::Int) {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(value.c_str(), &end);
    if (value.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
      throw UsageError(where + opt + ": expected a number in " + range_text(o) +
                       (o.unit.empty() ? "" : " " + o.unit) + ", got '" + value + "'");
    if (o.kind == Kind::Int && v != std::floor(v))
      throw UsageError(where + opt + ": expected an integer, got '" + value + "'");
    const bool lo_bad = o.lo_open ? !(v > o.lo) : !(v >= o.lo);
    const bool hi_bad = o.hi_open ? !(v < o.hi) : !(v <= o.hi);
    if (lo_bad || hi_bad)
      throw UsageError(where + opt + ": value " + value + " outside the valid range " +
                       range_text(o) + (o.unit.empty() ? "" : " " + o.unit));
  } else if (o.kind == Kind::Choice) {
    std::stringstream ss(o.choices);
    std::string ch;
    bool ok = false;
    while (std::getline(ss, ch, '|')) ok = ok || ch == value;
    if (!ok)
      throw UsageError(where + opt + ": unknown value '" + value + "', expected one of " +
                       o.choices);
  } else if (o.kind == Kind::Flag) {
    if (!(value == "true" || value == "false" || value == "1" || value == "0" ||
          value == "yes" || value == "no"))
      throw UsageError(where + opt + ": expected true or false, got '" + value + "'");
  }
  o.set(c, value);
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

void read_config_file(Config& c, const std::string& path) {
  std::ifstream in(path);
  if (!in) throw UsageError("--config: cannot open file '" + path + "'");
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line = line.substr(0, hash);
    line = trim(line);
    if (line.empty() || line[0] == '[') continue;  // TOML section headers are ignored
    const auto eq = line.find('=');
    const std::string where = path + ":" + std::to_string(lineno) + ": ";
    if (eq == std::string::npos) throw UsageError(where + "expected 'key = value', got '" + line + "'");
    std::string key = trim(line.substr(0, eq)), value = trim(line.substr(eq + 1));
    for (auto& ch : key)
      if (ch == '_') ch = '-';
    if (value.size() >= 2 && value.front() == '"' && value.back() == '"')
      value = value.substr(1, value.size() - 2);
    const Option* o = find_option(key);
    if (!o || key == "config") throw UsageError(where + "unknown key '" + key + "'");
    apply(c, *o, value, where);
  }
}

}  // namespace

std::string usage_text() {
  std::ostringstream o;
  o << "Usage: laser_drill [options]\n"
       "Single-pulse laser drilling model of Yang (2016), Part I (chapters 3-5).\n"
       "Defaults: the Table 5.1 super alloy at 7.5e10 W/m2, 700 us, rising-fall xi_p = 1.\n\n"
       "Options (SI units; every option may also be given as 'name = value' in --config):\n"
       "  --help                  this text\n"
       "  --config FILE           read 'key = value' lines (keys are option names)\n"
       "  --conduction-table      write the corrected-conduction table of Figs 3.7/3.8 to --out\n";
  for (const auto& op : options()) {
    std::string head = "  --" + op.name;
    if (op.kind == Kind::Real || op.kind == Kind::Int) head += " X";
    if (op.kind == Kind::Choice) head += " " + op.choices;
    if (op.kind == Kind::Text) head += " DIR";
    o << head;
    if (head.size() < 26) o << std::string(26 - head.size(), ' '); else o << "\n" << std::string(26, ' ');
    o << op.help;
    if (!op.unit.empty() && op.unit != "-") o << " [" << op.unit << "]";
    if (op.kind == Kind::Real || op.kind == Kind::Int) o << ", range " << range_text(op);
    Config def;
    if (op.kind != Kind::Flag) o << ", default " << op.get(def);
    o << "\n";
  }
  o << "\nExit status: 0 on a finished run (see status in summary.json), 2 on bad input\n"
       "or an unstable time step, 1 on an internal error.\n";
  return o.str();
}

Config parse_command_line(int argc, const char* const* argv, bool& help, bool& dump_conduction) {
  Config c;
  help = false;
  dump_conduction = false;
  // First pass: preset and config file, so that the command line overrides them.
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--config" || a == "--material") {
      if (i + 1 >= argc) throw UsageError(a + ": missing value");
      if (a == "--config") c.config_file = argv[i + 1];
      else apply(c, *find_option("material"), argv[i + 1], "");
      ++i;
    }
  }
  if (!c.config_file.empty()) read_config_file(c, c.config_file);
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--help" || a == "-h") { help = true; continue; }
    if (a == "--conduction-table") { dump_conduction = true; continue; }
    if (a.rfind("--", 0) != 0) throw UsageError("unexpected argument '" + a + "' (options start with --)");
    std::string name = a.substr(2), value;
    bool inline_value = false;
    const auto eq = name.find('=');
    if (eq != std::string::npos) { value = name.substr(eq + 1); name = name.substr(0, eq); inline_value = true; }
    if (name == "config" || name == "material") { if (!inline_value) ++i; continue; }
    const Option* o = find_option(name);
    if (!o) throw UsageError("unknown option '--" + name + "' (see --help)");
    if (o->kind == Kind::Flag) {
      apply(c, *o, inline_value ? value : "true", "");
      continue;
    }
    if (!inline_value) {
      if (i + 1 >= argc || std::string(argv[i + 1]).rfind("--", 0) == 0)
        throw UsageError("--" + name + ": missing value");
      value = argv[++i];
    }
    apply(c, *o, value, "");
  }
  return c;
}

void validate(Config& c) {
  const Material& m = c.mat;
  if (!(m.Tm > m.Ti))
    throw UsageError("--T-initial: must be below --T-melt (" + fmt(m.Tm) + " K), got " + fmt(m.Ti) + " K");
  if (!(m.Tsat0 > m.Tm))
    throw UsageError("--T-melt: must be below --T-sat0 (" + fmt(m.Tsat0) + " K), got " + fmt(m.Tm) + " K");
  if (c.dtau > 0.0) c.dt = c.dtau * c.R * c.R / (m.kl / (m.rho * m.cpl));
  // Automatic step: converged to < 1e-4 in centre depth for Table 5.1 at
  // 7.5e10 W/m2; the explicit limit of (4-14) scales as the melt thickness
  // squared, i.e. as I0^-2.
  if (!(c.dt > 0.0)) {
    c.dt = 5e-7 * std::min(1.0, std::pow(7.5e10 / c.I0, 2));
    c.dt_auto = true;
  }
  if (!(c.dt < c.tp))
    throw UsageError("--dt/--dtau: the time step " + fmt(c.dt) + " s must be shorter than the pulse " +
                     fmt(c.tp) + " s");
  if (c.xi_max > 0.0 && c.xi_max < 2.0 * c.dxi)
    throw UsageError("--xi-max: must be 0 (automatic) or at least 2 --dxi, got " + fmt(c.xi_max));
  const double steps = c.tp / c.dt;
  if (steps > 2e8)
    throw UsageError("--dt/--dtau: " + fmt(steps) + " steps requested, at most 2e8 allowed");
}

}  // namespace laser
