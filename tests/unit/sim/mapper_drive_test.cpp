// The mapper in the product: config/sim.toml's [mapping] on the simulated
// robot in lockstep, its recording replayed (the same map, bit for bit,
// by its digest), and the set-ups it refuses with what to change.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "runtime/config/config_loader.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "runtime/replay/hal_replay.hpp"
#include "sim/sim_drive.hpp"
#include "support/device_values.hpp"
#include "support/sim_toml.hpp"
#include "transport/event_log.hpp"

namespace mapper_drive_test {
using namespace rtfuse;  // NOLINT
using test::find_device;
std::string errors(const ConfigLoadResult& r) { return test::config_errors(r); }
std::int64_t value(const DeviceStatus& d, const char* key) { return test::device_value(d, key); }

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// sim.toml with its camera and mapper, two keyframes a second (the cost of
// the test is the rendering and the keyframes, not what they prove).
std::string config_text() { return replaced(test::sim_toml_text(true, true), "keyframe_interval = 0.2 ",
                                            "keyframe_interval = 0.5 "); }

// config/scenarios/straight.toml cut to 8 s: 4 m between two 1 s pauses.
std::string short_straight() {
  std::ifstream in(std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/straight.toml");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = replaced(ss.str(), "duration_s = 20.0", "duration_s = 8.0");
  text = replaced(text, "length_m = 10.0", "length_m = 4.0");
  text = replaced(replaced(text, "duration_s = 2.0", "duration_s = 1.0"), "duration_s = 2.0", "duration_s = 1.0");
  const std::string path = testing::TempDir() + "rtfuse_mapper_straight_" + std::to_string(::getpid()) + ".toml";
  std::ofstream(path) << text;
  return path;
}

TEST(MapperDrive, LockstepDriveMapsEveryKeyframeAndItsRecordingReplaysTheSameMap) {
  const std::string text = config_text();
  const ConfigLoadResult r = load_config_string(text, test::kSimTomlPath);
  ASSERT_TRUE(r.config) << errors(r);
  ASSERT_TRUE(r.config->hardware.mapping.enabled);
  const std::string path = testing::TempDir() + "rtfuse_mapper_drive_" + std::to_string(::getpid()) + ".lcm";
  sim::DriveOptions options;
  options.scenario_path = short_straight();
  options.record_path = path;
  options.config_text = text;
  const sim::DriveResult d = sim::run_sim_drive(*r.config, options, nullptr);
  std::remove(options.scenario_path.c_str());
  ASSERT_TRUE(d.ok) << d.error;
  ASSERT_NEAR(d.duration_s, 8.0, 0.5);
  const DeviceStatus* live = find_device(d.final, "mapper");
  ASSERT_NE(live, nullptr);
  // Two keyframes a second of the drive, but the last pose_delay's; the
  // first, before the filter has a pose, may go without one.
  EXPECT_GE(value(*live, "keyframes"), static_cast<std::int64_t>(2 * d.duration_s) - 2);
  EXPECT_EQ(value(*live, "dropped"), 0);
  EXPECT_LE(value(*live, "no_pose"), 1);
  EXPECT_EQ(value(*live, "bad_pose"), 0);
  EXPECT_EQ(value(*live, "inserted"), value(*live, "keyframes") - value(*live, "no_pose"));
  EXPECT_GT(value(*live, "occupied"), 1000);
  EXPECT_GT(value(*live, "known"), 50 * value(*live, "occupied") / 10);
  EXPECT_EQ(value(*live, "dropped_updates"), 0);
  EXPECT_GE(value(*live, "grids"), 6);  // 1 Hz of the drive
  EXPECT_NE(value(*live, "digest"), 0);

  transport::EventLogReader reader;
  std::string err;
  ASSERT_TRUE(reader.open(path, &err)) << err;
  HalRecording rec;
  ASSERT_TRUE(load_hal_recording(reader, {}, &rec, &err)) << err;
  const HalReplayResult replay = replay_hal_recording(rec, *r.config, nullptr, nullptr);
  std::remove(path.c_str());
  ASSERT_TRUE(replay.ok) << replay.error;
  EXPECT_EQ(replay.identical, replay.compared) << replay.first_mismatch;
  const DeviceStatus* replayed = find_device(replay.final, "mapper");
  ASSERT_NE(replayed, nullptr);
  for (const char* key : {"keyframes", "inserted", "no_pose", "points", "known", "occupied", "grids", "digest"}) {
    EXPECT_EQ(value(*replayed, key), value(*live, key)) << key;
  }
}

TEST(MapperDrive, ASetUpThatCannotWorkIsRefusedWithWhatToChange) {
  // Keys and ranges: the file, the line and the key.
  ConfigLoadResult r = load_config_string(test::sim_toml_text(true) +
                                              "\n[mapping]\nresolution = 0\ngrid_min_z = 1.0\ngrid_max_z = 0.5\n"
                                              "disparities = 48\nkeyframe_intervall = 1\n",
                                          test::kSimTomlPath);
  ASSERT_FALSE(r.config);
  const std::string all = errors(r);
  EXPECT_NE(all.find("mapping.resolution"), std::string::npos) << all;
  EXPECT_NE(all.find("mapping.grid_max_z"), std::string::npos) << all;
  EXPECT_NE(all.find("mapping.disparities"), std::string::npos) << all;
  EXPECT_NE(all.find("keyframe_intervall"), std::string::npos) << all;
  // No camera: nothing to map from.
  r = load_config_string(test::sim_toml_text(false) + "\n[mapping]\n", test::kSimTomlPath);
  ASSERT_FALSE(r.config);
  EXPECT_NE(errors(r).find("needs a [camera] section"), std::string::npos) << errors(r);

  // A pool of frames too small for the mapper's queue: the camera says
  // which setting to raise, before anything runs.
  r = load_config_string(test::sim_toml_text(true, true), test::kSimTomlPath);
  ASSERT_TRUE(r.config) << errors(r);
  RuntimeConfig cfg = *r.config;
  cfg.hardware.camera.pool_frames = 4;
  sim::DriveOptions options;
  options.scenario_path = std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/straight.toml";
  sim::DriveResult d = sim::run_sim_drive(cfg, options, nullptr);
  EXPECT_FALSE(d.ok);
  EXPECT_NE(d.error.find("camera.pool_frames >= 5"), std::string::npos) << d.error;
  // A map memory that cannot hold one keyframe at this range.
  cfg = *r.config;
  cfg.hardware.mapping.memory_mb = 1;
  cfg.hardware.mapping.max_range_m = 30.0;
  d = sim::run_sim_drive(cfg, options, nullptr);
  EXPECT_FALSE(d.ok);
  EXPECT_NE(d.error.find("[mapping]"), std::string::npos) << d.error;
  EXPECT_NE(d.error.find("raise the memory"), std::string::npos) << d.error;
}

}  // namespace mapper_drive_test
