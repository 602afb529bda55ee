// The running daemon's input path: config/sim.toml's simulated robot with
// every sensor (encoders over CAN, the MPU over I2C, the stereo camera and
// its visual odometry) and the loop, publisher and LCM threads of rtfused,
// plus one LCM sensor of each type, a global filter instance in map fusing
// three of them again (shared inputs, map -> odom) and set_pose accepted. Each input is one
// message, published on memq:// to the daemon's own LCM node while it runs:
// the first byte picks the channel (odometry, pose, twist, IMU, set_pose,
// navsat fix, as in sample_decoder_fuzz.cpp, whose seeds serve here; then
// the navigator's goal and stop), the rest is the bytes. The navigator runs
// with follow = true on the mapper's grid.
// Property: no crash or sanitizer report in any thread, every published
// odometry and pose finite, every velocity command finite and within the
// configured limits, and the daemon still publishing at the end.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>

#include "fuzz_check.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "rtfuse/odometry_t.hpp"
#include "rtfuse/twist_stamped_t.hpp"
#include "rtfuse/pose_with_covariance_stamped_t.hpp"
#include "runtime/devices/camera/camera_calibration.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/live/runtime.hpp"
#include "sim/sim_robot.hpp"

namespace {

constexpr const char* kChannels[] = {"fuzz/odometry", "fuzz/pose", "fuzz/twist", "fuzz/imu", "rtfuse/set_pose",
                                     "fuzz/navsat", "rtfuse/goal", "rtfuse/stop"};
constexpr int kNumChannels = sizeof(kChannels) / sizeof(kChannels[0]);

// Every kind of LCM sensor, each fusing what its type provides.
constexpr const char* kFuzzSensors = R"(
[[sensor]]
name = "fuzz_odometry"
type = "odometry"
channel = "fuzz/odometry"
config = [true, true, false, false, false, true, true, true, false, false, false, true, false, false, false]

[[sensor]]
name = "fuzz_pose"
type = "pose"
channel = "fuzz/pose"
config = [true, true, true, true, true, true, false, false, false, false, false, false, false, false, false]

[[sensor]]
name = "fuzz_twist"
type = "twist"
channel = "fuzz/twist"
config = [false, false, false, false, false, false, true, true, true, true, true, true, false, false, false]

[[sensor]]
name = "fuzz_imu"
type = "imu"
channel = "fuzz/imu"
config = [false, false, false, true, true, true, false, false, false, true, true, true, true, true, true]

[[sensor]]
name = "fuzz_navsat"
type = "navsat"
channel = "fuzz/navsat"
config = [true, true, true, false, false, false, false, false, false, false, false, false, false, false, false]
heading_imu = "fuzz_imu"
)";

// A global instance in map (robot_localization's dual EKF) on the same
// inputs: the shared rings fused twice, map -> odom from both estimates.
constexpr const char* kGlobalInstance = R"(
[[instance]]
name = "global"
world_frame = "map"

[[instance.sensor]]
name = "fuzz_odometry"
type = "odometry"
channel = "fuzz/odometry"
config = [false, false, false, false, false, false, true, true, false, false, false, true, false, false, false]

[[instance.sensor]]
name = "fuzz_imu"
type = "imu"
channel = "fuzz/imu"
config = [false, false, false, true, true, true, false, false, false, true, true, true, false, false, false]

[[instance.sensor]]
name = "fuzz_navsat"
type = "navsat"
channel = "fuzz/navsat"
config = [true, true, false, false, false, false, false, false, false, false, false, false, false, false, false]
heading_imu = "fuzz_imu"
pose_rejection_threshold = 5.0
)";

struct Daemon {
  rtfuse::RuntimeConfig cfg;  // what the robot and the runtime were made from, kept as rtfused keeps it
  rtfuse::hal::MonotonicClock clock;
  std::unique_ptr<rtfuse::sim::SimRobot> robot;
  std::unique_ptr<rtfuse::Runtime> runtime;
  std::atomic<std::int64_t> handled{0};  // input messages the LCM thread has dispatched
  std::atomic<std::int64_t> outputs{0};  // odometry and pose messages checked
  std::atomic<std::int64_t> commands{0};  // velocity commands checked
  std::int64_t published = 0;
};

Daemon* g_daemon = nullptr;  // lives until exit: its threads run to the end

void count_input(const char*, const std::uint8_t*, int, std::int64_t, void* user) {
  static_cast<Daemon*>(user)->handled.fetch_add(1, std::memory_order_relaxed);
}

bool finite(const rtfuse::pose_with_covariance_t& p) {
  const auto& q = p.pose;
  bool ok = std::isfinite(q.position.x) && std::isfinite(q.position.y) && std::isfinite(q.position.z) &&
            std::isfinite(q.orientation.x) && std::isfinite(q.orientation.y) && std::isfinite(q.orientation.z) &&
            std::isfinite(q.orientation.w);
  for (double c : p.covariance) ok = ok && std::isfinite(c);
  return ok;
}

void check_odometry(const char*, const std::uint8_t* data, int size, std::int64_t, void* user) {
  rtfuse::odometry_t m;
  FUZZ_CHECK(m.decode(data, 0, size) == size, "the daemon's odometry decodes");
  bool ok = finite(m.pose);
  const auto& t = m.twist.twist;
  ok = ok && std::isfinite(t.linear.x) && std::isfinite(t.linear.y) && std::isfinite(t.linear.z) &&
       std::isfinite(t.angular.x) && std::isfinite(t.angular.y) && std::isfinite(t.angular.z);
  for (double c : m.twist.covariance) ok = ok && std::isfinite(c);
  FUZZ_CHECK(ok, "no NaN or infinity in a published odometry");
  static_cast<Daemon*>(user)->outputs.fetch_add(1, std::memory_order_relaxed);
}

void check_pose(const char*, const std::uint8_t* data, int size, std::int64_t, void* user) {
  rtfuse::pose_with_covariance_stamped_t m;
  FUZZ_CHECK(m.decode(data, 0, size) == size, "the daemon's pose decodes");
  FUZZ_CHECK(finite(m.pose), "no NaN or infinity in a published pose");
  static_cast<Daemon*>(user)->outputs.fetch_add(1, std::memory_order_relaxed);
}

void check_cmd_vel(const char*, const std::uint8_t* data, int size, std::int64_t, void* user) {
  rtfuse::twist_stamped_t m;
  FUZZ_CHECK(m.decode(data, 0, size) == size, "the daemon's command decodes");
  const auto& f = static_cast<Daemon*>(user)->cfg.hardware.navigation.follower;
  const auto& t = m.twist;
  FUZZ_CHECK(std::isfinite(t.linear.x) && std::isfinite(t.angular.z), "no NaN or infinity in a command");
  FUZZ_CHECK(t.linear.x >= 0.0 && t.linear.x <= f.max_linear_mps, "the linear command within [0, max_linear]");
  FUZZ_CHECK(std::fabs(t.angular.z) <= f.max_angular_rps, "the angular command within max_angular");
  FUZZ_CHECK(t.linear.y == 0.0 && t.linear.z == 0.0 && t.angular.x == 0.0 && t.angular.y == 0.0,
             "a planar command");
  static_cast<Daemon*>(user)->commands.fetch_add(1, std::memory_order_relaxed);
}

[[noreturn]] void fail(const std::string& why) {
  std::fprintf(stderr, "daemon_input_fuzz: %s\n", why.c_str());
  std::abort();
}

// The end of a run: the daemon must still have been publishing.
void report() {
  Daemon& d = *g_daemon;
  const std::int64_t before = d.outputs.load();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const std::int64_t after = d.outputs.load();
  const rtfuse::Snapshot s = d.runtime->latest();
  std::fprintf(stderr,
               "daemon_input_fuzz: %lld messages published, %lld outputs checked, %lld ticks, %lld overruns, "
               "set_pose %lld applied %lld rejected, %lld commands checked\n",
               static_cast<long long>(d.published), static_cast<long long>(after),
               static_cast<long long>(s.loop.ticks), static_cast<long long>(s.loop.overruns),
               static_cast<long long>(s.set_pose_count), static_cast<long long>(s.set_pose_rejected),
               static_cast<long long>(d.commands.load()));
  for (int i = 0; i < s.num_sensors; ++i) {
    const rtfuse::SensorStats& st = s.sensors[i];
    std::fprintf(stderr,
                 "daemon_input_fuzz: sensor %s: received %lld accepted %lld rejected %lld (mahalanobis %lld, "
                 "invalid %lld, stale %lld, overflow %lld, rate %lld, oversize %lld, decode %lld)\n",
                 d.cfg.sensors[i].name.c_str(), static_cast<long long>(st.received),
                 static_cast<long long>(st.accepted), static_cast<long long>(rtfuse::rejected_total(st)),
                 static_cast<long long>(st.rejected_mahalanobis), static_cast<long long>(st.rejected_invalid),
                 static_cast<long long>(st.rejected_stale), static_cast<long long>(st.rejected_overflow),
                 static_cast<long long>(st.rejected_rate), static_cast<long long>(st.rejected_oversize),
                 static_cast<long long>(st.decode_errors));
  }
  if (after <= before) {
    std::fprintf(stderr, "daemon_input_fuzz: the daemon stopped publishing\n");
    std::_Exit(1);
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const std::string path = RTFUSE_SOURCE_DIR "/config/sim.toml";
  std::string text;
  int err = 0;
  if (!rtfuse::read_text_file(path, &text, &err)) fail(path + ": cannot read");
  const std::string off = "accept_set_pose = false";
  const std::size_t at = text.find(off);
  if (at == std::string::npos) fail(path + " has no '" + off + "' to turn on");
  text.replace(at, off.size(), "accept_set_pose = true");
  text += kFuzzSensors;
  text += kGlobalInstance;
  text += "\n[navigation]\nfollow = true\n";
  rtfuse::ConfigLoadResult loaded = rtfuse::load_config_string(text, path);
  if (!loaded.config) fail(loaded.errors.empty() ? "config" : loaded.errors.front().to_string());
  g_daemon = new Daemon;
  Daemon& d = *g_daemon;
  rtfuse::RuntimeConfig& cfg = d.cfg;
  cfg = *loaded.config;
  cfg.lcm_url = "memq://";
  std::string error;
  if (cfg.hardware.camera.enabled && !rtfuse::resolve_camera_calibration(&cfg.hardware.camera, &error)) fail(error);
  d.robot = rtfuse::sim::SimRobot::create(cfg, "", d.clock, rtfuse::monotonic_now_ns(), &error);
  if (!d.robot) fail(error);
  d.runtime = rtfuse::Runtime::create(cfg, d.robot->buses(), &error);
  if (!d.runtime) fail(error);
  for (const char* channel : kChannels) {
    if (!d.runtime->lcm().subscribe(channel, count_input, &d)) fail("subscribe");
  }
  if (!d.runtime->lcm().subscribe(cfg.publish.odometry_channel.c_str(), check_odometry, &d) ||
      !d.runtime->lcm().subscribe(cfg.publish.pose_channel.c_str(), check_pose, &d) ||
      !d.runtime->lcm().subscribe(cfg.instances[1].odometry_channel.c_str(), check_odometry, &d) ||
      !d.runtime->lcm().subscribe(cfg.instances[1].pose_channel.c_str(), check_pose, &d) ||
      !d.runtime->lcm().subscribe(cfg.hardware.navigation.cmd_vel_channel.c_str(), check_cmd_vel, &d)) {
    fail("subscribe");
  }
  std::string warnings;
  if (!d.runtime->start(&error, &warnings)) fail(error);
  std::atexit(report);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1 || size > (1u << 16)) return 0;
  Daemon& d = *g_daemon;
  const char* channel = kChannels[data[0] % kNumChannels];
  FUZZ_CHECK(d.runtime->lcm().publish(channel, data + 1, static_cast<int>(size - 1)), "memq publish");
  ++d.published;
  // memq:// queues without bound: keep at most 256 messages ahead of the
  // daemon's LCM thread, so a run measures the daemon, not the queue.
  while (d.published - d.handled.load(std::memory_order_relaxed) > 256) {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return 0;
}
