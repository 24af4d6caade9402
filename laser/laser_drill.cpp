// laser_drill: single-pulse laser drilling model (Yang 2016, Part I).
#include <chrono>
#include <cstdio>
#include <exception>
#include <iostream>

#include "laser_model.h"
#include "laser_output.h"
#include "laser_params.h"

int main(int argc, char** argv) {
  using namespace laser;
  Config cfg;
  bool help = false, dump_conduction = false;
  try {
    cfg = parse_command_line(argc, argv, help, dump_conduction);
    if (help) {
      std::cout << usage_text();
      return 0;
    }
    validate(cfg);
    const double dt_max = cfg.implicit_melt ? 0.0 : explicit_step_limit(cfg);
    if (dt_max > 0.0 && cfg.dt > dt_max) {
      char buf[256];
      std::snprintf(buf, sizeof buf,
                    "--dt/--dtau: time step %.4g s is above the explicit stability limit %.4g s of the "
                    "melt thickness update (4-14) at this intensity; valid range (0, %.4g] s",
                    cfg.dt, dt_max, dt_max);
      throw UsageError(buf);
    }
  } catch (const UsageError& e) {
    std::cerr << "laser_drill: error: " << e.what() << "\n";
    return 2;
  }
  try {
    if (dump_conduction) {
      write_conduction_table(cfg.out);
      std::cout << "laser_drill: wrote " << cfg.out << "/conduction_table.csv\n";
      return 0;
    }
    const auto t0 = std::chrono::steady_clock::now();
    Result r = run_simulation(cfg);
    // The automatic step is halved (at most 6 times) when the run-time check of
    // (4-14) fires; a step given by the user is never changed.
    for (int k = 0; k < 6 && cfg.dt_auto && r.status == "unstable_time_step"; ++k) {
      cfg.dt *= 0.5;
      if (!cfg.quiet)
        std::fprintf(stderr, "laser_drill: automatic step unstable (%s); retrying with dt = %.4g s\n",
                     r.message.c_str(), cfg.dt);
      r = run_simulation(cfg);
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (r.status == "unstable_time_step") {
      // A time step the explicit scheme cannot take is bad input: nothing is written.
      std::cerr << "laser_drill: error: --dt/--dtau: " << r.message << "\n";
      return 2;
    }
    write_outputs(cfg, r, wall);
    std::printf("status %s; depth %.4g m; volume %.4g m3; rate %.4g m3/s; T_peak %.1f K; "
                "p_peak %.4g Pa; wall %.3f s\n",
                r.status.c_str(), r.depth_center, r.volume_removed, r.removal_rate, r.T_peak,
                r.p_peak, wall);
    std::fflush(stdout);
    if (!r.message.empty())
      std::fprintf(stderr, "laser_drill: %s: %s\n", r.status.c_str(), r.message.c_str());
  } catch (const std::exception& e) {
    std::cerr << "laser_drill: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
