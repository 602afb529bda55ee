// The simulated robot's stereo camera through the same camera driver a real
// ZED runs: config/sim.toml plus a [camera], driven in lockstep.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <cstdio>

#include "runtime/config_loader.hpp"
#include "runtime/device_layout.hpp"
#include "runtime/hal_replay.hpp"
#include "sim/simulated_drive.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"

namespace {

using namespace rtfuse;  // NOLINT

const std::string kSimToml = std::string(RTFUSE_SOURCE_DIR) + "/config/sim.toml";

// The left eye 0.3 m up at the front, looking forward: the optical frame's
// z is base_link's x, its x is -y, its y is -z.
constexpr const char* kCamera = R"(
[camera]
calibration = "calibration/SN10000001.conf"
resolution = "VGA"
fps = 30

[[static_transform]]
parent = "base_link"
child = "camera_optical"
translation = [0.2, 0.06, 0.3]
rpy = [-1.5707963267948966, 0.0, -1.5707963267948966]
)";

std::string sim_toml() {
  std::ifstream in(kSimToml);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

ConfigLoadResult load(const std::string& extra) {
  // Named after config/sim.toml so its relative paths (scenario, calibration) resolve from config/.
  return load_config_string(sim_toml() + extra, kSimToml);
}

std::string errors(const ConfigLoadResult& r) {
  std::string all;
  for (const ConfigError& e : r.errors) all += e.to_string() + "\n";
  return all;
}

const DeviceStatus* find_device(const Snapshot& s, const char* name) {
  for (int i = 0; i < s.num_devices; ++i) {
    if (std::string(s.devices[i].name.c_str()) == name) return &s.devices[i];
  }
  return nullptr;
}

std::int64_t value(const DeviceStatus& d, const char* key) {
  for (int i = 0; i < d.num_values; ++i) {
    if (std::string(d.keys[i]) == key) return d.values[i];
  }
  ADD_FAILURE() << "no key " << key;
  return -1;
}

TEST(SimCamera, LockstepDriveRectifiesEveryFrameAtTheConfiguredRate) {
  const ConfigLoadResult r = load(kCamera);
  ASSERT_TRUE(r.config) << errors(r);
  sim::DriveOptions options;
  options.scenario_path = std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/straight.toml";
  const sim::DriveResult d = sim::run_simulated_drive(*r.config, options, nullptr);
  ASSERT_TRUE(d.ok) << d.error;
  const DeviceStatus* camera = find_device(d.final, "camera");
  ASSERT_NE(camera, nullptr);
  EXPECT_STREQ(camera->state.c_str(), "frame");
  EXPECT_EQ(camera->level, DeviceLevel::kOk);
  // One frame per 1/30 s of the drive, the first one period after the start.
  const std::int64_t expected = static_cast<std::int64_t>(d.duration_s * 30.0);
  EXPECT_NEAR(static_cast<double>(value(*camera, "frames")), static_cast<double>(expected), 1.0);
  EXPECT_NEAR(static_cast<double>(value(*camera, "fps_milli")), 30000.0, 1.0);
  EXPECT_EQ(value(*camera, "dropped"), 0);
  EXPECT_EQ(value(*camera, "rejected_size"), 0);
  EXPECT_EQ(value(*camera, "pool_full"), 0);
  // The camera changes nothing in the estimate: the drive's error stays as without it.
  EXPECT_LT(d.final_error_m, 0.1);
}

// Frames are recorded on a stream of their own and replayed through the
// same camera driver: every frame it rectified live is rectified again, and
// the estimate outputs stay byte-identical.
TEST(SimCamera, RecordedFramesReplayThroughTheDriver) {
  const std::string text = sim_toml() + kCamera;
  const ConfigLoadResult r = load_config_string(text, kSimToml);
  ASSERT_TRUE(r.config) << errors(r);
  const std::string path = testing::TempDir() + "rtfuse_sim_camera_" + std::to_string(::getpid()) + ".lcm";
  sim::DriveOptions options;
  options.scenario_path = std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/straight.toml";
  options.record_path = path;
  options.config_text = text;
  const sim::DriveResult d = sim::run_simulated_drive(*r.config, options, nullptr);
  ASSERT_TRUE(d.ok) << d.error;
  EXPECT_EQ(d.recording_lost, 0);
  const DeviceStatus* live = find_device(d.final, "camera");
  ASSERT_NE(live, nullptr);

  transport::EventLogReader reader;
  std::string err;
  ASSERT_TRUE(reader.open(path, &err)) << err;
  transport::HalRecording rec;
  ASSERT_TRUE(transport::load_hal_recording(reader, {}, &rec, &err)) << err;
  EXPECT_EQ(rec.lost_frames, 0);
  const HalReplayResult replay = replay_hal_recording(rec, *r.config, nullptr, nullptr);
  std::remove(path.c_str());
  ASSERT_TRUE(replay.ok) << replay.error;
  EXPECT_FALSE(replay.ended_early) << replay.note;
  EXPECT_GT(replay.compared, 0);
  EXPECT_EQ(replay.identical, replay.compared) << replay.first_mismatch;
  const DeviceStatus* replayed = find_device(replay.final, "camera");
  ASSERT_NE(replayed, nullptr);
  EXPECT_EQ(value(*replayed, "frames"), value(*live, "frames"));
  EXPECT_GT(value(*replayed, "frames"), 500);
  EXPECT_EQ(value(*replayed, "rejected_size"), 0);
}

TEST(SimCamera, CameraWithoutMountIsRefusedNamingTheFrame) {
  const ConfigLoadResult r = load(R"(
[camera]
calibration = "calibration/SN10000001.conf"
frame = "nowhere_optical"
)");
  ASSERT_TRUE(r.config) << errors(r);
  sim::DriveOptions options;
  options.scenario_path = std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/straight.toml";
  const sim::DriveResult d = sim::run_simulated_drive(*r.config, options, nullptr);
  EXPECT_FALSE(d.ok);
  EXPECT_NE(d.error.find("camera.frame 'nowhere_optical' is not connected to 'base_link'"), std::string::npos) << d.error;
}

TEST(SimCamera, ConfigRefusesAModeTheCameraDoesNotHave) {
  const ConfigLoadResult r = load(R"(
[camera]
calibration = "calibration/SN10000001.conf"
resolution = "2K"
fps = 30
)");
  EXPECT_FALSE(r.config);
  EXPECT_NE(errors(r).find("camera.fps"), std::string::npos) << errors(r);
  EXPECT_NE(errors(r).find("2K"), std::string::npos) << errors(r);
}

TEST(SimCamera, MissingCalibrationFileNamesThePath) {
  const ConfigLoadResult r = load(R"(
[camera]
calibration = "calibration/SN999.conf"
)");
  ASSERT_TRUE(r.config) << errors(r);
  sim::DriveOptions options;
  options.scenario_path = std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/straight.toml";
  const sim::DriveResult d = sim::run_simulated_drive(*r.config, options, nullptr);
  EXPECT_FALSE(d.ok);
  EXPECT_NE(d.error.find("SN999.conf"), std::string::npos) << d.error;
}

}  // namespace
