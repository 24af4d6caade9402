// laser_drill: single-pulse laser drilling model (Yang 2016, Part I).
// Exit status: 0 finished run (status in summary.json), 2 bad input (nothing
// written), 1 write failure or internal error (no summary.json), 3 status
// diverged (summary.json written: a non-finite or physically absurd state).
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <exception>
#include <iostream>
#include <memory>
#include <optional>

#include "laser_model.h"
#include "laser_output.h"
#include "laser_params.h"
#include "laser_timestep.h"

int main(int argc, char** argv) {
  using namespace laser;
  Invocation inv;
  std::optional<TimeStepPolicy> policy;
  std::unique_ptr<OutputDir> out;
  try {
    inv = parse_command_line(argc, argv);
    if (inv.exit_now) return 0;
    if (!inv.dump_conduction) {
      validate(inv.cfg);
      policy.emplace(inv.cfg);
    }
    // the output folder is checked, created and locked before any computation
    out = std::make_unique<OutputDir>(inv.cfg.out, inv.cfg.overwrite);
  } catch (const UsageError& e) {
    std::cerr << "laser_drill: error: " << e.what() << "\n";
    return 2;
  }
  const Config& cfg = inv.cfg;
  try {
    if (inv.dump_conduction) {
      write_conduction_table(*out);
      std::cout << "laser_drill: wrote " << cfg.out << "/conduction_table.csv\n";
      return 0;
    }
    const auto t0 = std::chrono::steady_clock::now();
    Result r = policy->run(cfg, [&] { return out->profiles_sink(); });
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (r.status == "unstable_time_step") {
      // A time step the explicit scheme cannot take is bad input: nothing is written.
      std::cerr << "laser_drill: error: " << policy->reason() << ": " << r.message << "\n";
      out.reset();
      return 2;
    }
    for (const auto& n : r.notes) std::fprintf(stderr, "laser_drill: note: %s\n", n.c_str());
    out->write_tables(cfg, r);
    out->commit(summary_json(cfg, r, wall));
    out.reset();
    char est[96];
    if (r.status == "diverged")  // no error estimate of a state that is not a solution
      std::snprintf(est, sizeof est, "no error estimate: diverged");
    else
      std::snprintf(est, sizeof est, "est. error depth %.1e, volume %.1e", r.step.depth_error, r.step.volume_error);
    std::printf("status %s; depth %.4g m; volume %.4g m3; rate %.4g m3/s; T_peak %.1f K; "
                "p_peak %.4g Pa; dt %.3g s (%s); wall %.3f s\n",
                r.status.c_str(), r.depth_center, r.volume_removed, r.removal_rate, r.T_peak, r.p_peak, r.dt, est,
                wall);
    std::fflush(stdout);
    for (const auto& w : r.warnings) std::fprintf(stderr, "laser_drill: warning: %s\n", w.c_str());
    if (!r.message.empty()) std::fprintf(stderr, "laser_drill: %s: %s\n", r.status.c_str(), r.message.c_str());
    if (r.status == "diverged") return 3;
  } catch (const WriteError& e) {
    std::cerr << "laser_drill: error: " << e.what() << "\n";
    out.reset();  // removes the staged files and the lock
    std::fflush(nullptr);
    // An HDF5 file whose close failed stays in the library's table and its
    // exit handler (H5_term_library) then crashes; the files are already gone.
    std::_Exit(1);
  } catch (const std::exception& e) {
    std::cerr << "laser_drill: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
