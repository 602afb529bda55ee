// rtfuse-sim: drives the bus-level simulated robot through a scenario in
// lockstep (as fast as the CPU allows), with the daemon's drivers and
// filter, and writes the drive as a HAL recording: the CANopen frames and
// MPU register bytes with their data-ready edges the drivers saw, the loop
// ticks, the published outputs and the ground truth on its own channel.
// rtfuse-replay replays such a file byte for byte; tools/plot_trajectory.py
// draws it. Prints one JSON line with the errors against ground truth.
//
// --report-every S (the soak, tools/soak.sh): one JSON line per S simulated
// seconds before the final one, with the process's resident memory, the
// error, the largest variance and whether any state or covariance entry
// was ever not finite, and the counters; under tools/soak.sh's allocation
// probe the first report arms it (start-up is over) and the end disarms it.
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "apps/command_line.hpp"
#include "apps/mapper_files.hpp"
#include "apps/nav_figure.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/devices/hardware.hpp"
#include "runtime/devices/navigator/navigator_device.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/sim_drive.hpp"

extern "C" void rtfuse_alloc_probe_steady(int steady) __attribute__((weak));

namespace {

long resident_kib() {
  // statm's second field is resident pages. open/read, not fopen: no FILE
  // is allocated while the allocation probe is armed.
  char buf[128];
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  const ssize_t n = ::read(fd, buf, sizeof buf - 1);
  ::close(fd);
  if (n <= 0) return -1;
  buf[n] = 0;
  long size = 0, resident = 0;
  if (std::sscanf(buf, "%ld %ld", &size, &resident) != 2) return -1;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

struct SoakReport {
  double every_s = 0;
  double next_s = 0;
  double max_variance = 0;
  double max_error = 0;
  bool finite = true;
  bool armed = false;
  std::chrono::steady_clock::time_point wall0 = std::chrono::steady_clock::now();

  void on_tick(rtfuse::TimeNs t, rtfuse::TimeNs t0, const rtfuse::Snapshot& s, const rtfuse::sim::TruthState& truth) {
    for (int k = 0; k < 15; ++k) finite = finite && std::isfinite(s.state[k]);
    for (int k = 0; k < 15; ++k) {
      const double v = s.covariance[k * 16];
      finite = finite && std::isfinite(v);
      if (v > max_variance) max_variance = v;
    }
    const double e = s.initialized ? std::hypot(s.state[0] - truth.x, s.state[1] - truth.y) : 0.0;
    if (e > max_error) max_error = e;
    const double sim_s = static_cast<double>(t - t0) / 1e9;
    if (sim_s < next_s) return;
    next_s += every_s;
    std::int64_t received = 0, accepted = 0, rejected = 0;
    for (int i = 0; i < s.num_sensors; ++i) {
      received += s.sensors[i].received;
      accepted += s.sensors[i].accepted;
      rejected += rtfuse::rejected_total(s.sensors[i]);
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    std::printf("{\"report\": 1, \"sim_s\": %.1f, \"wall_s\": %.1f, \"rss_kib\": %ld, \"error_m\": %.4f, "
                "\"max_error_m\": %.4f, \"position_sigma_m\": %.4f, \"max_variance\": %.6g, \"finite\": %s, "
                "\"ticks\": %" PRId64 ", \"fused\": %" PRId64 ", \"received\": %" PRId64 ", \"accepted\": %" PRId64
                ", \"rejected\": %" PRId64 "}\n",
                sim_s, wall, resident_kib(), e, max_error, std::sqrt(s.covariance[0] + s.covariance[16]), max_variance,
                finite ? "true" : "false", s.loop.ticks, s.loop.measurements_fused, received, accepted, rejected);
    std::fflush(stdout);
    if (!armed && rtfuse_alloc_probe_steady != nullptr) {
      rtfuse_alloc_probe_steady(1);
      armed = true;
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  rtfuse::apps::CommandLine cli{"rtfuse-sim: drive the simulated robot in lockstep and record the drive at HAL level"};
  std::string config_path, scenario_path, out_path;
  bool quiet = false;
  double report_every = 0;
  cli.option("-c,--config", &config_path, "robot config (TOML) with [hardware] backend = \"sim\"").required();
  cli.option("-s,--scenario", &scenario_path, "drive scenario (default: the config's [hardware] scenario)");
  cli.option("-o,--out", &out_path, "write the drive to this LCM log (a HAL recording)");
  std::string trace_path;
  cli.option("--trace", &trace_path,
                 "write t, the truth and every instance's x y yaw (and map -> odom) at 50 Hz to this CSV file");
  std::string map_out, nav_out;
  cli.option("--nav-out", &nav_out,
                 "write the navigator's costmap, its last path, the truly driven trajectory and the goals as a PNG");
  cli.option("--map-out", &map_out,
                 "write the mapper's map at the end: PREFIX.bt, PREFIX.pgm + PREFIX.yaml and PREFIX.png");
  cli.flag("-q,--quiet", &quiet, "no progress line");
  cli.option("--report-every", &report_every, "a JSON line every S simulated seconds (the soak; 0: none)")
      .non_negative();
  if (const auto exit = cli.parse(argc, argv)) return *exit;
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
  std::string map_error;
  if (!map_out.empty() && !cfg.hardware.mapping.enabled) {
    std::fprintf(stderr, "rtfuse-sim: --map-out needs a [mapping] section in %s\n", config_path.c_str());
    return 2;
  }
  if (!nav_out.empty() && !cfg.hardware.navigation.enabled) {
    std::fprintf(stderr, "rtfuse-sim: --nav-out needs a [navigation] section in %s\n", config_path.c_str());
    return 2;
  }
  rtfuse::apps::NavFigure nav_figure;
  std::vector<std::uint8_t> nav_costs;
  options.at_end = [&](rtfuse::Hardware& hw) {
    rtfuse::MapperDevice* mapper = hw.find<rtfuse::MapperDevice>("mapper");
    if (mapper != nullptr && !map_out.empty()) {
      rtfuse::apps::write_mapper_files(*mapper, map_out, "rtfuse-sim: the map at the end", &map_error);
    }
    rtfuse::NavigatorDevice* nav = hw.find<rtfuse::NavigatorDevice>("planner");
    if (nav != nullptr && !nav_out.empty()) {
      const rtfuse::navigation::CostView v = nav->costmap().view();
      nav_costs.assign(v.cost, v.cost + static_cast<std::size_t>(v.width) * static_cast<std::size_t>(v.height));
      nav_figure.costs = nav_costs.data();
      nav_figure.width = v.width;
      nav_figure.height = v.height;
      nav_figure.resolution = nav->layout().resolution_m;
      nav_figure.origin_x = nav->layout().origin_x;
      nav_figure.origin_y = nav->layout().origin_y;
      const rtfuse::navigation::PathFollower& f = nav->follower();
      for (int i = 0; i < f.path_size(); ++i) nav_figure.path.push_back({f.path()[i].x, f.path()[i].y});
    }
  };
  options.trace_path = trace_path;
  SoakReport soak;
  soak.every_s = report_every;
  soak.next_s = report_every;
  rtfuse::TimeNs t0 = -1;
  std::int64_t ticks_seen = 0;
  if (report_every > 0 || !nav_out.empty()) {
    options.after_tick = [&](rtfuse::TimeNs t, const rtfuse::Snapshot& s, const rtfuse::sim::TruthState& truth) {
      if (t0 < 0) t0 = t;
      if (report_every > 0) soak.on_tick(t, t0, s, truth);
      // The driven trajectory, 20 points a second of a 200 Hz loop.
      if (!nav_out.empty() && ticks_seen++ % 10 == 0) nav_figure.driven.push_back({truth.x, truth.y});
    };
  }
  const bool tty = !quiet && isatty(STDERR_FILENO) != 0;
  const rtfuse::sim::DriveResult r =
      rtfuse::sim::run_sim_drive(cfg, options, [tty](const rtfuse::sim::DriveProgress& p) {
        if (tty) std::fprintf(stderr, "\rsim: %.0f of %.0f s\033[K", p.sim_time_s, p.duration_s);
      });
  if (soak.armed) rtfuse_alloc_probe_steady(0);
  if (tty) std::fprintf(stderr, "\n");
  if (!r.ok) {
    std::fprintf(stderr, "rtfuse-sim: %s\n", r.error.c_str());
    return 1;
  }
  if (!nav_out.empty() && nav_figure.costs != nullptr) {
    nav_figure.title = "rtfuse-sim: the costmap, the last path and the drive";
    std::string scenario_error;
    rtfuse::sim::DriveScenario scenario;
    const std::string scenario_file = scenario_path.empty() ? cfg.hardware.scenario : scenario_path;
    if (rtfuse::sim::load_drive_scenario(scenario_file, &scenario, &scenario_error)) {
      for (const rtfuse::sim::ObstacleBox& b : scenario.obstacles) {
        nav_figure.obstacles.push_back(
            {b.x - 0.5 * b.size_x, b.y - 0.5 * b.size_y, b.x + 0.5 * b.size_x, b.y + 0.5 * b.size_y});
      }
      for (const rtfuse::sim::DriveGoal& g : scenario.goals) nav_figure.goals.push_back({g.x_m, g.y_m});
    }
    char line[160];
    nav_figure.figures.push_back("# the drive");
    std::snprintf(line, sizeof line, "time        %.0f s", r.duration_s);
    nav_figure.figures.push_back(line);
    std::snprintf(line, sizeof line, "goals       %d of %zu reached", r.goals_reached, r.goals.size());
    nav_figure.figures.push_back(line);
    double worst = 0.0;
    for (const rtfuse::sim::GoalOutcome& g : r.goals) {
      if (g.reached) worst = std::max(worst, g.truth_error_m);
    }
    std::snprintf(line, sizeof line, "worst goal  %.2f m (truth)", worst);
    nav_figure.figures.push_back(line);
    std::snprintf(line, sizeof line, "closest     %.2f m to an obstacle", r.min_obstacle_distance_m);
    nav_figure.figures.push_back(line);
    std::snprintf(line, sizeof line, "plans       %lld, %lld re-plans blocked",
                  static_cast<long long>(r.final.nav.plans), static_cast<long long>(r.final.nav.replans_blocked));
    nav_figure.figures.push_back(line);
    std::snprintf(line, sizeof line, "estimate    %.2f m RMS error", r.rms_error_m);
    nav_figure.figures.push_back(line);
    std::string nav_error;
    if (!rtfuse::apps::write_nav_png(nav_figure, nav_out, &nav_error)) {
      std::fprintf(stderr, "rtfuse-sim: %s\n", nav_error.c_str());
      return 1;
    }
  }
  if (!map_error.empty()) {
    std::fprintf(stderr, "rtfuse-sim: the map's files: %s\n", map_error.c_str());
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
              "\"x\": %.4f, \"y\": %.4f, \"yaw\": %.4f, \"instances\": {",
              r.duration_s, r.ticks, r.final_error_m, r.rms_error_m, r.final_yaw_error_rad, r.max_error_m, r.max_jump_m,
              r.raw_final_error_m, r.raw_rms_error_m, s.state[0], s.state[1], s.state[5]);
  // Every instance's errors by name (the first's are the keys above too).
  for (int k = 0; k < r.num_instances; ++k) {
    const rtfuse::sim::InstanceErrors& e = r.instances[k];
    std::printf("%s\"%s\": {\"samples\": %" PRId64
                ", \"final_error_m\": %.4f, \"rms_error_m\": %.4f, \"final_yaw_error_rad\": %.4f, "
                "\"max_error_m\": %.4f, \"max_jump_m\": %.4f, \"max_map_odom_step_m\": %.4f, \"fixes_fused\": %" PRId64
                "}",
                k ? ", " : "", cfg.instances[static_cast<std::size_t>(k)].name.c_str(), e.samples, e.final_error_m,
                e.rms_error_m, e.final_yaw_error_rad, e.max_error_m, e.max_jump_m, e.max_map_odom_step_m,
                s.instances[k].fixes_fused);
  }
  std::printf("}");
  if (!r.goals.empty()) {
    // A commanded drive: what became of each goal, the true nearest
    // approach to an obstacle, and whether the base's readers agreed.
    std::printf(", \"goals_reached\": %d, \"min_obstacle_distance_m\": %.4f, \"commands\": %" PRId64
                ", \"late_commands\": %" PRId64 ", \"watchdog_stops\": %" PRId64 ", \"truth_misses\": %" PRId64
                ", \"goals\": [",
                r.goals_reached, r.min_obstacle_distance_m, r.commands, r.late_commands, r.watchdog_stops,
                r.history_misses);
    for (std::size_t i = 0; i < r.goals.size(); ++i) {
      const rtfuse::sim::GoalOutcome& g = r.goals[i];
      std::printf("%s{\"sent\": %s, \"reached\": %s, \"rejected\": %s, \"error_m\": %.4f, \"sent_s\": %.2f, "
                  "\"done_s\": %.2f, \"why\": \"%s\"}",
                  i ? ", " : "", g.sent ? "true" : "false", g.reached ? "true" : "false",
                  g.rejected ? "true" : "false", g.truth_error_m, g.sent_s, g.done_s, g.why.c_str());
    }
    std::printf("]");
    // The navigator's counters as diagnostics_t has them (plans, their
    // time, re-plans, the costmap's time).
    for (int i = 0; i < s.num_devices; ++i) {
      const rtfuse::DeviceStatus& d = s.devices[i];
      if (std::strcmp(d.name.c_str(), "navigator") != 0) continue;
      std::printf(", \"navigator\": {");
      for (int k = 0; k < d.num_values; ++k) {
        std::printf("%s\"%s\": %lld", k ? ", " : "", d.keys[k], static_cast<long long>(d.values[k]));
      }
      std::printf("}");
    }
  }
  std::printf("}\n");
  return 0;
}
