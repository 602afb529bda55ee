// The hardware layer's figures (issue 3, section 6) for docs/performance.md,
// on the bus-level simulated robot of config/sim.toml:
//
//   BM_HardwareTick            one millisecond of the 1 kHz loop through the
//                              mock HAL: the IMU thread's due data-ready
//                              edges (MPU driver) + the loop tick (CANopen
//                              SYNC and TPDOs, wheel odometry, fusion)
//   BM_ReplayTenMinuteDrive    load + replay of a recorded 10-minute drive
//                              (rtfuse-replay on a HAL recording)
//   BM_SimulateTenMinuteDrive  the same drive simulated in lockstep
//                              (rtfuse-sim), with and without recording
//
// The operator new that counts allocations is rtfuse_bench.cpp's (one per
// executable); BM_HardwareTick must report allocs_per_iter = 0.
// Nothing asserts a time; a benchmark that cannot do its job says why with
// SkipWithError.
#include <benchmark/benchmark.h>
#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "hal/mock/sim_clock.hpp"
#include "live_camera_rig.hpp"
#include "support/sim_toml.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "runtime/replay/hal_replay.hpp"
#include "runtime/devices/hardware.hpp"
#include "runtime/devices/imu/imu_device.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "sim/sim_drive.hpp"
#include "sim/sim_imu.hpp"
#include "sim/sim_robot.hpp"
#include "support/alloc_counter.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"

namespace {

namespace fs = std::filesystem;
using rtfuse::TimeNs;
using rtfuse::test::AllocScope;

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

bool read_file(const fs::path& p, std::string* text) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  *text = s.str();
  return true;
}

const fs::path kSimConfig = fs::path(RTFUSE_SOURCE_DIR) / "config" / "sim.toml";
const fs::path kDemoScenario = fs::path(RTFUSE_SOURCE_DIR) / "config" / "scenarios" / "demo.toml";

// config/sim.toml, optionally at another loop rate. Loaded under its own path
// so its relative [hardware] scenario resolves to config/scenarios/.
std::optional<rtfuse::RuntimeConfig> sim_config(const std::string& text, std::string* error) {
  rtfuse::ConfigLoadResult loaded = rtfuse::load_config_string(text, kSimConfig.string());
  if (!loaded.ok()) {
    *error = loaded.errors.empty() ? std::string("config rejected") : loaded.errors.front().to_string();
    return std::nullopt;
  }
  return std::move(loaded.config);
}

// ---------------------------------------------------------------------------
// One millisecond at 1 kHz

// 30 s of the demo drive after 1 s of warm-up: standstill, the first
// straight and arc, the wet patch at 30 s; before the encoder dropout at
// 95 s, whose node reboot is not a steady-state tick.
constexpr std::int64_t kHardwareTicks = 30'000;
constexpr int kWarmupTicks = 1'000;
constexpr TimeNs kPeriodNs = 1'000'000;

void BM_HardwareTick(benchmark::State& state) {
  std::string error;
  // The robot without its camera: camera:1 runs one beside the loop below.
  std::string text = rtfuse::test::sim_toml_text(false);
  const std::string from = "frequency = 200", to = "frequency = 1000";
  const std::size_t at = text.find(from);
  if (at == std::string::npos) {
    state.SkipWithError(("no '" + from + "' in " + kSimConfig.string() + " to raise to 1 kHz").c_str());
    return;
  }
  text.replace(at, from.size(), to);
  const std::optional<rtfuse::RuntimeConfig> cfg = sim_config(text, &error);
  if (!cfg) {
    state.SkipWithError(("config/sim.toml at 1 kHz: " + error).c_str());
    return;
  }

  // Away from 0 so no stamp is ever mistaken for "unset" (as rtfuse-sim).
  const TimeNs t0 = 1'000'000'000;
  rtfuse::hal::mock::SimClock clock(t0);
  std::unique_ptr<rtfuse::sim::SimRobot> robot = rtfuse::sim::SimRobot::create(*cfg, "", clock, t0, &error);
  std::unique_ptr<rtfuse::FusionCore> core = robot ? rtfuse::FusionCore::create(*cfg, &error) : nullptr;
  std::unique_ptr<rtfuse::Hardware> hw = core ? rtfuse::Hardware::create(robot->buses(), *core, &error) : nullptr;
  if (!hw) {
    state.SkipWithError(("set-up: " + error).c_str());
    return;
  }
  core->set_devices(hw.get());
  if (!hw->start(t0, &error)) {
    state.SkipWithError(("Hardware::start: " + error).c_str());
    return;
  }
  rtfuse::ImuDevice* imu_device = hw->find<rtfuse::ImuDevice>("imu");
  rtfuse::sim::SimImu* sim_imu = robot->device<rtfuse::sim::SimImu>("imu");
  if (imu_device == nullptr || sim_imu == nullptr) {
    state.SkipWithError("config/sim.toml runs no IMU driver: the benchmark would measure the encoders only");
    return;
  }

  rtfuse::LoopStats loop;
  loop.rate_hz = 1000.0;
  loop.period_ns = kPeriodNs;
  TimeNs t = t0;
  // What the IMU thread and the loop thread do in one period, in lockstep as
  // run_sim_drive does: the data-ready edges due by the tick, then the
  // tick (SYNC, TPDOs, wheel odometry, drain, fusion, snapshot).
  auto one_period = [&]() {
    t += kPeriodNs;
    clock.set(t);
    for (int k = 0; k < 64 && sim_imu->next_edge_time() <= t; ++k) imu_device->step_imu(rtfuse::kDeviceStepTimeoutNs);
    clock.set(t);
    ++loop.ticks;
    core->tick(t, loop);
  };
  for (int i = 0; i < kWarmupTicks; ++i) one_period();

  // camera:1 runs a camera thread beside the loop (on the other core, as on
  // a robot): the tick must not get slower because of it. The lockstep ticks
  // of one run take ~0.1 s, in which a 30 fps camera would deliver three
  // frames; so the camera here captures every millisecond, keeping its
  // thread about half busy with VGA pairs for the whole run (a harsher
  // neighbour than a real 30 fps camera).
  std::unique_ptr<rtfuse::bench::LiveCameraRig> camera;
  std::atomic<bool> camera_running{true};
  std::thread camera_thread;
  if (state.range(0) != 0) {
    camera = rtfuse::bench::LiveCameraRig::create(std::string(RTFUSE_SOURCE_DIR) + "/config/calibration/SN10000001.conf",
                                                  &error, 1'000'000);
    if (!camera) {
      state.SkipWithError(("camera: " + error).c_str());
      return;
    }
    camera_thread = std::thread([&camera, &camera_running]() {
      rtfuse::drivers::StereoFrameResult r;
      while (camera_running.load(std::memory_order_relaxed)) camera->camera().step(50'000'000, &r);
    });
  }
  const rtfuse::Snapshot s0 = core->last_snapshot();
  const std::int64_t imu0 = imu_device->samples();
  // Per-iteration durations, sized before the timed loop.
  std::vector<std::int64_t> durations(static_cast<std::size_t>(state.max_iterations), 0);
  std::size_t n = 0;
  std::size_t allocations = 0;
  {
    AllocScope allocs;
    for (auto _ : state) {
      const Clock::time_point a = Clock::now();
      one_period();
      const Clock::time_point b = Clock::now();
      if (n < durations.size()) durations[n++] = std::chrono::duration_cast<std::chrono::nanoseconds>(b - a).count();
      benchmark::ClobberMemory();
    }
    allocations = allocs.count();
  }
  camera_running.store(false);
  if (camera_thread.joinable()) camera_thread.join();
  if (camera) state.counters["camera_frames"] = static_cast<double>(camera->camera().stats().rectified);
  const rtfuse::Snapshot& s1 = core->last_snapshot();

  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocations), benchmark::Counter::kAvgIterations);
  if (n > 0) {
    durations.resize(n);
    double sum = 0.0;
    for (std::int64_t d : durations) sum += static_cast<double>(d);
    const double mean_ns = sum / static_cast<double>(n);
    std::sort(durations.begin(), durations.end());
    const std::size_t p99 = (n * 99 + 99) / 100 - 1;  // nearest rank
    state.counters["tick_median_us"] = static_cast<double>(durations[n / 2]) * 1e-3;
    state.counters["tick_p99_us"] = static_cast<double>(durations[p99]) * 1e-3;
    state.counters["tick_max_us"] = static_cast<double>(durations.back()) * 1e-3;
    state.counters["core_share_at_1kHz"] = mean_ns / static_cast<double>(kPeriodNs);
  }
  // The work measured must be the real one: wheel twists and IMU samples
  // fused at their rates (1 kHz and 200 Hz).
  const std::int64_t wheels = s1.sensors[0].accepted - s0.sensors[0].accepted;
  const std::int64_t imu = s1.sensors[1].accepted - s0.sensors[1].accepted;
  const double iters = static_cast<double>(state.iterations());
  state.counters["wheel_per_iter"] = static_cast<double>(wheels) / iters;
  state.counters["imu_per_iter"] = static_cast<double>(imu) / iters;
  const std::int64_t imu_read = imu_device->samples() - imu0;
  if (!s1.initialized) {
    state.SkipWithError("the filter never initialised");
  } else if (wheels < state.iterations() * 9 / 10 || imu < state.iterations() / 5 * 9 / 10 ||
             imu_read < state.iterations() / 5 * 9 / 10) {
    std::ostringstream why;
    why << "expected ~1 wheel twist and ~0.2 IMU samples fused per tick, got " << wheels << " and " << imu
        << " in " << state.iterations() << " ticks (IMU samples read " << imu_read << ")";
    state.SkipWithError(why.str().c_str());
  }
}
BENCHMARK(BM_HardwareTick)->ArgName("camera")->Arg(0)->Arg(1)->Iterations(kHardwareTicks)->Unit(benchmark::kMicrosecond);

// ---------------------------------------------------------------------------
// A 10-minute drive: simulated and recorded once, replayed per iteration

constexpr double kTenMinutes = 600.0;

// The demo drive's path (190.8 s) three times over, then standing still up
// to 600 s: same robot, slip, dropout and IMU as the live demo.
bool ten_minute_scenario(std::string* text, std::string* error) {
  if (!read_file(kDemoScenario, text)) {
    *error = "cannot read " + kDemoScenario.string();
    return false;
  }
  const std::string duration = "\nduration_s = 200.0\n";
  const std::size_t d = text->find(duration);
  const std::size_t first = text->find("\n[[path]]\n");
  const std::size_t robot = text->find("\n[robot]\n");
  if (d == std::string::npos || first == std::string::npos || robot == std::string::npos || robot < first) {
    *error = kDemoScenario.string() + " no longer has 'duration_s = 200.0', [[path]] entries and then [robot]";
    return false;
  }
  const std::string path = text->substr(first, robot - first);
  text->insert(robot, path + path);
  text->replace(d, duration.size(), "\nduration_s = 600.0\n");
  return true;
}

struct TenMinuteDrive {
  bool ok = false;
  std::string error;
  fs::path dir;
  std::string scenario_path;
  std::string record_path;
  std::string config_text;  // config/sim.toml, 200 Hz, as recorded
  std::optional<rtfuse::RuntimeConfig> config;
  double sim_s = 0.0;
  std::int64_t ticks = 0;
  double record_mb = 0.0;

  TenMinuteDrive() = default;
  TenMinuteDrive(const TenMinuteDrive&) = delete;
  TenMinuteDrive& operator=(const TenMinuteDrive&) = delete;
  ~TenMinuteDrive() {
    std::error_code ec;
    if (!dir.empty()) fs::remove_all(dir, ec);
  }
};

void make_ten_minute_drive(TenMinuteDrive& r) {
  std::string scenario;
  if (!ten_minute_scenario(&scenario, &r.error)) return;
  // Without the camera: these figures are the encoders', the IMU's and the
  // filter's (a ten-minute recording with frames would hold 18 GB).
  r.config_text = rtfuse::test::sim_toml_text(false);
  r.config = sim_config(r.config_text, &r.error);
  if (!r.config) return;
  std::string tmpl = (fs::temp_directory_path() / "rtfuse_hw_bench.XXXXXX").string();
  if (mkdtemp(tmpl.data()) == nullptr) {
    r.error = "mkdtemp failed for " + tmpl;
    return;
  }
  r.dir = tmpl;
  r.scenario_path = (r.dir / "ten_minutes.toml").string();
  r.record_path = (r.dir / "ten_minutes.lcm").string();
  {
    std::ofstream out(r.scenario_path, std::ios::binary);
    out << scenario;
    if (!out) {
      r.error = "cannot write " + r.scenario_path;
      return;
    }
  }
  rtfuse::sim::DriveOptions options;
  options.scenario_path = r.scenario_path;
  options.record_path = r.record_path;
  options.config_text = r.config_text;
  const rtfuse::sim::DriveResult d = rtfuse::sim::run_sim_drive(*r.config, options, {});
  if (!d.ok) {
    r.error = "recording the drive: " + d.error;
    return;
  }
  if (d.recording_lost > 0) {
    r.error = "the recorder lost " + std::to_string(d.recording_lost) + " bus events";
    return;
  }
  r.sim_s = d.duration_s;
  r.ticks = d.ticks;
  std::error_code ec;
  r.record_mb = static_cast<double>(fs::file_size(r.record_path, ec)) / 1e6;
  r.ok = true;
}

const TenMinuteDrive& ten_minute_drive() {
  static TenMinuteDrive d;
  static const bool made = (make_ten_minute_drive(d), true);
  (void)made;
  return d;
}

// rtfuse-replay on the recording: load it whole, parse its config, replay
// through the drivers checking every bus call and every estimate output.
void BM_ReplayTenMinuteDrive(benchmark::State& state) {
  const TenMinuteDrive& drive = ten_minute_drive();
  if (!drive.ok) {
    state.SkipWithError(("10-minute drive: " + drive.error).c_str());
    return;
  }
  double load_s = 0.0, replay_s = 0.0, total_s = 0.0;
  std::int64_t events = 0, ticks = 0, compared = 0;
  for (auto _ : state) {
    const Clock::time_point start = Clock::now();
    {
      rtfuse::transport::EventLogReader in;
      rtfuse::HalRecording rec;
      std::string error;
      if (!in.open(drive.record_path, &error) ||
          !rtfuse::load_hal_recording(in, rtfuse::HalRecordingOptions{}, &rec, &error)) {
        state.SkipWithError(("loading the recording: " + error).c_str());
        break;
      }
      load_s += seconds_since(start);
      const Clock::time_point replay_start = Clock::now();
      const rtfuse::ConfigLoadResult loaded = rtfuse::load_config_string(rec.info.config_text, rec.info.config_path);
      if (!loaded.ok()) {
        state.SkipWithError("the recording's config does not load");
        break;
      }
      const rtfuse::HalReplayResult r = rtfuse::replay_hal_recording(rec, *loaded.config, nullptr, {});
      replay_s += seconds_since(replay_start);
      if (!r.ok || !r.first_mismatch.empty() || r.compared == 0 || r.identical != r.compared ||
          r.ticks != drive.ticks) {
        state.SkipWithError(("the replay does not reproduce the drive: " + r.error + r.first_mismatch).c_str());
        break;
      }
      events = rec.events;
      ticks = r.ticks;
      compared = r.compared;
    }  // the recording is freed inside the timing, as rtfuse-replay does before it exits
    const double iteration_s = seconds_since(start);
    total_s += iteration_s;
    state.SetIterationTime(iteration_s);
    // Give the freed recording back to the kernel, so every iteration pays
    // the page faults of a fresh rtfuse-replay process (a warm heap makes
    // loading ~2.5x faster than any real run).
    malloc_trim(0);
  }
  const double iters = static_cast<double>(state.iterations());
  if (state.iterations() > 0 && total_s > 0.0) {
    state.counters["x_real_time"] = drive.sim_s / (total_s / iters);
    state.counters["load_s"] = load_s / iters;
    state.counters["replay_s"] = replay_s / iters;
    state.counters["free_s"] = (total_s - load_s - replay_s) / iters;
  }
  state.counters["sim_s"] = drive.sim_s;
  state.counters["record_MB"] = drive.record_mb;
  state.counters["events"] = static_cast<double>(events);
  state.counters["ticks"] = static_cast<double>(ticks);
  state.counters["outputs_compared"] = static_cast<double>(compared);
}
BENCHMARK(BM_ReplayTenMinuteDrive)->Iterations(1)->Unit(benchmark::kMillisecond)->UseManualTime();

// rtfuse-sim on the same scenario: scenario load, lockstep drive, and (arg 1)
// the HAL recording written to a file as the replay above reads it.
void BM_SimulateTenMinuteDrive(benchmark::State& state) {
  const TenMinuteDrive& drive = ten_minute_drive();
  if (!drive.ok) {
    state.SkipWithError(("10-minute drive: " + drive.error).c_str());
    return;
  }
  rtfuse::sim::DriveOptions options;
  options.scenario_path = drive.scenario_path;
  options.config_text = drive.config_text;
  if (state.range(0) != 0) options.record_path = (drive.dir / "simulate.lcm").string();
  double total_s = 0.0, sim_s = 0.0;
  for (auto _ : state) {
    const Clock::time_point start = Clock::now();
    const rtfuse::sim::DriveResult d = rtfuse::sim::run_sim_drive(*drive.config, options, {});
    total_s += seconds_since(start);
    if (!d.ok || d.recording_lost > 0) {
      state.SkipWithError(("the drive failed: " + d.error).c_str());
      break;
    }
    sim_s = d.duration_s;
  }
  if (state.iterations() > 0 && total_s > 0.0) {
    state.counters["x_real_time"] = sim_s / (total_s / static_cast<double>(state.iterations()));
  }
  state.counters["sim_s"] = sim_s;
  if (!options.record_path.empty()) {
    std::error_code ec;
    fs::remove(options.record_path, ec);
  }
}
BENCHMARK(BM_SimulateTenMinuteDrive)
    ->ArgName("record")
    ->Arg(0)
    ->Arg(1)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
