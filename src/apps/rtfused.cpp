// rtfused: the live daemon. Loads the config (the embedded config/sim.toml by
// default), opens the buses its drivers need (the kernel's with
// [hardware] backend = "linux", the bus-level simulated robot with "sim"),
// starts the runtime, and with --record writes a HAL recording. With the
// simulated robot it publishes ground truth and reports the error against it.
// The older LCM-level simulated robot ([sim] enabled, config/sim_lcm.toml)
// publishes sensor messages on the input channels instead.
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "apps/command_line.hpp"
#include "apps/mapper_files.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "mapping/map_digest.hpp"
#include "runtime/devices/mapper/mapper_device.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/devices/device_registry.hpp"
#include "runtime/devices/linux_hal.hpp"
#include "runtime/live/loop_timer.hpp"
#include "runtime/live/realtime.hpp"
#include "runtime/live/runtime.hpp"
#include "rtfuse/twist_stamped_t.hpp"
#include "sim/goal_sequence.hpp"
#include "sim/ground_truth.hpp"
#include "sim/sim_lcm_robot.hpp"
#include "sim/sim_robot.hpp"

#ifndef RTFUSE_VERSION  // set by src/apps/CMakeLists.txt from project(VERSION)
#define RTFUSE_VERSION "unknown"
#endif

namespace rtfuse::apps {
extern const std::string_view kEmbeddedSimConfig;
extern const std::string_view kEmbeddedDemoScenario;
extern const std::string_view kEmbeddedCameraCalibration;
}

// Optional hook for the allocation probe (tests/system/alloc_probe.c, loaded
// with LD_PRELOAD): told when start-up is over and when shutdown begins.
extern "C" void rtfuse_alloc_probe_steady(int steady) __attribute__((weak));

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }

void sim_thread(rtfuse::sim::SimLcmRobot* sim, rtfuse::transport::LcmNode* lcm, std::atomic<bool>* run) {
  rtfuse::name_this_thread("rtfuse-sim");
  rtfuse::sim::SimMessage msg;
  while (run->load(std::memory_order_relaxed)) {
    // Sleep in short slices so a stop is noticed even between messages.
    const rtfuse::TimeNs now = rtfuse::monotonic_now_ns();
    const rtfuse::TimeNs next = std::min(sim->next_time(), now + 20'000'000);
    rtfuse::sleep_until(next);
    while (sim->next_due(rtfuse::monotonic_now_ns(), &msg)) lcm->publish(msg.channel, msg.data, msg.size);
  }
}

// A commanded simulated base hears rtfuse/cmd_vel as a robot's base would:
// on the LCM thread, into its command feed, issued when it arrived.
struct CommandListener {
  rtfuse::sim::SimRobot* robot = nullptr;
  rtfuse::twist_stamped_t msg{};  // kept: decoding reuses its string's capacity
};

void on_cmd_vel(const char*, const std::uint8_t* data, int size, std::int64_t, void* user) {
  auto* c = static_cast<CommandListener*>(user);
  if (c->msg.decode(data, 0, size) != size) return;
  c->robot->commands().push({rtfuse::monotonic_now_ns(), c->msg.twist.linear.x, c->msg.twist.angular.z});
}

// Ground truth of the bus-level simulated robot onto LCM, at 50 Hz; a
// commanded robot's through a truth reader of this thread's own.
void truth_thread(rtfuse::sim::SimRobot* robot, rtfuse::transport::LcmNode* lcm, std::atomic<bool>* run) {
  rtfuse::name_this_thread("rtfuse-sim");
  std::unique_ptr<rtfuse::sim::CommandedTruth> reader = robot->make_truth_reader();
  rtfuse::sim::GroundTruthEncoder encoder;
  rtfuse::TimeNs next = rtfuse::monotonic_now_ns();
  while (run->load(std::memory_order_relaxed)) {
    next += 20'000'000;
    rtfuse::sleep_until(next);
    int size = 0;
    const rtfuse::sim::TruthState truth =
        reader ? reader->truth_at(rtfuse::ns_to_sec(next - robot->start_time())) : robot->truth_at(next);
    const std::uint8_t* bytes = encoder.encode(truth, next, &size);
    if (size > 0) lcm->publish(rtfuse::sim::kGroundTruthChannel, bytes, size);
  }
}


}  // namespace

int main(int argc, char** argv) {
  rtfuse::apps::CommandLine cli{"rtfused: real-time EKF sensor fusion daemon (LCM in, LCM out)"};
  std::string config_path;
  double duration = 0.0;
  std::string lcm_url;
  bool quiet = false;
  cli.version_flag("--version", "rtfused " RTFUSE_VERSION);
  cli.option("-c,--config", &config_path, "TOML config (default: the embedded config/sim.toml)");
  cli.option("-d,--duration", &duration, "stop after this many seconds (0: run until SIGINT/SIGTERM)")
      .non_negative();
  cli.option("--lcm-url", &lcm_url, "override [lcm] url");
  cli.flag("-q,--quiet", &quiet, "no live status line");
  std::string record_path;
  cli.option("--record", &record_path,
                 "write every bus event, loop tick and output to this LCM log (replay it with rtfuse-replay)");
  std::string map_out;
  cli.option("--map-out", &map_out,
                 "with [mapping]: write the map at exit to PREFIX.bt, PREFIX.pgm + .yaml and PREFIX.png "
                 "(overrides [mapping] output)");
  if (const auto exit = cli.parse(argc, argv)) return *exit;

  std::string config_text(rtfuse::apps::kEmbeddedSimConfig);
  if (!config_path.empty()) {
    config_text.clear();
    int err = 0;
    if (!rtfuse::read_text_file(config_path, &config_text, &err)) {
      std::fprintf(stderr, "rtfused: %s: cannot read: %s\n", config_path.c_str(), std::strerror(err));
      return 2;
    }
  }
  rtfuse::ConfigLoadResult loaded = rtfuse::load_config_string(
      config_text, config_path.empty() ? std::string("<embedded config/sim.toml>") : config_path);
  if (!loaded.config) {
    for (const auto& e : loaded.errors) std::fprintf(stderr, "%s\n", e.to_string().c_str());
    return 2;
  }
  rtfuse::RuntimeConfig cfg = *loaded.config;
  if (!lcm_url.empty()) cfg.lcm_url = lcm_url;
  if (!map_out.empty()) {
    if (!cfg.hardware.mapping.enabled) {
      std::fprintf(stderr, "rtfused: --map-out needs a [mapping] section in %s\n", cfg.source.c_str());
      return 2;
    }
    cfg.hardware.mapping.output = map_out;
  }
  // The embedded config's camera is the one of the embedded calibration.
  if (config_path.empty() && cfg.hardware.camera.enabled) {
    cfg.hardware.camera.calibration_text = rtfuse::apps::kEmbeddedCameraCalibration;
  }
  // The files the devices name are read here, once, so a missing one stops
  // before anything runs.
  for (int i = 0; i < rtfuse::device_type_count(); ++i) {
    const rtfuse::DeviceDescriptor& d = rtfuse::device_type(i);
    std::string why;
    if (d.enabled(cfg) && !d.prepare(cfg, &why)) {
      std::fprintf(stderr, "rtfused: %s\n", why.c_str());
      return 2;
    }
  }

  std::string error;
  rtfuse::HalBuses buses;
  std::unique_ptr<rtfuse::LinuxHal> linux_hal;
  rtfuse::hal::MonotonicClock clock;
  std::unique_ptr<rtfuse::sim::SimRobot> robot;
  if (cfg.hardware.backend == rtfuse::HalBackend::kLinux) {
    linux_hal = rtfuse::LinuxHal::open(cfg, &error);
    if (!linux_hal) {
      std::fprintf(stderr, "rtfused: %s\n", error.c_str());
      return 1;
    }
    buses = linux_hal->buses();
    const std::string lines = linux_hal->describe();
    for (std::size_t at = 0, nl; (nl = lines.find('\n', at)) != std::string::npos; at = nl + 1) {
      std::fprintf(stderr, "rtfused: %s\n", lines.substr(at, nl - at).c_str());
    }
  } else if (cfg.hardware.backend == rtfuse::HalBackend::kSim) {
    // The embedded config's scenario is the embedded demo drive.
    const std::string_view demo = rtfuse::apps::kEmbeddedDemoScenario;
    const bool embedded = config_path.empty();
    robot = rtfuse::sim::SimRobot::create(cfg, embedded ? "<embedded config/scenarios/demo.toml>" : "",
                                                clock, rtfuse::monotonic_now_ns(), &error,
                                                embedded ? &demo : nullptr);
    if (!robot) {
      std::fprintf(stderr, "rtfused: %s\n", error.c_str());
      return 2;
    }
    buses = robot->buses();
  }
  auto runtime = rtfuse::Runtime::create(cfg, buses, record_path, config_text, &error);
  if (!runtime) {
    std::fprintf(stderr, "rtfused: %s\n", error.c_str());
    return 1;
  }
  std::unique_ptr<rtfuse::sim::SimLcmRobot> sim;
  if (cfg.sim.enabled) sim = std::make_unique<rtfuse::sim::SimLcmRobot>(cfg.sim, rtfuse::monotonic_now_ns());

  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  std::string warnings;
  if (!runtime->start(&error, &warnings)) {
    std::fprintf(stderr, "rtfused: %s\n", error.c_str());
    return 3;
  }
  if (!warnings.empty()) std::fprintf(stderr, "rtfused: warning: %s", warnings.c_str());
  std::fprintf(stderr, "rtfused: %s, loop %.0f Hz, %d sensors, LCM %s%s%s%s\n", cfg.source.c_str(), cfg.rate_hz,
               cfg.num_sensors, cfg.lcm_url.c_str(),
               sim ? ", LCM-level simulated robot" : "", robot ? ", bus-level simulated robot" : "",
               record_path.empty() ? "" : (", recording to " + record_path).c_str());

  // A commanded drive: the base follows rtfuse/cmd_vel, and the scenario's
  // goals go out on the goal channel one after the other, as an operator
  // would send them.
  CommandListener listener;
  std::unique_ptr<rtfuse::sim::GoalSequence> goals;
  if (robot && robot->commanded()) {
    listener.robot = robot.get();
    listener.msg.header.frame_id.reserve(256);
    if (!runtime->lcm().subscribe(cfg.hardware.navigation.cmd_vel_channel.c_str(), on_cmd_vel, &listener)) {
      std::fprintf(stderr, "rtfused: cannot subscribe to %s\n", cfg.hardware.navigation.cmd_vel_channel.c_str());
      return 1;
    }
    goals = std::make_unique<rtfuse::sim::GoalSequence>(robot->goals(), robot->start_time());
  }

  std::atomic<bool> sim_run{true};
  std::thread sim_worker;
  if (sim) sim_worker = std::thread(sim_thread, sim.get(), &runtime->lcm(), &sim_run);
  if (robot) sim_worker = std::thread(truth_thread, robot.get(), &runtime->lcm(), &sim_run);

  const bool tty = isatty(STDERR_FILENO) != 0;
  const rtfuse::TimeNs start = rtfuse::monotonic_now_ns();
  const rtfuse::TimeNs end = duration > 0 ? start + rtfuse::sec_to_ns(duration) : INT64_MAX;
  rtfuse::TimeNs next_status = start;
  rtfuse::TimeNs next_sample = start;
  bool probe_armed = false;
  double err_sq_sum = 0.0;
  long err_samples = 0;
  double last_error = NAN;
  double instance_error[rtfuse::kMaxInstances] = {};
  double instance_sq_sum[rtfuse::kMaxInstances] = {};
  long instance_samples[rtfuse::kMaxInstances] = {};
  rtfuse::Snapshot s;
  bool recording_failure_said = false;

  while (!g_stop.load() && rtfuse::monotonic_now_ns() < end) {
    rtfuse::sleep_until(std::min(end, next_sample));
    const rtfuse::TimeNs now = rtfuse::monotonic_now_ns();
    if (!probe_armed && rtfuse_alloc_probe_steady && now - start > 1'000'000'000) {
      rtfuse_alloc_probe_steady(1);
      probe_armed = true;
    }
    if (now < next_sample) continue;
    next_sample = now + 100'000'000;
    s = runtime->latest();
    // Said when it happens (the journal of a service), not only at exit;
    // allocates once, on the failure.
    if (!recording_failure_said && runtime->recording() != nullptr && runtime->recording()->recorder().failed()) {
      std::string why;
      runtime->recording()->recorder().failed(&why);
      std::fprintf(stderr,
                   "rtfused: recording %s failed at %.1f s: %s; the loop runs on, the recording is cut there "
                   "(rtfuse-replay --allow-truncated)\n",
                   record_path.c_str(), rtfuse::ns_to_sec(now - start), why.c_str());
      recording_failure_said = true;
    }
    rtfuse::sim::DriveGoal goal;
    if (goals && goals->step(now, s.initialized, s.nav, robot->truth_at(now), &goal)) {
      const std::vector<std::uint8_t> b = rtfuse::sim::encode_goal(goal, cfg.world_frame.c_str(), now);
      runtime->lcm().publish(cfg.hardware.navigation.goal_channel.c_str(), b.data(), static_cast<int>(b.size()));
      std::fprintf(stderr, "%srtfused: goal %d of %zu: (%.2f, %.2f)\n", tty && !quiet ? "\n" : "", goals->current() + 1,
                   robot->goals().size(), goal.x_m, goal.y_m);
    }
    if ((sim || robot) && s.initialized) {
      double tx = 0.0, ty = 0.0;
      if (sim) {
        const rtfuse::sim::TruthPose truth = sim->truth(s.stamp_ns);
        tx = truth.x;
        ty = truth.y;
      } else {
        const rtfuse::sim::TruthState truth = robot->truth_at(s.stamp_ns);
        tx = truth.x;
        ty = truth.y;
      }
      last_error = std::hypot(s.state[0] - tx, s.state[1] - ty);
      err_sq_sum += last_error * last_error;
      ++err_samples;
      // Every further instance once it publishes (a map instance: after
      // its first fix), against the same truth at its own stamp.
      for (int k = 1; robot && k < s.num_instances; ++k) {
        const rtfuse::InstanceSnapshot& in = s.instances[k];
        if (!in.initialized || in.awaiting_fix) continue;
        const rtfuse::sim::TruthState truth = robot->truth_at(in.stamp_ns);
        instance_error[k] = std::hypot(in.state[0] - truth.x, in.state[1] - truth.y);
        instance_sq_sum[k] += instance_error[k] * instance_error[k];
        ++instance_samples[k];
      }
    }
    if (quiet || now < next_status) continue;
    next_status = now + (tty ? 250'000'000 : 5'000'000'000);
    char err_text[32] = "";
    if (!std::isnan(last_error)) std::snprintf(err_text, sizeof(err_text), " | err %.3f m", last_error);
    // The rate of every device that measures one (the camera's, from its capture stamps).
    char rates[96] = "";
    for (int i = 0, at = 0; i < s.num_devices; ++i) {
      const rtfuse::DeviceStatus& d = s.devices[i];
      for (int k = 0; k < d.num_values && at < static_cast<int>(sizeof rates); ++k) {
        if (std::strcmp(d.keys[k], "fps_milli") != 0) continue;
        at += std::snprintf(rates + at, sizeof rates - static_cast<std::size_t>(at), " | %s %.1f fps", d.name.c_str(),
                            static_cast<double>(d.values[k]) / 1000.0);
      }
    }
    // The map growing: keyframes, their rate, known and occupied voxels.
    char map_text[96] = "";
    for (int i = 0; i < s.num_devices; ++i) {
      const rtfuse::DeviceStatus& d = s.devices[i];
      if (std::strcmp(d.name.c_str(), "mapper") != 0) continue;
      long long v[4] = {};
      const char* keys[4] = {"inserted", "rate_milli", "known", "occupied"};
      for (int k = 0; k < d.num_values; ++k) {
        for (int j = 0; j < 4; ++j) {
          if (std::strcmp(d.keys[k], keys[j]) == 0) v[j] = d.values[k];
        }
      }
      std::snprintf(map_text, sizeof map_text, " | map %lld kf %.1f/s %.0fk vox %.0fk occ", v[0], v[1] / 1000.0,
                    static_cast<double>(v[2]) / 1e3, static_cast<double>(v[3]) / 1e3);
    }
    char line[400];
    std::snprintf(line, sizeof(line),
                  "t=%6.1fs loop %.0f Hz overruns %lld jitter max %.0f us | x %.2f y %.2f yaw %.2f | fused %lld%s%s%s",
                  rtfuse::ns_to_sec(now - start), s.loop.rate_hz, static_cast<long long>(s.loop.overruns),
                  s.loop.jitter_max_ns / 1e3, s.state[0], s.state[1], s.state[5],
                  static_cast<long long>(s.loop.measurements_fused), rates, map_text, err_text);
    std::fprintf(stderr, tty ? "\r%s\033[K" : "%s\n", line);
  }
  if (probe_armed) rtfuse_alloc_probe_steady(0);
  if (tty && !quiet) std::fprintf(stderr, "\n");

  sim_run.store(false);
  if (sim_worker.joinable()) sim_worker.join();
  const bool recorded = runtime->stop(&error);
  s = runtime->latest();
  std::printf("rtfused: ran %.1f s, %lld ticks, %lld overruns, %lld measurements fused\n",
              rtfuse::ns_to_sec(rtfuse::monotonic_now_ns() - start), static_cast<long long>(s.loop.ticks),
              static_cast<long long>(s.loop.overruns), static_cast<long long>(s.loop.measurements_fused));
  for (int i = 0; i < s.num_devices; ++i) {
    const rtfuse::DeviceStatus& d = s.devices[i];
    std::printf("rtfused: device %s (%s): %s", d.name.c_str(), d.hardware_id.c_str(), d.state.c_str());
    for (int k = 0; k < d.num_values; ++k) std::printf(", %s %lld", d.keys[k], static_cast<long long>(d.values[k]));
    if (!d.message.empty()) std::printf("; last error: %s", d.message.c_str());
    std::printf("\n");
  }
  if (goals) {
    int i = 0;
    for (const rtfuse::sim::GoalOutcome& g : goals->outcomes()) {
      ++i;
      if (!g.sent) continue;
      if (!g.reached && !g.rejected) {  // no outcome yet: no distance was taken
        std::printf("rtfused: goal %d: still driving to it at exit (sent at %.1f s)\n", i, g.sent_s);
        continue;
      }
      std::printf("rtfused: goal %d: %s, %.3f m from it (truth)%s%s\n", i, g.reached ? "reached" : "refused",
                  g.truth_error_m, g.why.empty() ? "" : ": ", g.why.c_str());
    }
  }
  if ((sim || robot) && err_samples > 0) {
    std::printf("rtfused: position error against ground truth: final %.3f m, RMS %.3f m over %ld samples\n",
                last_error, std::sqrt(err_sq_sum / err_samples), err_samples);
  }
  for (int k = 1; k < s.num_instances; ++k) {
    if (instance_samples[k] == 0) continue;
    std::printf("rtfused: instance %s: position error against ground truth: final %.3f m, RMS %.3f m over %ld "
                "samples\n",
                cfg.instances[static_cast<std::size_t>(k)].name.c_str(), instance_error[k],
                std::sqrt(instance_sq_sum[k] / static_cast<double>(instance_samples[k])), instance_samples[k]);
  }
  rtfuse::MapperDevice* mapper =
      runtime->hardware() != nullptr ? runtime->hardware()->find<rtfuse::MapperDevice>("mapper") : nullptr;
  if (mapper != nullptr && !cfg.hardware.mapping.output.empty()) {
    const std::string& prefix = cfg.hardware.mapping.output;
    if (!rtfuse::apps::write_mapper_files(*mapper, prefix, "rtfused: the map at exit", &error)) {
      std::fprintf(stderr, "rtfused: the map's files: %s\n", error.c_str());
      return 1;
    }
    std::printf("rtfused: map written to %s.bt, %s.pgm + %s.yaml and %s.png\n", prefix.c_str(), prefix.c_str(),
                prefix.c_str(), prefix.c_str());
  }
  if (!record_path.empty()) {
    if (!recorded) {
      std::fprintf(stderr, "rtfused: recording %s: %s\n", record_path.c_str(), error.c_str());
      return 1;
    }
    std::printf("rtfused: recorded to %s (replay: rtfuse-replay -l %s)\n", record_path.c_str(), record_path.c_str());
  }
  return 0;
}
