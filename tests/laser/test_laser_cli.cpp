// The laser_drill executable: bad input is rejected before any computation
// with the option, its unit and range, exit status 2 and nothing written;
// outputs are complete or absent (full disk, reused and shared --out).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <toml++/toml.h>

#include "laser_params.h"

#ifndef LASER_DRILL_EXE
#error "LASER_DRILL_EXE must name the laser_drill executable"
#endif

namespace fs = std::filesystem;

namespace {
struct CliRun {
  int code;
  std::string err, out;
};

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Runs laser_drill with args (a shell word list); file_limit > 0 sets
// RLIMIT_FSIZE in the child, so that writes beyond it fail as on a full disk.
CliRun run(const std::string& args, const fs::path& dir, long file_limit = 0) {
  fs::create_directories(dir);
  const fs::path err = dir / "stderr.txt", out = dir / "stdout.txt";
  const std::string cmd = std::string(LASER_DRILL_EXE) + " " + args + " >" + out.string() + " 2>" + err.string();
  int status;
  if (file_limit == 0) {
    status = std::system(cmd.c_str());
  } else {
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::signal(SIGXFSZ, SIG_IGN);  // write() then fails with EFBIG instead of killing
      const rlimit rl{static_cast<rlim_t>(file_limit), static_cast<rlim_t>(file_limit)};
      ::setrlimit(RLIMIT_FSIZE, &rl);
      ::execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
      std::_Exit(127);
    }
    ::waitpid(pid, &status, 0);
  }
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(err), slurp(out)};
}

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("laser_cli_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

struct BadCase {
  std::string what;       // the bad input checked
  std::string args;       // %D is replaced by the scratch folder
  std::string config;     // written to %D/case.toml when not empty
  std::string must_contain[3];
};

void PrintTo(const BadCase& b, std::ostream* os) { *os << b.what; }

std::string subst(std::string s, const fs::path& d) {
  for (size_t k; (k = s.find("%D")) != std::string::npos;) s.replace(k, 2, d.string());
  return s;
}

class LaserBadInput : public ::testing::TestWithParam<BadCase> {};
}  // namespace

TEST_P(LaserBadInput, RejectedBeforeComputingWithOptionUnitRange) {
  const BadCase& bc = GetParam();
  const fs::path dir = scratch("bad");
  if (!bc.config.empty()) std::ofstream(dir / "case.toml", std::ios::binary) << bc.config;
  const fs::path out = dir / "out";
  const auto t0 = std::chrono::steady_clock::now();
  const bool own_out = bc.args.find("--out") != std::string::npos;
  const CliRun r = run(subst(bc.args, dir) + " --quiet" + (own_out ? "" : " --out " + out.string()), dir);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.code, 2) << r.err;
  for (const auto& m : bc.must_contain)
    if (!m.empty()) EXPECT_NE(r.err.find(m), std::string::npos) << "missing '" << m << "' in: " << r.err;
  EXPECT_FALSE(fs::exists(out)) << "output folder created for bad input";
  EXPECT_LT(s, 0.5) << "rejected only after computing";  // the default case computes for 0.3-0.8 s
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(
    Laser, LaserBadInput,
    ::testing::Values(
        BadCase{"section_ignored", "--config %D/case.toml", "[material]\nintensity = 5e10\n",
                {"[material] intensity", "belongs in [laser]"}},
        BadCase{"key_outside_section", "--config %D/case.toml", "intensity = 5e10\n", {"intensity", "[laser]"}},
        BadCase{"unknown_section", "--config %D/case.toml", "[beam]\nintensity = 5e10\n", {"unknown section [beam]"}},
        BadCase{"repeated_key", "--config %D/case.toml", "[laser]\nintensity = 5e10\nintensity = 6e10\n",
                {"case.toml:3", "redefine", "intensity"}},
        BadCase{"config_value_range", "--config %D/case.toml", "[laser]\nradius = 1e50\n",
                {"[laser] radius", "[1e-06, 0.01] m", "1e+50"}},
        BadCase{"config_value_type", "--config %D/case.toml", "[laser]\npulse = \"1e-4\"\n",
                {"[laser] pulse", "decimal number in [1e-09, 0.01] s"}},
        BadCase{"config_unknown_key", "--config %D/case.toml", "[laser]\nspeed_of_light = 3e8\n",
                {"case.toml:2", "speed_of_light", "unknown key"}},
        BadCase{"material_foo", "--material=foo", "", {"--material", "superalloy", "foo"}},
        BadCase{"frames_atoi", "--frames 1e3", "", {"--frames", "integer in [2, 100000]", "1e3"}},
        BadCase{"frames_too_many", "--frames 1000000", "", {"--frames", "[2, 100000]"}},
        BadCase{"config_directory", "--config %D", "", {"--config", "not a regular file"}},
        BadCase{"config_dev_zero", "--config /dev/zero", "", {"--config", "not a regular file"}},
        BadCase{"config_nul_byte", "--config %D/case.toml", std::string("[output]\nout = \"ab\0cd\"\n", 22),
                {"--config", "case.toml:2", "NUL"}},
        BadCase{"radius_1e300", "--radius 1e300", "", {"--radius", "[1e-06, 0.01] m", "1e300"}},
        BadCase{"radius_1e50", "--radius 1e50", "", {"--radius", "[1e-06, 0.01] m"}},
        BadCase{"radius_1em30", "--radius 1e-30", "", {"--radius", "[1e-06, 0.01] m"}},
        BadCase{"intensity_1e20", "--intensity 1e20", "", {"--intensity", "[1e+06, 1e+13] W/m2"}},
        BadCase{"pulse_1e300", "--pulse 1e300", "", {"--pulse", "[1e-09, 0.01] s"}},
        BadCase{"hex_number", "--intensity 0x1p36", "", {"--intensity", "decimal number", "W/m2"}},
        BadCase{"leading_space", "--intensity ' 5e10'", "", {"--intensity", "decimal number", "W/m2"}},
        BadCase{"dxi_bad_alloc", "--dxi 1e-7", "", {"--dxi", "[0.001, 0.5]"}},
        BadCase{"out_existing_file", "--out %D/case.toml", "[laser]\n", {"--out", "not a directory"}},
        BadCase{"out_under_a_file", "--out %D/case.toml/sub", "[laser]\n", {"--out", "not a directory"}},
        BadCase{"out_uncreatable", "--out /proc/laser_drill_out", "", {"--out", "cannot create"}},
        BadCase{"negative_intensity", "--intensity -1e10", "", {"--intensity", "W/m2"}},
        BadCase{"xi_p_zero", "--xi-p 0", "", {"--xi-p", "(0, 10]"}},
        BadCase{"melt_content_unknown", "--melt-content hot", "", {"--melt-content", "transient", "hot"}},
        BadCase{"melt_content_transient_ode", "--melt-content transient --melt-heat ode", "",
                {"--melt-content", "--melt-heat flux", "ode"}},
        BadCase{"melt_content_transient_conduction", "--melt-content transient --model conduction", "",
                {"--melt-content", "flow model", "conduction"}},
        BadCase{"heat_courant_ode", "--heat-courant 0.5 --melt-heat ode", "",
                {"--heat-courant", "(0, 10]", "ode"}},
        BadCase{"heat_courant_text_flow", "--heat-courant 0.5 --melt-flow text", "",
                {"--heat-courant", "inert", "--melt-flow text"}},
        BadCase{"heat_courant_conduction", "--heat-courant 0.25 --model conduction", "",
                {"--heat-courant", "conduction", "0.25"}},
        BadCase{"heat_courant_config_ode", "--config %D/case.toml",
                "[numerics]\nheat_courant = 0.5\n[model]\nmelt_heat = \"ode\"\n", {"--heat-courant", "inert", "0.5"}},
        BadCase{"m_one", "--m 1", "", {"--m", "(1, 100]"}},
        BadCase{"T_melt_above_sat", "--T-melt 3500", "", {"--T-melt", "--T-sat0", "K"}},
        BadCase{"model_unknown", "--model turbulent", "", {"--model", "conduction, rising, risingfall, boundary"}},
        BadCase{"dt_above_limit", "--dt 5e-5", "", {"--dt", "explicit stability limit", "s"}},
        // became unstable only after running before (step 16, t = 85 us): now refused up front
        BadCase{"dt_above_accepted", "--dt 5.3e-6", "", {"--dt", "accepted step", "3.126e-06"}},
        BadCase{"dt_above_accepted_config", "--config " LASER_INPUTS_DIR "/rising_m2.toml --dt 6.21e-6", "",
                {"--dt", "accepted step", "3.126e-06"}},
        BadCase{"dt_longer_than_pulse", "--dt 1e-4 --pulse 5e-5 --melt-update implicit", "",
                {"--dt", "shorter than the pulse"}},
        BadCase{"repeated_option", "--intensity 5e10 --intensity 6e10", "", {"--intensity"}},
        BadCase{"unknown_option", "--no-such-option 3", "", {"--no-such-option"}},
        BadCase{"stray_argument", "stray", "", {"stray"}},
        BadCase{"melt_flow_unknown", "--melt-flow upwind", "", {"--melt-flow", "conservative, text", "upwind"}},
        BadCase{"T_critical_below_sat", "--T-critical 3000", "", {"--T-critical", "--T-sat0", "3000 K"}},
        BadCase{"absorptivity_above_one", "--absorptivity 1.2", "", {"--absorptivity", "(0, 1]", "1.2"}},
        BadCase{"absorptivity_zero", "--absorptivity 0", "", {"--absorptivity", "(0, 1]"}},
        BadCase{"recoil_unknown", "--recoil half", "", {"--recoil", "full, knight", "half"}},
        BadCase{"cannot_finish_1e13", "--intensity 1e13", "", {"--intensity 1e+13 W/m2", "--pulse", "node steps"}},
        BadCase{"cannot_finish_fine_grid", "--intensity 5e12 --dxi 0.001", "", {"--dxi", "cannot finish", "node steps"}},
        BadCase{"T_critical_negative", "--T-critical -5", "", {"--T-critical", "K", "-5"}}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return info.param.what; });

TEST(LaserCli, VersionAndHelp) {
  const fs::path dir = scratch("help");
  CliRun r = run("--version", dir);
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.out.rfind("laser_drill ", 0), 0u) << r.out;
  r = run("--help", dir);
  EXPECT_EQ(r.code, 0);
  for (const char* s : {"--intensity", "W/m2", "--pulse", "--radius", "--melt-energy", "advected", "--tol",
                        "--overwrite", "default 7.5e+10", "[laser] intensity", "[material] pr"})
    EXPECT_NE(r.out.find(s), std::string::npos) << s;
  fs::remove_all(dir);
}

// --config=FILE is honoured; TOML literal strings, '#' inside strings and 5_000
// are read as TOML; a --frames above the run's steps is clipped with a note.
TEST(LaserCli, TomlConfigIsReadAsToml) {
  const fs::path dir = scratch("toml");
  const fs::path out = dir / "run#1";
  std::ofstream(dir / "low.toml") << "[laser]\nintensity = 2.5e10   # W/m2\npulse = 2e-5\n"
                                     "[output]\nframes = 5_000\nout = '" << out.string() << "'\n"
                                     "[model]\nmelt_energy = \"text\"\ncurvature = false\n";
  const CliRun r = run("--config=" + (dir / "low.toml").string() + " --quiet", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(fs::exists(out / "summary.json")) << "out = 'DIR/run#1' not honoured";
  const std::string j = slurp(out / "summary.json");
  EXPECT_NE(j.find("\"intensity_W_per_m2\": 25000000000.0"), std::string::npos) << j;
  EXPECT_NE(j.find("\"melt_energy\": \"text\""), std::string::npos);
  EXPECT_NE(r.err.find("--frames 5000 clipped to"), std::string::npos) << r.err;
  EXPECT_NE(j.find("clipped to"), std::string::npos);
  fs::remove_all(dir);
}

TEST(LaserCli, RunWritesAllOutputsAndErrorEstimate) {
  const fs::path dir = scratch("run");
  const fs::path out = dir / "out";
  const CliRun r = run("--intensity 5e10 --model rising --m 3 --pulse 100e-6 --quiet --out " + out.string(), dir);
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* f : {"summary.json", "final_profile.csv", "centre.csv", "profiles.h5"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  EXPECT_FALSE(fs::exists(out / ".laser_drill.lock"));
  const std::string j = slurp(out / "summary.json");
  for (const char* k : {"\"status\": \"ok\"", "\"depth_error_estimate\"", "\"volume_error_estimate\"",
                        "\"model\": \"rising\"", "\"m\": 3.0", "\"energy_check\"", "\"melt_energy\": \"advected\""})
    EXPECT_NE(j.find(k), std::string::npos) << k << "\n" << j;
  EXPECT_EQ(j.find("nan"), std::string::npos);
  fs::remove_all(dir);
}

TEST(LaserCli, LowIntensityReportsNoMelt) {
  const fs::path dir = scratch("nomelt");
  const CliRun r = run("--intensity 1e8 --quiet --out " + (dir / "out").string(), dir);
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(slurp(dir / "out" / "summary.json").find("\"status\": \"no_melt\""), std::string::npos);
  EXPECT_NE(r.err.find("does not reach T_m"), std::string::npos);
  fs::remove_all(dir);
}

// A reused --out is refused; --overwrite first removes what the earlier run
// wrote (also a stale conduction_table.csv) and refuses foreign files.
TEST(LaserOutput, ReusedOutRefusedUnlessOverwrite) {
  const fs::path dir = scratch("reuse");
  const fs::path out = dir / "out";
  const std::string args = "--pulse 20e-6 --quiet --out " + out.string();
  ASSERT_EQ(run(args, dir).code, 0);
  ASSERT_EQ(run("--conduction-table --overwrite --out " + out.string(), dir).code, 0);
  EXPECT_TRUE(fs::exists(out / "conduction_table.csv"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));  // removed by --overwrite
  ASSERT_EQ(run(args + " --overwrite", dir).code, 0);
  EXPECT_FALSE(fs::exists(out / "conduction_table.csv")) << "stale file kept";
  const std::string before = slurp(out / "summary.json");
  CliRun r = run(args + " --intensity 5e10", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--out"), std::string::npos);
  EXPECT_NE(r.err.find("not empty"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(out / "summary.json"), before);
  std::ofstream(out / "notes.txt") << "mine\n";
  r = run(args + " --overwrite", dir);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("notes.txt"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  EXPECT_EQ(slurp(out / "summary.json"), before);
  fs::remove_all(dir);
}

// A second run into a folder another run is writing stops with a clear error
// and leaves the first run's output whole.
TEST(LaserOutput, SharedOutIsLocked) {
  const fs::path dir = scratch("shared");
  const fs::path out = dir / "out";
  // a run of about a second (small grid spacing)
  const std::string cmd = std::string(LASER_DRILL_EXE) + " --pulse 100e-6 --dxi 0.004 --quiet --out " +
                          out.string() + " >" + (dir / "first.txt").string() + " 2>&1 & echo $! >" +
                          (dir / "pid").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  for (int k = 0; k < 200 && !fs::exists(out / ".laser_drill.lock"); ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(fs::exists(out / ".laser_drill.lock"));
  const CliRun r = run("--pulse 20e-6 --quiet --overwrite --out " + out.string(), dir);
  const bool first_running = ::kill(std::stoi(slurp(dir / "pid")), 0) == 0;
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("another laser_drill run"), std::string::npos) << r.err;
  // wait for the first run and check it wrote a whole, consistent set
  for (int k = 0; k < 3000 && ::kill(std::stoi(slurp(dir / "pid")), 0) == 0; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_TRUE(first_running) << "the first run ended before the second started; the test proves nothing";
  const std::string j = slurp(out / "summary.json");
  EXPECT_NE(j.find("\"pulse_s\": 0.0001"), std::string::npos) << slurp(dir / "first.txt");
  for (const auto& e : fs::directory_iterator(out)) EXPECT_NE(e.path().extension(), ".part") << e.path();
  fs::remove_all(dir);
}

// Full disk, imitated by a file-size limit (RLIMIT_FSIZE; writes fail with
// EFBIG like ENOSPC on a full file system): exit 1 naming the file, no
// summary.json, no partial file left; a limit that fits lets the run succeed.
TEST(LaserOutput, FullDiskNeverReportsSuccess) {
  const fs::path dir = scratch("full");
  for (long limit : {20000L, 200000L, 600000L, 4000000L}) {
    const fs::path out = dir / ("out" + std::to_string(limit));
    const CliRun r = run("--pulse 100e-6 --frames 50 --quiet --out " + out.string(), dir, limit);
    if (r.code == 0) {
      // then every file is complete: the run was able to write all of them
      EXPECT_TRUE(fs::exists(out / "summary.json")) << limit;
      const std::string csv = slurp(out / "centre.csv");
      EXPECT_EQ(csv.back(), '\n') << limit;
      EXPECT_GE(limit, 1000000L) << "success reported under a limit the outputs (0.87 MB) cannot fit";
    } else {
      EXPECT_EQ(r.code, 1) << limit << ": " << r.err;
      EXPECT_NE(r.err.find("cannot write " + out.string()), std::string::npos) << r.err;
      EXPECT_FALSE(fs::exists(out / "summary.json")) << limit;
      if (fs::exists(out))
        for (const auto& e : fs::directory_iterator(out)) ADD_FAILURE() << "left behind: " << e.path();
    }
  }
  fs::remove_all(dir);
}

// Every example config is valid TOML (toml++) with meaningful sections, read
// by the program's own reader; each also runs at a reduced size (CMakeLists).
TEST(LaserConfigs, ExamplesAreValidToml) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(LASER_INPUTS_DIR)) {
    if (e.path().extension() != ".toml") continue;
    ++n;
    EXPECT_NO_THROW(toml::parse_file(e.path().string())) << e.path();
    laser::Config c;
    c.I0 = 0;  // every example sets the intensity
    try {
      laser::read_config_file(c, e.path().string());
    } catch (const std::exception& x) {
      ADD_FAILURE() << e.path() << ": " << x.what();
    }
    EXPECT_EQ(c.I0, 7.5e10) << e.path();
  }
  EXPECT_GE(n, 4);
}
