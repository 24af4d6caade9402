#include "laser_params.h"

#include <CLI/CLI.hpp>
#include <toml++/toml.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

namespace laser {

std::vector<std::string> material_presets() { return {"superalloy"}; }

namespace {

// A value as it came in: text from the command line or a TOML node.
struct Value {
  std::string text;                 // command line
  const toml::node* node = nullptr; // config file
};

enum class Kind { Real, Int, Choice, Flag, Text };

struct Param {
  std::string name;     // command-line name without --; TOML key with '_' for '-'
  std::string section;  // TOML section
  Kind kind;
  std::string unit;
  double lo = 0, hi = 0;
  bool lo_open = false;
  std::vector<std::string> choices;  // Choice
  std::string help;
  std::function<void(Config&, double)> set_num;
  std::function<void(Config&, const std::string&)> set_text;
  std::function<void(Config&, bool)> set_flag;
  std::function<std::string(const Config&)> get;
  bool cli_value = true;  // Flag: the value the command-line switch sets
  std::string toml_key() const {
    std::string k = name;
    for (auto& ch : k)
      if (ch == '-') ch = '_';
    return k;
  }
};

std::string range_text(const Param& p) {
  std::string s = (p.lo_open ? "(" : "[") + fmt(p.lo) + ", " + fmt(p.hi) + "]";
  if (!p.unit.empty() && p.unit != "-") s += " " + p.unit;
  return s;
}

std::string choices_text(const Param& p) {
  std::string s;
  for (const auto& c : p.choices) s += (s.empty() ? "" : ", ") + c;
  return s;
}

// Strict decimal number: no leading blanks or '+', no hex, the whole text.
std::optional<double> strict_real(const std::string& s) {
  double v = 0;
  const char* b = s.data();
  const char* e = b + s.size();
  if (s.empty() || s.size() > 64) return std::nullopt;
  const auto r = std::from_chars(b, e, v, std::chars_format::general);
  if (r.ec != std::errc() || r.ptr != e || !std::isfinite(v)) return std::nullopt;
  return v;
}
std::optional<long long> strict_int(const std::string& s) {
  long long v = 0;
  const char* b = s.data();
  const char* e = b + s.size();
  if (s.empty() || s.size() > 20) return std::nullopt;
  const auto r = std::from_chars(b, e, v, 10);
  if (r.ec != std::errc() || r.ptr != e) return std::nullopt;
  return v;
}

// Range check; returns the message (empty when fine). `given` is the text shown.
std::string check_range(const Param& p, double v, const std::string& given) {
  const bool lo_bad = p.lo_open ? !(v > p.lo) : !(v >= p.lo);
  if (lo_bad || !(v <= p.hi) || !std::isfinite(v))
    return "value " + given + (p.unit.empty() || p.unit == "-" ? "" : " " + p.unit) +
           " outside the valid range " + range_text(p);
  return "";
}

std::string expected_text(const Param& p) {
  switch (p.kind) {
    case Kind::Real: return "a decimal number in " + range_text(p);
    case Kind::Int: return "a decimal integer in " + range_text(p);
    case Kind::Choice: return "one of " + choices_text(p);
    case Kind::Flag: return "true or false";
    case Kind::Text: return "a string";
  }
  return "";
}

std::string quoted(const std::string& s) {
  std::string o = "'";
  for (char c : s) {
    if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", static_cast<unsigned char>(c));
      o += buf;
    } else {
      o += c;
    }
  }
  return o + "'";
}

std::string bad_value(const Param& p, const std::string& given) {
  return "expected " + expected_text(p) + ", got " + given;
}

// A command-line value of p applied to c; returns the error message or "".
std::string apply_text(Config& c, const Param& p, const std::string& s) {
  const auto bad = [&](const std::string& given) { return bad_value(p, given); };
  switch (p.kind) {
    case Kind::Real: {
      const auto x = strict_real(s);
      if (!x) return bad(quoted(s));
      const std::string e = check_range(p, *x, s);
      if (!e.empty()) return e;
      p.set_num(c, *x);
      return "";
    }
    case Kind::Int: {
      const auto x = strict_int(s);
      if (!x) return bad(quoted(s));
      const std::string e = check_range(p, double(*x), s);
      if (!e.empty()) return e;
      p.set_num(c, double(*x));
      return "";
    }
    case Kind::Choice:
      for (const auto& ch : p.choices)
        if (ch == s) { p.set_text(c, s); return ""; }
      return bad(quoted(s));
    case Kind::Flag: p.set_flag(c, p.cli_value); return "";
    case Kind::Text:
      if (s.empty()) return "expected a non-empty string";
      p.set_text(c, s);
      return "";
  }
  return "";
}

// A TOML value of p applied to c; returns the error message or "".
std::string apply_node(Config& c, const Param& p, const toml::node& n) {
  const auto bad = [&](const std::string& given) { return bad_value(p, given); };
  std::ostringstream shown;
  n.visit([&](auto&& x) {
    if constexpr (toml::is_string<decltype(x)>) shown << quoted(x.get());
    else if constexpr (toml::is_number<decltype(x)> || toml::is_boolean<decltype(x)>) shown << x;
    else shown << "a TOML " << x.type();
  });
  switch (p.kind) {
    case Kind::Real: {
      double x;
      if (auto f = n.as_floating_point()) x = f->get();
      else if (auto i = n.as_integer()) x = double(i->get());
      else return bad(shown.str());
      const std::string e = check_range(p, x, shown.str());
      if (!e.empty()) return e;
      p.set_num(c, x);
      return "";
    }
    case Kind::Int: {
      auto i = n.as_integer();
      if (!i) return bad(shown.str());
      const std::string e = check_range(p, double(i->get()), shown.str());
      if (!e.empty()) return e;
      p.set_num(c, double(i->get()));
      return "";
    }
    case Kind::Choice: {
      auto s = n.as_string();
      if (!s) return bad(shown.str());
      for (const auto& ch : p.choices)
        if (ch == s->get()) { p.set_text(c, s->get()); return ""; }
      return bad(quoted(s->get()));
    }
    case Kind::Flag: {
      auto b = n.as_boolean();
      if (!b) return bad(shown.str());
      p.set_flag(c, b->get());
      return "";
    }
    case Kind::Text: {
      auto s = n.as_string();
      if (!s || s->get().empty()) return bad(shown.str());
      p.set_text(c, s->get());
      return "";
    }
  }
  return "";
}

// Checks a value for p and applies it to c; returns the error message or "".
std::string apply(Config& c, const Param& p, const Value& v) {
  return v.node == nullptr ? apply_text(c, p, v.text) : apply_node(c, p, *v.node);
}

Param real(const std::string& n, const std::string& sec, const std::string& unit, double lo, double hi,
           bool lo_open, const std::string& help, double Config::*field) {
  Param p{n, sec, Kind::Real, unit, lo, hi, lo_open, {}, help, nullptr, nullptr, nullptr, nullptr};
  p.set_num = [field](Config& c, double v) { c.*field = v; };
  p.get = [field](const Config& c) { return fmt(c.*field); };
  return p;
}
Param matreal(const std::string& n, const std::string& unit, double lo, double hi, const std::string& help,
              double Material::*field) {
  Param p{n, "material", Kind::Real, unit, lo, hi, true, {}, help, nullptr, nullptr, nullptr, nullptr};
  p.set_num = [field](Config& c, double v) { c.mat.*field = v; };
  p.get = [field](const Config& c) { return fmt(c.mat.*field); };
  return p;
}
// A switch: on the command line --NAME turns the feature off (value false);
// in the config file the key is the feature (e.g. curvature = false).
Param flag(const std::string& cli, const std::string& key, const std::string& sec, const std::string& help,
           bool Config::*field, bool cli_value) {
  Param p{cli, sec, Kind::Flag, "", 0, 0, false, {}, help, nullptr, nullptr, nullptr, nullptr};
  p.set_flag = [field](Config& c, bool v) { c.*field = v; };
  p.get = [field](const Config& c) { return std::string(c.*field ? "true" : "false"); };
  p.cli_value = cli_value;
  (void)key;
  return p;
}
Param choice(const std::string& n, const std::string& sec, std::vector<std::string> ch, const std::string& help,
             std::function<void(Config&, const std::string&)> set,
             std::function<std::string(const Config&)> get) {
  Param p{n, sec, Kind::Choice, "", 0, 0, false, std::move(ch), help, nullptr, std::move(set), nullptr,
          std::move(get)};
  return p;
}

// Options of the beam, in the order of --help.
void add_laser_params(std::vector<Param>& t) {
  // [laser]
  t.push_back(real("intensity", "laser", "W/m2", 1e6, 1e13, false,
                   "laser intensity at the beam centre, I0 in (3-21)", &Config::I0));
  t.push_back(real("absorptivity", "laser", "-", 0, 1, true,
                   "absorbed fraction of the beam (the text absorbs all: 1); the model runs with absorptivity x I0",
                   &Config::absorptivity));
  t.push_back(choice(
      "recoil", "model", {"full", "knight"},
      "recoil pressure driving the melt flow: full = p_sat(T_s) as in the text, knight = 0.54 p_sat "
      "(Anisimov/Knight, evaporation through a Knudsen layer)",
      [](Config& c, const std::string& v) { c.recoil = v == "knight" ? 0.54 : 1.0; },
      [](const Config& c) { return std::string(c.recoil == 1.0 ? "full" : "knight"); }));
  t.push_back(real("pulse", "laser", "s", 1e-9, 1e-2, false, "pulse length t_p", &Config::tp));
  t.push_back(real("radius", "laser", "m", 1e-6, 1e-2, false, "beam radius R in (3-21)", &Config::R));
}

// Options of [model]: the melt flow and the fronts, in the order of --help.
void add_model_params(std::vector<Param>& t) {
  // [model]
  t.push_back(choice(
      "model", "model", {"conduction", "rising", "risingfall", "boundary"}, "melt flow model",
      [](Config& c, const std::string& v) {
        c.model = v == "conduction" ? FlowModel::Conduction
                  : v == "rising"   ? FlowModel::Rising
                  : v == "risingfall" ? FlowModel::RisingFall : FlowModel::Boundary;
      },
      [](const Config& c) { return std::string(to_string(c.model)); }));
  t.push_back(real("m", "model", "-", 1, 100, true, "index of the rising profile u = A zeta xi^(1/m) (4-17)",
                   &Config::m));
  t.push_back(real("xi-p", "model", "-", 0, 10, true,
                   "peak position of the rising-fall profile u = A xi zeta exp(-xi/xi_p) (4-22)", &Config::xi_p));
  t.push_back(choice(
      "solid", "model", {"exact", "shifted", "stefan"},
      "solid conduction after onset: exact = (3-29)-(3-34), shifted = (3-35)/(3-36), stefan = (3-30) alone",
      [](Config& c, const std::string& v) {
        c.solid = v == "exact" ? SolidModel::Exact : v == "shifted" ? SolidModel::Shifted : SolidModel::Stefan;
      },
      [](const Config& c) { return std::string(to_string(c.solid)); }));
  t.push_back(choice(
      "melt-energy", "model", {"advected", "text"},
      "melt layer energy: advected = quasi-steady advection-diffusion (exponential profile, the vaporized mass "
      "pays c_pl (T_s - T_m)), text = the dissertation's linear conduction layer",
      [](Config& c, const std::string& v) { c.melt_energy = v == "text" ? MeltEnergy::Text : MeltEnergy::Advected; },
      [](const Config& c) { return std::string(to_string(c.melt_energy)); }));
  t.push_back(choice(
      "melt-flow", "model", {"conservative", "text"},
      "surface-normal melt velocity in (4-13): conservative = divergence of the layer's volume flux "
      "(melt is conserved; includes -u(g) dg/dxi), text = v(xi, g) of (4-22) as printed",
      [](Config& c, const std::string& v) { c.melt_flow = v == "text" ? MeltFlow::Text : MeltFlow::Conservative; },
      [](const Config& c) { return std::string(to_string(c.melt_flow)); }));
  t.push_back(choice(
      "melt-heat", "model", {"auto", "ode", "flux"},
      "heat the melt flow carries sideways, b2 of (4-25): ode = the text's integral balance (4-27) marched "
      "along xi, flux = finite-volume face fluxes of the conservative flow (volume flux x upwind 2 theta_sat/3, "
      "solved with the surface temperature; what leaves one column enters the next; needs --melt-flow "
      "conservative), auto = flux with --melt-flow conservative, ode with --melt-flow text",
      [](Config& c, const std::string& v) {
        c.melt_heat = v == "flux" ? MeltHeat::Flux : v == "ode" ? MeltHeat::Ode : MeltHeat::Auto;
      },
      [](const Config& c) {
        return std::string(c.melt_heat == MeltHeat::Flux ? "flux" : c.melt_heat == MeltHeat::Ode ? "ode" : "auto");
      }));
  t.push_back(choice(
      "melt-content", "model", {"auto", "transient", "steady"},
      "heat content of the melt layer with the face heat fluxes: transient = the layer's energy balance keeps "
      "the transient term of (3-3b) (inflowing heat first raises the layer's content), steady = the text's "
      "quasi-steady layer (heat brought in is conducted out in the same step); auto = transient with --melt-heat "
      "flux and --melt-update implicit or trapezoidal, steady otherwise (transient needs --melt-heat flux)",
      [](Config& c, const std::string& v) {
        c.melt_content = v == "transient" ? MeltContent::Transient : v == "steady" ? MeltContent::Steady : MeltContent::Auto;
      },
      [](const Config& c) {
        const MeltContent m = c.melt_content;
        return std::string(m == MeltContent::Transient ? "transient" : m == MeltContent::Steady ? "steady" : "auto");
      }));
  t.push_back(real("shift", "model", "tau_m", 0, 10, true,
                   "backward shift of the Stefan solution for --solid shifted (3-36: 3 tau_0 = 3/(4 pi))",
                   &Config::shift));
}

// Options of [model] for the fronts and the melt thickness update.
void add_front_params(std::vector<Param>& t) {
  t.push_back(flag("no-curvature", "curvature", "model", "switch off the curvature factor (3-37)",
                   &Config::curvature, false));
  t.push_back(choice(
      "curvature-factor", "model", {"conduction", "text"},
      "curvature factor C_c of (3-37): conduction = its branches as conduction into the curved solid sets them "
      "(C_c >= 1 where the front bulges into the solid; damps node-scale modes of the front), text = (3-37) as "
      "printed (C_c <= 1 there)",
      [](Config& c, const std::string& v) { c.curvature_form = v == "text" ? CurvatureForm::Text : CurvatureForm::Conduction; },
      [](const Config& c) { return std::string(to_string(c.curvature_form)); }));
  t.push_back(flag("no-moving-origin", "moving_origin", "model",
                   "switch off the moving-origin term in (3-39)/(3-40)", &Config::moving_origin, false));
  t.push_back(choice(
      "melt-update", "model", {"explicit", "implicit", "trapezoidal"},
      "melt thickness update: explicit = (4-14) as in the text, implicit = backward Euler in g, "
      "trapezoidal = the trapezoidal rule in g, S1 and S2 (second order in the layer's own rates)",
      [](Config& c, const std::string& v) {
        c.implicit_melt = v != "explicit";
        c.trapezoidal_melt = v == "trapezoidal";
      },
      [](const Config& c) { return std::string(c.melt_update_name()); }));
}

// Options of [numerics] and [output], in the order of --help.
void add_numerics_params(std::vector<Param>& t) {
  // [numerics]
  t.push_back(real("dxi", "numerics", "-", 1e-3, 0.5, false, "radial grid spacing d(xi) = dr/R", &Config::dxi));
  t.push_back(real("xi-max", "numerics", "-", 0, 10, false,
                   "outer end of the grid (0: just beyond the last node that melts)", &Config::xi_max));
  t.push_back(real("dt", "numerics", "s", 1e-13, 1e-3, false,
                   "time step (default: chosen from pulse, radius and intensity and checked by step doubling)",
                   &Config::dt));
  t.push_back(real("dtau", "numerics", "-", 1e-12, 10, false, "time step in tau = t alpha_l / R^2 (overrides --dt)",
                   &Config::dtau));
  t.push_back(real("tol", "numerics", "-", 1e-6, 0.5, false,
                   "relative depth/volume error allowed by the step-doubling estimate", &Config::tol));
  t.push_back(real("heat-courant", "numerics", "-", 0, 10, false,
                   "heat Courant number C = dtau sum|c_k| g / a of the face heat fluxes (--melt-heat flux) kept in "
                   "each step by splitting it into the fewest equal sub-steps with C <= this (at most 1000); 0: "
                   "no splitting (beyond C = 1 the b2 limit of (4-25) acts)", &Config::heat_courant));
  // [output]
  {
    Param p{"frames", "output", Kind::Int, "-", 2, 1e5, false, {}, "number of profile frames in profiles.h5 "
            "(more than the run's steps + 1 are clipped with a note)", nullptr, nullptr, nullptr, nullptr};
    p.set_num = [](Config& c, double v) { c.frames = static_cast<int>(v); };
    p.get = [](const Config& c) { return std::to_string(c.frames); };
    t.push_back(p);
  }
  {
    Param p{"out", "output", Kind::Text, "", 0, 0, false, {}, "output directory (must be empty or new)",
            nullptr, nullptr, nullptr, nullptr};
    p.set_text = [](Config& c, const std::string& v) { c.out = v; };
    p.get = [](const Config& c) { return c.out; };
    t.push_back(p);
  }
  t.push_back(flag("overwrite", "overwrite", "output",
                   "remove what an earlier run wrote into --out before running", &Config::overwrite, true));
  t.push_back(flag("quiet", "quiet", "output", "no progress output on stderr", &Config::quiet, true));
}

// Options of [material], in the order of --help.
void add_material_params(std::vector<Param>& t) {
  // [material]
  t.push_back(choice(
      "material", "material", material_presets(), "material preset (Table 5.1); the properties below override it",
      [](Config& c, const std::string& v) { c.material = v; },
      [](const Config& c) { return c.material; }));
  t.push_back(matreal("hls", "J/kg", 1e2, 1e8, "latent heat of melting h_ls", &Material::hls));
  t.push_back(matreal("hlv", "J/kg", 1e4, 1e9, "latent heat of vaporization h_lv", &Material::hlv));
  t.push_back(matreal("rho", "kg/m3", 1e2, 1e5, "density (solid and melt)", &Material::rho));
  t.push_back(matreal("molar-mass", "kg/mol", 1e-3, 1, "vapour molar mass M", &Material::M));
  t.push_back(matreal("T-initial", "K", 0, 1e4, "initial temperature T_i", &Material::Ti));
  t.push_back(matreal("T-melt", "K", 0, 1e4, "melting temperature T_m", &Material::Tm));
  t.push_back(matreal("T-sat0", "K", 0, 2e4, "saturation temperature at p0, T_sat0", &Material::Tsat0));
  t.push_back(matreal("p0", "Pa", 1, 1e9, "reference pressure of T_sat0", &Material::p0));
  t.push_back(matreal("k-liquid", "W/(m K)", 1e-2, 1e4, "thermal conductivity of the melt k_l", &Material::kl));
  t.push_back(matreal("k-solid", "W/(m K)", 1e-2, 1e4, "thermal conductivity of the solid k_s", &Material::ks));
  t.push_back(matreal("cp-liquid", "J/(kg K)", 1, 1e5, "specific heat of the melt c_pl", &Material::cpl));
  t.push_back(matreal("cp-solid", "J/(kg K)", 1, 1e5, "specific heat of the solid c_ps", &Material::cps));
  t.push_back(matreal("T-critical", "K", 0, 1e5,
                      "critical temperature T_c: a warning above 0.8 T_c, status diverged above T_c",
                      &Material::Tc));
  t.push_back(matreal("pr", "-", 1e-6, 1e7, "Prandtl number of the melt nu/alpha_l", &Material::Pr));
}

const std::vector<Param>& params() {
  static const std::vector<Param> table = [] {
    std::vector<Param> t;
    add_laser_params(t);
    add_model_params(t);
    add_front_params(t);
    add_numerics_params(t);
    add_material_params(t);
    return t;
  }();
  return table;
}

// TOML key of a parameter: the option name with '_' for '-', and the feature
// name without "no-" for the switches.
std::string key_of(const Param& p) {
  std::string k = p.toml_key();
  if (p.kind == Kind::Flag && k.rfind("no_", 0) == 0) k = k.substr(3);
  return k;
}

struct Setting {
  const Param* p;
  Value v;
  std::string where;  // "--name" or "file:line: key"
};

constexpr std::uintmax_t kMaxConfigBytes = 1 << 20;

std::vector<Setting> load_config(const std::string& path, toml::table& keep) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw UsageError("--config: file '" + path + "' does not exist");
  if (!fs::is_regular_file(st))
    throw UsageError("--config: '" + path + "' is not a regular file (a TOML file of at most 1 MiB is expected)");
  const auto size = fs::file_size(path, ec);
  if (ec || size > kMaxConfigBytes)
    throw UsageError("--config: '" + path + "' is larger than 1 MiB; a TOML file of at most 1 MiB is expected");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError("--config: cannot open file '" + path + "'");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto nul = text.find('\0');
  if (nul != std::string::npos) {
    const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + nul, '\n'));
    throw UsageError("--config: " + path + ":" + std::to_string(line) + ": NUL byte in the file (not valid TOML)");
  }
  try {
    keep = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw UsageError("--config: " + path + ":" + std::to_string(e.source().begin.line) + ": " +
                     std::string(e.description()));
  }
  std::vector<Setting> out;
  std::map<std::string, bool> sections;
  for (const auto& p : params()) sections[p.section] = true;
  for (auto&& [k, node] : keep) {
    const std::string sec(k.str());
    const std::string at = path + ":" + std::to_string(node.source().begin.line) + ": ";
    if (!node.is_table()) {
      const Param* p = nullptr;
      for (const auto& q : params())
        if (key_of(q) == sec) p = &q;
      throw UsageError("--config: " + at + "key '" + sec + "' outside a section" +
                       (p ? "; it belongs in [" + p->section + "]" : "") +
                       " (sections: [laser], [model], [numerics], [output], [material])");
    }
    if (!sections.count(sec))
      throw UsageError("--config: " + at + "unknown section [" + sec +
                       "] (sections: [laser], [model], [numerics], [output], [material])");
    for (auto&& [kk, vn] : *node.as_table()) {
      const std::string key(kk.str());
      const std::string where = path + ":" + std::to_string(vn.source().begin.line) + ": [" + sec + "] " + key;
      const Param* p = nullptr;
      for (const auto& q : params())
        if (key_of(q) == key) p = &q;
      if (!p) throw UsageError("--config: " + where + ": unknown key");
      if (p->section != sec)
        throw UsageError("--config: " + where + ": key belongs in [" + p->section + "], not [" + sec + "]");
      out.push_back({p, Value{"", &vn}, where});
    }
  }
  return out;
}

void apply_all(Config& c, const std::vector<Setting>& s) {
  for (const auto& x : s) {
    const std::string e = apply(c, *x.p, x.v);
    if (!e.empty()) throw UsageError(x.where + ": " + e);
  }
}

}  // namespace

std::vector<std::pair<std::string, std::string>> config_keys() {
  std::vector<std::pair<std::string, std::string>> k;
  for (const auto& p : params()) k.push_back({p.section, key_of(p)});
  return k;
}

void read_config_file(Config& c, const std::string& path) {
  toml::table t;
  const auto s = load_config(path, t);
  for (const auto& x : s)
    if (x.p->name == "material") apply_all(c, {x});
  for (const auto& x : s)
    if (x.p->name != "material") apply_all(c, {x});
}

Invocation parse_command_line(int argc, const char* const* argv) {
  Invocation inv;
  Config defaults;
  CLI::App app{"laser_drill: single-pulse laser drilling model of Yang (2016), Part I (chapters 3-5).\n"
               "Defaults: the Table 5.1 super alloy at 7.5e10 W/m2, 700 us, rising-fall xi_p = 1.",
               "laser_drill"};
  app.set_version_flag("--version", std::string("laser_drill ") + kVersion);
  app.get_formatter()->column_width(30);
  std::string config_file;
  app.add_option("--config", config_file,
                 "TOML file with sections [laser] [model] [numerics] [output] [material]; keys are the option "
                 "names with '_' for '-' (curvature/moving_origin = false for the --no- switches)")
      ->type_name("FILE")
      ->multi_option_policy(CLI::MultiOptionPolicy::Throw);
  app.add_flag("--conduction-table", inv.dump_conduction,
               "write the corrected-conduction table of Figs 3.7/3.8 to --out and stop");
  std::map<std::string, std::string> raw;
  std::map<std::string, CLI::Option*> opts;
  for (const auto& p : params()) {
    std::string help = p.help;
    if (p.kind == Kind::Real || p.kind == Kind::Int) help += ", range " + range_text(p);
    if (p.kind == Kind::Choice) help += "; one of " + choices_text(p);
    if (p.kind != Kind::Flag) help += ", default " + p.get(defaults);
    help += " (config: [" + p.section + "] " + key_of(p) + ")";
    if (p.kind == Kind::Flag) {
      opts[p.name] = app.add_flag("--" + p.name)->description(help)->multi_option_policy(CLI::MultiOptionPolicy::Throw);
      continue;
    }
    // Values are taken as text and converted here (strict decimal, unit and
    // range in the message): CLI11's own conversion accepts hex and blanks.
    CLI::Option* o = app.add_option("--" + p.name, raw[p.name], help);
    const Param* pp = &p;
    o->check(CLI::Validator(
        [pp](std::string& s) {
          Config scratch;
          return apply(scratch, *pp, Value{s, nullptr});
        },
        ""));
    o->type_name(p.kind == Kind::Real ? "X" : p.kind == Kind::Int ? "N" : p.kind == Kind::Choice ? "NAME" : "DIR");
    o->multi_option_policy(CLI::MultiOptionPolicy::Throw);
    opts[p.name] = o;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {  // --help, --version
      app.exit(e, std::cout, std::cerr);
      inv.exit_now = true;
      return inv;
    }
    throw UsageError(e.what());
  }
  // defaults < preset < config file < command line
  Config& c = inv.cfg;
  std::vector<Setting> file;
  toml::table keep;
  if (!config_file.empty()) file = load_config(config_file, keep);
  std::vector<Setting> cli;
  for (const auto& p : params())
    if (opts[p.name]->count() > 0) cli.push_back({&p, Value{raw[p.name], nullptr}, "--" + p.name});
  const auto is_preset = [](const Setting& s) { return s.p->name == "material"; };
  for (const auto* set : {&file, &cli})
    for (const auto& s : *set)
      if (is_preset(s)) apply_all(c, {s});
  c.mat = Material{};  // the only preset (Table 5.1)
  for (const auto* set : {&file, &cli})
    for (const auto& s : *set)
      if (!is_preset(s)) apply_all(c, {s});
  c.config_file = config_file;
  return inv;
}

}  // namespace laser
