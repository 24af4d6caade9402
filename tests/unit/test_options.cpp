// The keyword table of fix mpm/fluid (mpm/options.h): it parses, it is what fix_modify accepts, its
// errors name keyword, expectation and value, and docs/fix_mpm_fluid.md lists exactly its keywords.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "mpm/error.h"
#include "mpm/options.h"

namespace {

mpm::ParseEnv box_env() {
  mpm::ParseEnv env;
  for (int d = 0; d < 3; ++d) env.boxhi[d] = 2.0;
  env.ntypes = 2;
  env.group_exists = [](const char *g) { return std::string(g) == "grains"; };
  return env;
}

// parses "fix f all mpm/fluid <words>"
mpm::Options parse(const std::string &words) {
  std::vector<std::string> w = {"f", "all", "mpm/fluid"};
  std::istringstream is(words);
  for (std::string s; is >> s;) w.push_back(s);
  std::vector<char *> argv;
  for (auto &s : w) argv.push_back(&s[0]);
  return mpm::parse_options(static_cast<int>(argv.size()), argv.data(), box_env());
}

std::string error_of(const std::string &words) {
  try {
    parse(words);
  } catch (const mpm::Error &e) {
    return e.what();
  }
  return "";
}

const std::string kBase = "cell 0.5 density 1000 pressure eos bulk 2e6 fill col 2 2 2 type 1 ";

TEST(Options, DefaultsAndValues) {
  const mpm::Options o = parse(kBase + "viscosity 1e-3 cfl 0.3 transfer flip 0.95 update usl "
                                       "boundary zlo shear 1e-3 output 10 out points v p grid mass cfl 0.3");
  EXPECT_EQ(o.grid.ncell[0], 4);
  EXPECT_EQ(o.grid.pad, 1);
  EXPECT_DOUBLE_EQ(o.eos.K, 2e6);
  EXPECT_DOUBLE_EQ(o.viscosity, 1e-3);
  EXPECT_DOUBLE_EQ(o.cfl, 0.3);
  EXPECT_EQ(o.transfer, mpm::Transfer::Flip);
  EXPECT_DOUBLE_EQ(o.flip_alpha, 0.95);
  EXPECT_FALSE(o.musl);
  EXPECT_EQ(o.model, mpm::Model::Standard);
  EXPECT_EQ(o.grad_p, mpm::GradP::Weak);
  EXPECT_TRUE(o.reaction_points);
  EXPECT_EQ(o.drag_form, mpm::DragForm::Consistent);
  EXPECT_EQ(o.face[4].kind, mpm::BcKind::Shear);
  EXPECT_EQ(o.face[0].kind, mpm::BcKind::NoSlip);
  EXPECT_EQ(o.out_point_fields, (std::vector<std::string>{"v", "p"}));
  EXPECT_EQ(o.out_grid_fields, (std::vector<std::string>{"mass"}));  // 'cfl' ended the list
  EXPECT_DOUBLE_EQ(o.mass_threshold, 1e-5);
}

// model yang2016: the dissertation's coupling forms, all three, and only with its pressure model
TEST(Options, ModelPresetSetsTheTextsForms) {
  const mpm::Options o = parse(kBase + "viscosity 1e-3 model yang2016");
  EXPECT_EQ(o.model, mpm::Model::Yang2016);
  EXPECT_EQ(o.grad_p, mpm::GradP::Fit);
  EXPECT_FALSE(o.reaction_points);
  EXPECT_EQ(o.drag_form, mpm::DragForm::Literal);
  EXPECT_EQ(error_of(kBase + "model text"), "Fix mpm/fluid: keyword 'model' expects 'standard' or 'yang2016', got 'text'");
  EXPECT_NE(error_of("cell 0.5 density 1000 fill col 2 2 2 type 1 pressure projection model yang2016")
                .find("'model yang2016' is the dissertation's weakly compressible model and needs 'pressure eos'"),
            std::string::npos);
  EXPECT_NE(error_of(kBase + "drag stokes literal").find("the text's literal form belongs to 'model yang2016'"),
            std::string::npos);
  // the forms are the model's, not keywords of their own
  for (const char *retired : {"grad_p fit", "reaction direct", "antilock no", "wall_traction no", "theta_transport yes",
                              "dtheta_source no", "free_surface node"})
    EXPECT_NE(error_of(kBase + retired).find("unknown keyword"), std::string::npos) << retired;
}

TEST(Options, ErrorsNameKeywordExpectationAndValue) {
  EXPECT_EQ(error_of(kBase + "cfl 0"), "Fix mpm/fluid: keyword 'cfl' expects a CFL number in (0,1], got '0'");
  EXPECT_EQ(error_of(kBase + "bulk"), "Fix mpm/fluid: keyword 'bulk' expects a positive bulk modulus (pressure), got nothing");
  EXPECT_NE(error_of(kBase + "colour red").find("unknown keyword 'colour'"), std::string::npos);
  EXPECT_NE(error_of(kBase + "couple nosuch").find("keyword 'couple' expects an existing group-ID"), std::string::npos);
  EXPECT_NE(error_of(kBase + "couple grains").find("needs keyword 'viscosity' > 0"), std::string::npos);
  EXPECT_NE(error_of(kBase + "fill col 2 2 2 type 3").find("'fill type' expects an existing atom type"), std::string::npos);
  EXPECT_NE(error_of("cell 0.3 density 1000 pressure eos bulk 2e6").find("divides the grid extent"), std::string::npos);
  EXPECT_NE(error_of(kBase + "output 1 o points velocity").find("'output points' expects point fields"), std::string::npos);
  // 0 is inside the range (theta_smooth acts with couple only: InertKeywordsRefused)
  EXPECT_EQ(error_of(kBase + "viscosity 1e-3 couple grains theta_smooth 0"), "");
}

// every N or every auto: auto starts at N = 1 (the fluid's first step chooses N); anything else is
// refused with the range and 'auto' named
TEST(Options, EveryIntegerOrAuto) {
  const mpm::Options a = parse(kBase + "every auto");
  EXPECT_TRUE(a.every_auto);
  EXPECT_EQ(a.fluid_every, 1);
  const mpm::Options n = parse(kBase + "every 7");
  EXPECT_FALSE(n.every_auto);
  EXPECT_EQ(n.fluid_every, 7);
  const std::string expect = "Fix mpm/fluid: keyword 'every' expects an integer N >= 1 (the fluid advances every N-th "
                             "time step) or 'auto', got '";
  EXPECT_EQ(error_of(kBase + "every 0"), expect + "0'");
  EXPECT_EQ(error_of(kBase + "every Auto"), expect + "Auto'");
  EXPECT_EQ(error_of(kBase + "every 2.5"), expect + "2.5'");
}

// fill ... inside mesh-ID [outside mesh-ID ...]: values, and refusals that name the keyword, what it
// expects and the value (the meshes themselves are checked when the points are created)
TEST(Options, FillInsideOutsideMeshes) {
  const std::string fill = "cell 0.5 density 1000 fill col 2 2 2 type 1 ";
  const mpm::Options o = parse(fill + "inside drum outside bar1 outside bar2 viscosity 1e-3");
  EXPECT_EQ(o.fill_inside, "drum");
  EXPECT_EQ(o.fill_outside, (std::vector<std::string>{"bar1", "bar2"}));
  EXPECT_DOUBLE_EQ(o.viscosity, 1e-3);  // the next keyword ends the fill
  EXPECT_EQ(parse(fill + "outside rock").fill_inside, "");
  // a fill given again replaces the meshes too
  EXPECT_EQ(parse(fill + "inside drum fill col 2 2 2 type 1").fill_inside, "");
  EXPECT_EQ(error_of(fill + "inside"),
            "Fix mpm/fluid: keyword 'fill inside' expects the ID of a closed fix mesh/surface, got nothing");
  EXPECT_EQ(error_of(fill + "inside drum inside jar"),
            "Fix mpm/fluid: keyword 'fill inside' expects one container mesh ('inside' given once), got 'jar'");
  EXPECT_EQ(error_of(fill + "inside drum outside drum"),
            "Fix mpm/fluid: keyword 'fill outside' expects a mesh not named before in this fill, got 'drum'");
  EXPECT_EQ(error_of(fill + "outside bar outside bar"),
            "Fix mpm/fluid: keyword 'fill outside' expects a mesh not named before in this fill, got 'bar'");
}

// probe, probe_window and mesh_wall's reference_point: values, and refusals that name the keyword,
// what it expects and the value given
TEST(Options, ProbesAndReferencePoint) {
  const mpm::Options o = parse(kBase + "probe point 1 1 0.5 probe box 0 2 0 2 0.25 0.75 probe_window 0.1");
  ASSERT_EQ(o.probes.size(), 2u);
  EXPECT_FALSE(o.probes[0].box);
  EXPECT_DOUBLE_EQ(o.probes[0].lo[2], 0.5);
  EXPECT_TRUE(o.probes[1].box);
  EXPECT_DOUBLE_EQ(o.probes[1].hi[2], 0.75);
  EXPECT_DOUBLE_EQ(o.probe_window, 0.1);
  EXPECT_TRUE(o.warnings.empty());  // probe repeats, one probe each
  EXPECT_EQ(error_of(kBase + "probe line 0 0 0"),
            "Fix mpm/fluid: keyword 'probe' expects 'point x y z' or 'box xlo xhi ylo yhi zlo zhi' (length), got 'line'");
  EXPECT_EQ(error_of(kBase + "probe point 1 1"),
            "Fix mpm/fluid: keyword 'probe point' expects three coordinates x y z (length), got nothing");
  EXPECT_EQ(error_of(kBase + "probe point 1 y 1"), "Fix mpm/fluid: keyword 'probe point' expects a coordinate (length), got 'y'");
  EXPECT_EQ(error_of(kBase + "probe box 0 1 0 1 0.6 0.4"),
            "Fix mpm/fluid: keyword 'probe box' expects hi > lo in every dimension, got '0.4'");
  EXPECT_EQ(error_of(kBase + "probe point 1 1 2.5"),
            "Fix mpm/fluid: keyword 'probe point' expects a point inside the grid along z [0, 2], got 2.5");
  EXPECT_EQ(error_of(kBase + "probe box -1 1 0 1 0 1"),
            "Fix mpm/fluid: keyword 'probe box' expects bounds inside the grid along x [0, 2], got -1");
  EXPECT_EQ(error_of(kBase + "probe point 1 1 1 probe_window -1"),
            "Fix mpm/fluid: keyword 'probe_window' expects a time window (time) >= 0 of the probes' average, got '-1'");
  EXPECT_NE(error_of(kBase + "probe_window 1").find("'probe_window' (the probes' averaging window) needs keyword 'probe'"),
            std::string::npos);
  // mesh_wall ... reference_point x y z (parsed for the adapter)
  std::vector<std::string> w = {"reference_point", "1", "2.5", "-3", "side"};
  std::vector<char *> a;
  for (auto &x : w) a.push_back(&x[0]);
  double ref[3] = {0, 0, 0};
  EXPECT_EQ(mpm::parse_reference_point(5, a.data(), 0, ref), 4);
  EXPECT_DOUBLE_EQ(ref[1], 2.5);
  EXPECT_DOUBLE_EQ(ref[2], -3.0);
  EXPECT_EQ(mpm::parse_reference_point(5, a.data(), 4, ref), 4);  // not the keyword: nothing read
  w = {"reference_point", "1", "x", "0"};
  a.clear();
  for (auto &x : w) a.push_back(&x[0]);
  try {
    mpm::parse_reference_point(4, a.data(), 0, ref);
    ADD_FAILURE() << "reference_point 1 x 0 accepted";
  } catch (const mpm::Error &e) {
    EXPECT_EQ(std::string(e.what()), "Fix mpm/fluid: keyword 'mesh_wall reference_point' expects three coordinates x y z "
                                     "(length) of the torque's reference point, got 'x'");
  }
  w = {"reference_point", "1", "2"};
  a.clear();
  for (auto &x : w) a.push_back(&x[0]);
  try {
    mpm::parse_reference_point(3, a.data(), 0, ref);
    ADD_FAILURE() << "reference_point with two values accepted";
  } catch (const mpm::Error &e) {
    EXPECT_NE(std::string(e.what()).find("got nothing"), std::string::npos) << e.what();
  }
}

TEST(Options, FixModifyTakesTheModifiableRowsOnly) {
  mpm::Options o = parse(kBase);
  std::vector<std::string> w = {"damping", "5"};
  std::vector<char *> a = {&w[0][0], &w[1][0]};
  EXPECT_EQ(mpm::modify_option(o, 2, a.data()), 2);
  EXPECT_DOUBLE_EQ(o.damping, 5.0);
  // a keyword fix_modify cannot change, or no keyword: an error naming the word and what it changes
  for (const char *word : {"viscosity", "tolerance", "colour"}) {
    w = {word, "1"};
    a = {&w[0][0], &w[1][0]};
    try {
      mpm::modify_option(o, 2, a.data());
      ADD_FAILURE() << word << " accepted";
    } catch (const mpm::Error &e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(std::string("'") + word + "'"), std::string::npos) << m;
      EXPECT_NE(m.find("it changes"), std::string::npos) << m;
      EXPECT_NE(m.find("damping"), std::string::npos) << m;
    }
  }
  // a value another choice makes inert: refused, the option unchanged
  w = {"cell_check", "no"};
  a = {&w[0][0], &w[1][0]};
  EXPECT_THROW(mpm::modify_option(o, 2, a.data()), mpm::Error);
  EXPECT_TRUE(o.cell_check);
  w = {"subcycle", "maybe"};
  a = {&w[0][0], &w[1][0]};
  EXPECT_THROW(mpm::modify_option(o, 2, a.data()), mpm::Error);
  std::vector<std::string> b = {"boundary", "all", "partial", "0.5"};
  std::vector<char *> ab = {&b[0][0], &b[1][0], &b[2][0], &b[3][0]};
  EXPECT_EQ(mpm::modify_option(o, 4, ab.data()), 4);
  EXPECT_EQ(o.face[5].kind, mpm::BcKind::Partial);
}

// Ranges whose violation failed late (inside hypre, at step 1, as "reduce the timestep") or did
// nothing: refused by the parser, naming the keyword and the range.
TEST(Options, RangesRefusedAtTheCommand) {
  const std::string proj = "cell 0.5 density 1000 pressure projection fill col 2 2 2 type 1 ";
  EXPECT_NE(error_of(proj + "max_iterations 2147483647").find("'max_iterations' expects an integer in [1, 1000000]"),
            std::string::npos);
  EXPECT_EQ(error_of(proj + "max_iterations 1000000"), "");
  std::string p = proj;
  p.replace(p.find("density 1000"), 12, "density 1e308");
  EXPECT_NE(error_of(p).find("'density' expects with 'pressure projection' a reference density in [1e-150, 1e150]"),
            std::string::npos);
  EXPECT_NE(error_of(kBase + "pmin 1e300").find("'pmin' expects"), std::string::npos);
  EXPECT_EQ(error_of(kBase + "pmin 0"), "");
  EXPECT_EQ(error_of(kBase + "pmin -1e5"), "");
  EXPECT_NE(error_of(kBase + "eos tait 1e300").find("keyword 'eos' (tait"), std::string::npos);
  EXPECT_EQ(error_of(kBase + "eos tait 7"), "");
  EXPECT_NE(error_of(kBase + "viscosity 1e308").find("'viscosity'"), std::string::npos);
  EXPECT_NE(error_of(proj + "viscosity 1e308").find("'viscosity'"), std::string::npos);
  EXPECT_NE(error_of(kBase + "height z x -1").find("'height' expects a wall position inside the grid"), std::string::npos);
  EXPECT_EQ(error_of(kBase + "height z x 1"), "");
  EXPECT_NE(error_of(kBase + "output 10 o points").find("'output' expects at least one field"), std::string::npos);
  EXPECT_NE(error_of(kBase + "hydrostatic z -1 9.81").find("'hydrostatic' expects a surface above"), std::string::npos);
}

// The table of keywords another choice makes inert: each an error naming the keyword and why;
// accepted where they act.
TEST(Options, InertKeywordsRefused) {
  for (const char *kw : {"drag stokes", "theta_smooth 0.1", "theta_min 0.5", "cell_check no"}) {
    const std::string name = std::string(kw).substr(0, std::string(kw).find(' '));
    const std::string e = error_of(kBase + kw);
    EXPECT_NE(e.find("keyword '" + name + "' has no effect here"), std::string::npos) << e;
    EXPECT_NE(e.find("'couple'"), std::string::npos) << e;
    EXPECT_EQ(error_of(kBase + "viscosity 1e-3 couple grains " + kw), "") << kw;
  }
  EXPECT_NE(error_of(kBase + "boundary xlo shear 1e-3").find("keyword 'boundary' has no effect"), std::string::npos);
  EXPECT_EQ(error_of(kBase + "viscosity 1e-3 boundary xlo shear 1e-3"), "");
}

// superficial_velocity: a number or v_name on a periodic axis; refusals name the keyword, what it
// expects and the value; fix_modify changes the value on the fix command's axis only.
TEST(Options, SuperficialVelocity) {
  auto periodic_z = [](const std::string &words) {
    std::vector<std::string> w = {"f", "all", "mpm/fluid"};
    std::istringstream is(words);
    for (std::string s; is >> s;) w.push_back(s);
    std::vector<char *> argv;
    for (auto &s : w) argv.push_back(&s[0]);
    mpm::ParseEnv env = box_env();
    env.periodic[2] = true;
    return mpm::parse_options(static_cast<int>(argv.size()), argv.data(), env);
  };
  mpm::Options o = periodic_z(kBase + "superficial_velocity z 0.05");
  EXPECT_TRUE(o.drive.active);
  EXPECT_EQ(o.drive.axis, 2);
  EXPECT_DOUBLE_EQ(o.drive.target, 0.05);
  EXPECT_TRUE(o.drive.variable.empty());
  o = periodic_z(kBase + "superficial_velocity z v_U");
  EXPECT_EQ(o.drive.variable, "U");
  EXPECT_FALSE(parse(kBase).drive.active);
  EXPECT_EQ(error_of(kBase + "superficial_velocity z 0.05"),
            "Fix mpm/fluid: keyword 'superficial_velocity' expects a periodic axis (the flux it holds leaves the box "
            "through one face and enters through the other), got 'z', along which the box is not periodic (boundary p "
            "in that dimension)");
  EXPECT_EQ(error_of(kBase + "superficial_velocity w 0.05"),
            "Fix mpm/fluid: keyword 'superficial_velocity' expects an axis x, y or z, got 'w'");
  EXPECT_EQ(error_of(kBase + "superficial_velocity z nan"),
            "Fix mpm/fluid: keyword 'superficial_velocity' expects a finite superficial velocity (velocity) or v_name "
            "of an equal-style variable, got 'nan'");
  EXPECT_NE(error_of(kBase + "superficial_velocity z").find("got nothing"), std::string::npos);
  try {
    periodic_z(kBase + "superficial_velocity z 0.05 gate z 1 lower never");
    ADD_FAILURE() << "gate across the driven axis accepted";
  } catch (const mpm::Error &e) {
    EXPECT_NE(std::string(e.what()).find("keyword 'gate' across axis z stops the flux"), std::string::npos) << e.what();
  }
  // fix_modify: a new value or variable on the same axis
  o = periodic_z(kBase + "superficial_velocity z 0.05");
  std::vector<std::string> w = {"superficial_velocity", "z", "0.1"};
  std::vector<char *> a = {&w[0][0], &w[1][0], &w[2][0]};
  EXPECT_EQ(mpm::modify_option(o, 3, a.data()), 3);
  EXPECT_DOUBLE_EQ(o.drive.target, 0.1);
  w = {"superficial_velocity", "x", "0.2"};
  a = {&w[0][0], &w[1][0], &w[2][0]};
  EXPECT_THROW(mpm::modify_option(o, 3, a.data()), mpm::Error);
  EXPECT_EQ(o.drive.axis, 2);
  EXPECT_DOUBLE_EQ(o.drive.target, 0.1);  // unchanged by the refused call
  mpm::Options none = parse(kBase);
  w = {"superficial_velocity", "z", "0.1"};
  a = {&w[0][0], &w[1][0], &w[2][0]};
  EXPECT_THROW(mpm::modify_option(none, 3, a.data()), mpm::Error);
  EXPECT_FALSE(none.drive.active);
}

TEST(Options, RepeatedKeywordWarned) {
  const mpm::Options o = parse(kBase + "cfl 0.3 cfl 0.4 boundary xlo freeslip boundary xhi freeslip");
  ASSERT_EQ(o.warnings.size(), 1u);
  EXPECT_NE(o.warnings[0].find("keyword 'cfl' given more than once"), std::string::npos);
  EXPECT_DOUBLE_EQ(o.cfl, 0.4);
}

TEST(Options, EveryRowIsComplete) {
  std::set<std::string> names;
  for (const mpm::Keyword &k : mpm::keywords()) {
    EXPECT_TRUE(names.insert(k.name).second) << k.name;
    EXPECT_TRUE(*k.type && *k.unit && *k.deflt && *k.help) << k.name;
    const int kinds = (k.real != nullptr) + (k.flag != nullptr) + (k.parse != nullptr);
    EXPECT_EQ(kinds, 1) << k.name << ": one of numeric target, yes/no flag, parse function";
  }
}

// The rows of the reference page's section '## Keywords': one table whose rows start with
// | `keyword` |. Each row as its cells, trimmed, code spans read without their backquotes; a '|'
// escaped as '\|' stays in its cell.
std::vector<std::vector<std::string>> keyword_rows() {
  std::ifstream in(MPM_DOC_PAGE);
  EXPECT_TRUE(in) << MPM_DOC_PAGE;
  std::vector<std::vector<std::string>> rows;
  auto trim = [](std::string s) {
    s.erase(0, s.find_first_not_of(' '));
    s.erase(s.find_last_not_of(' ') + 1);
    return s;
  };
  bool inside = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("## ", 0) == 0) inside = line == "## Keywords";
    if (!inside || line.rfind("| `", 0) != 0) continue;
    std::vector<std::string> cells(1);
    for (std::size_t i = 1; i < line.size(); ++i) {
      if (line[i] == '|' && line[i - 1] != '\\') {
        cells.back() = trim(cells.back());
        cells.emplace_back();
      } else if (line[i] != '`') {
        cells.back() += line[i];
      }
    }
    rows.push_back(cells);
  }
  return rows;
}

// The contract with the reference page: its Keywords table has one row per row of mpm::keywords().
TEST(Options, ReferencePageListsExactlyTheTableKeywords) {
  std::vector<std::string> page;
  for (const std::vector<std::string> &row : keyword_rows()) page.push_back(row[0]);
  std::vector<std::string> table;
  for (const mpm::Keyword &k : mpm::keywords()) table.push_back(k.name);
  std::sort(page.begin(), page.end());
  std::sort(table.begin(), table.end());
  EXPECT_EQ(page, table) << "docs/fix_mpm_fluid.md, section Keywords";
}

// The same table's Default column (the fifth) holds each keyword's default as mpm::keywords() gives it.
TEST(Options, ReferencePageDefaultsAreTheTableDefaults) {
  std::map<std::string, std::string> page;
  for (const std::vector<std::string> &row : keyword_rows()) {
    ASSERT_GE(row.size(), 6u) << row[0];
    page[row[0]] = row[4];
  }
  for (const mpm::Keyword &k : mpm::keywords()) {
    ASSERT_TRUE(page.count(k.name)) << k.name;
    EXPECT_EQ(page[k.name], k.deflt) << "docs/fix_mpm_fluid.md, section Keywords, default of '" << k.name << "'";
  }
}

}  // namespace

// boundary FACE inflow U | outflow: the parsed faces and velocities, and the refusals (the value,
// 'all', a periodic face, pressure eos, mesh_wall, fix_modify changing a face's kind)
TEST(Options, BoundaryInflowOutflow) {
  const std::string proj = "cell 0.5 density 1000 fill col 2 2 2 type 1 ";
  mpm::Options o = parse(proj + "boundary zlo inflow 0.05 boundary zhi outflow");
  EXPECT_EQ(o.face[4].kind, mpm::BcKind::Inflow);
  EXPECT_DOUBLE_EQ(o.face[4].inflow, 0.05);
  EXPECT_EQ(o.face[5].kind, mpm::BcKind::Outflow);
  EXPECT_TRUE(o.flow_faces());
  EXPECT_DOUBLE_EQ(o.face_velocity(4), 0.05);   // along +z at the low face
  EXPECT_DOUBLE_EQ(o.face_velocity(5), 0.0);    // an outflow imposes no velocity
  EXPECT_DOUBLE_EQ(parse(proj + "boundary xhi inflow 0.2").face_velocity(1), -0.2);  // into the grid: -x
  EXPECT_FALSE(parse(proj).flow_faces());
  const std::string inflow = "Fix mpm/fluid: keyword 'boundary inflow' expects a normal velocity U > 0 (velocity, into "
                             "the grid) of the inflow, got ";
  EXPECT_EQ(error_of(proj + "boundary zlo inflow 0"), inflow + "'0'");
  EXPECT_EQ(error_of(proj + "boundary zlo inflow -1"), inflow + "'-1'");
  EXPECT_EQ(error_of(proj + "boundary zlo inflow nan"), inflow + "'nan'");
  EXPECT_EQ(error_of(proj + "boundary zlo inflow"), inflow + "nothing");
  EXPECT_NE(error_of(proj + "boundary all outflow").find("expects one face (xlo xhi ylo yhi zlo zhi) for 'inflow' or "
                                                         "'outflow', got 'all'"), std::string::npos);
  EXPECT_NE(error_of(kBase + "boundary zhi outflow").find("keyword 'boundary zhi outflow' needs 'pressure projection'"),
            std::string::npos);
  mpm::ParseEnv env = box_env();
  env.periodic[0] = true;
  std::vector<std::string> w = {"f", "all", "mpm/fluid", "cell", "0.5", "density", "1000", "boundary", "xlo", "inflow", "1"};
  std::vector<char *> argv;
  for (auto &s : w) argv.push_back(&s[0]);
  try {
    mpm::parse_options(static_cast<int>(argv.size()), argv.data(), env);
    ADD_FAILURE() << "an inflow on a periodic face accepted";
  } catch (const mpm::Error &e) {
    EXPECT_NE(std::string(e.what()).find("keyword 'boundary xlo inflow' expects a face of a non-periodic dimension, got "
                                         "xlo"), std::string::npos) << e.what();
  }
  // fix_modify: an inflow's U may change, a face's kind to or from inflow / outflow not
  std::vector<std::string> b = {"boundary", "zlo", "inflow", "0.1"};
  std::vector<char *> ab = {&b[0][0], &b[1][0], &b[2][0], &b[3][0]};
  EXPECT_EQ(mpm::modify_option(o, 4, ab.data()), 4);
  EXPECT_DOUBLE_EQ(o.face[4].inflow, 0.1);
  b = {"boundary", "zhi", "noslip"};
  ab = {&b[0][0], &b[1][0], &b[2][0]};
  EXPECT_THROW(mpm::modify_option(o, 3, ab.data()), mpm::Error);
  EXPECT_EQ(o.face[5].kind, mpm::BcKind::Outflow);
  b = {"boundary", "xlo", "outflow"};
  ab = {&b[0][0], &b[1][0], &b[2][0]};
  EXPECT_THROW(mpm::modify_option(o, 3, ab.data()), mpm::Error);
  EXPECT_EQ(o.face[0].kind, mpm::BcKind::NoSlip);
}
