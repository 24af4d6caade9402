// The laser_drill executable: bad input is rejected with the option and its
// valid range, a non-zero exit code and nothing written; good input writes
// the documented outputs.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

#ifndef LASER_DRILL_EXE
#error "LASER_DRILL_EXE must name the laser_drill executable"
#endif

namespace fs = std::filesystem;

namespace {
struct CliRun {
  int code;
  std::string err, out;
};

CliRun run(const std::string& args, const fs::path& dir) {
  fs::create_directories(dir);
  const fs::path err = dir / "stderr.txt", out = dir / "stdout.txt";
  const std::string cmd = std::string(LASER_DRILL_EXE) + " " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  auto slurp = [](const fs::path& p) {
    std::ifstream f(p);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  };
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(err), slurp(out)};
}

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("laser_cli_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  return p;
}

struct BadCase {
  std::string args;
  std::string must_contain[2];
};

void PrintTo(const BadCase& b, std::ostream* os) { *os << b.args; }

class LaserBadInput : public ::testing::TestWithParam<BadCase> {};
}  // namespace

TEST_P(LaserBadInput, RejectedWithMessageAndNothingWritten) {
  const BadCase& bc = GetParam();
  const fs::path dir = scratch("bad");
  const fs::path out = dir / "out";
  const CliRun r = run(bc.args + " --quiet --out " + out.string(), dir);
  EXPECT_EQ(r.code, 2) << r.err;
  for (const auto& s : bc.must_contain)
    if (!s.empty()) EXPECT_NE(r.err.find(s), std::string::npos) << "stderr: " << r.err;
  EXPECT_FALSE(fs::exists(out)) << "output directory created for bad input";
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(
    Laser, LaserBadInput,
    ::testing::Values(
        BadCase{"--intensity -1e10", {"--intensity", "(0, inf)"}},
        BadCase{"--intensity 0", {"--intensity", "(0, inf)"}},
        BadCase{"--rho 0", {"--rho", "(0, inf)"}},
        BadCase{"--k-solid -3", {"--k-solid", "(0, inf)"}},
        BadCase{"--pulse abc", {"--pulse", "expected a number"}},
        BadCase{"--T-melt 3500", {"--T-melt", "--T-sat0"}},
        BadCase{"--T-melt 3443.15", {"--T-melt", "below"}},
        BadCase{"--model turbulent", {"--model", "conduction|rising|risingfall|boundary"}},
        BadCase{"--xi-p 0", {"--xi-p", "(0, inf)"}},
        BadCase{"--xi-p -0.5", {"--xi-p", "(0, inf)"}},
        BadCase{"--m 1", {"--m", "(1, inf)"}},
        BadCase{"--m 0.5", {"--m", "(1, inf)"}},
        BadCase{"--dxi 0.7", {"--dxi", "(0, 0.5]"}},
        BadCase{"--dt 1.5e-5", {"unstable", "--dt"}},
        BadCase{"--dt 5e-5", {"--dt", "explicit stability limit"}},
        BadCase{"--dt 1e-3", {"--dt", "shorter than the pulse"}},
        BadCase{"--no-such-option 3", {"unknown option", "--no-such-option"}},
        BadCase{"--intensity", {"--intensity", "missing value"}},
        BadCase{"stray", {"unexpected argument", "stray"}}),
    [](const ::testing::TestParamInfo<BadCase>& info) {
      std::string n;
      for (char c : info.param.args) n += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
      return std::to_string(info.index) + "_" + n;
    });

TEST(LaserCli, BadConfigFileKeyNamesFileAndLine) {
  const fs::path dir = scratch("cfg");
  fs::create_directories(dir);
  std::ofstream(dir / "case.toml") << "# case\nintensity = 5e10\nspeed_of_light = 3e8\n";
  const CliRun r = run("--config " + (dir / "case.toml").string() + " --out " + (dir / "out").string(), dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("case.toml:3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("speed-of-light"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

TEST(LaserCli, HelpListsUnitsAndDefaults) {
  const fs::path dir = scratch("help");
  const CliRun r = run("--help", dir);
  EXPECT_EQ(r.code, 0);
  for (const char* s : {"--intensity", "[W/m2]", "--pulse", "--radius", "[m]", "--model", "--xi-p", "--pr",
                        "--dxi", "--dtau", "--out", "default 7.5e+10", "default risingfall"})
    EXPECT_NE(r.out.find(s), std::string::npos) << s;
  fs::remove_all(dir);
}

TEST(LaserCli, ConfigFileRunWritesAllOutputs) {
  const fs::path dir = scratch("run");
  fs::create_directories(dir);
  // command line overrides the file: the pulse is shortened to keep the test fast
  std::ofstream(dir / "case.toml") << "[laser]\nintensity = 5e10\nmodel = \"rising\"\nm = 3\npulse = 1e-3\n";
  const fs::path out = dir / "out";
  const CliRun r = run("--config " + (dir / "case.toml").string() + " --pulse 100e-6 --quiet --out " + out.string(), dir);
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* f : {"summary.json", "final_profile.csv", "centre.csv", "profiles.h5"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  std::ifstream js(out / "summary.json");
  std::stringstream s;
  s << js.rdbuf();
  const std::string j = s.str();
  for (const char* k : {"\"status\": \"ok\"", "\"t_melt_center_s\"", "\"depth_center_m\"", "\"volume_removed_m3\"",
                        "\"removal_rate_m3_per_s\"", "\"T_peak_K\"", "\"p_peak_Pa\"", "\"wall_time_s\"",
                        "\"model\": \"rising\"", "\"m\": 3", "\"pulse_s\": 0.0001", "\"intensity_W_per_m2\": 5e+10"})
    EXPECT_NE(j.find(k), std::string::npos) << k << "\n" << j;
  EXPECT_EQ(j.find("nan"), std::string::npos);
  fs::remove_all(dir);
}

TEST(LaserCli, LowIntensityReportsNoMelt) {
  const fs::path dir = scratch("nomelt");
  const CliRun r = run("--intensity 1e8 --quiet --out " + (dir / "out").string(), dir);
  EXPECT_EQ(r.code, 0);
  std::ifstream js(dir / "out" / "summary.json");
  std::stringstream s;
  s << js.rdbuf();
  EXPECT_NE(s.str().find("\"status\": \"no_melt\""), std::string::npos);
  EXPECT_NE(r.err.find("does not reach T_m"), std::string::npos);
  fs::remove_all(dir);
}
