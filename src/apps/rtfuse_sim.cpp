// rtfuse-sim: drives the bus-level simulated robot through a scenario in
// lockstep (as fast as the CPU allows), with the daemon's drivers and
// filter, and writes the drive as a HAL recording: the CANopen frames and
// MPU register bytes with their data-ready edges the drivers saw, the loop
// ticks, the published outputs and the ground truth on its own channel.
// rtfuse-replay replays such a file byte for byte; tools/plot_trajectory.py
// draws it. Prints one JSON line with the errors against ground truth.
#include <unistd.h>

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <string>

#include <CLI/CLI.hpp>

#include "runtime/config_loader.hpp"
#include "sim/simulated_drive.hpp"

namespace {


}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rtfuse-sim: drive the simulated robot in lockstep and record the drive at HAL level"};
  std::string config_path, scenario_path, out_path;
  bool quiet = false;
  app.add_option("-c,--config", config_path, "robot config (TOML) with [hardware] backend = \"sim\"")->required();
  app.add_option("-s,--scenario", scenario_path, "drive scenario (default: the config's [hardware] scenario)");
  app.add_option("-o,--out", out_path, "write the drive to this LCM log (a HAL recording)");
  app.add_flag("-q,--quiet", quiet, "no progress line");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  std::string text;
  int err = 0;
  if (!rtfuse::read_text_file(config_path, &text, &err)) {
    std::fprintf(stderr, "rtfuse-sim: cannot read %s: %s\n", config_path.c_str(), std::strerror(err));
    return 2;
  }
  const rtfuse::ConfigLoadResult loaded = rtfuse::load_config_string(text, config_path);
  if (!loaded.config) {
    for (const auto& e : loaded.errors) std::fprintf(stderr, "%s\n", e.to_string().c_str());
    return 2;
  }
  const rtfuse::RuntimeConfig& cfg = *loaded.config;
  if (cfg.hardware.backend != rtfuse::HalBackend::kSim) {
    std::fprintf(stderr, "rtfuse-sim: %s: [hardware] backend must be \"sim\"\n", config_path.c_str());
    return 2;
  }
  rtfuse::sim::DriveOptions options;
  options.scenario_path = scenario_path;
  options.record_path = out_path;
  options.config_text = text;
  const bool tty = !quiet && isatty(STDERR_FILENO) != 0;
  const rtfuse::sim::DriveResult r =
      rtfuse::sim::run_simulated_drive(cfg, options, [tty](const rtfuse::sim::DriveProgress& p) {
        if (tty) std::fprintf(stderr, "\rsim: %.0f of %.0f s\033[K", p.sim_time_s, p.duration_s);
      });
  if (tty) std::fprintf(stderr, "\n");
  if (!r.ok) {
    std::fprintf(stderr, "rtfuse-sim: %s\n", r.error.c_str());
    return 1;
  }
  if (r.recording_lost > 0) {
    std::fprintf(stderr, "rtfuse-sim: the recorder lost %" PRId64 " bus events: the recording is incomplete\n",
                 r.recording_lost);
    return 1;
  }
  const rtfuse::Snapshot& s = r.final;
  std::printf("{\"duration_s\": %.3f, \"ticks\": %" PRId64
              ", \"final_error_m\": %.4f, \"rms_error_m\": %.4f, \"final_yaw_error_rad\": %.4f, "
              "\"max_error_m\": %.4f, \"max_jump_m\": %.4f, \"raw_final_error_m\": %.4f, \"raw_rms_error_m\": %.4f, "
              "\"x\": %.4f, \"y\": %.4f, \"yaw\": %.4f}\n",
              r.duration_s, r.ticks, r.final_error_m, r.rms_error_m, r.final_yaw_error_rad, r.max_error_m, r.max_jump_m,
              r.raw_final_error_m, r.raw_rms_error_m, s.state[0], s.state[1], s.state[5]);
  return 0;
}
