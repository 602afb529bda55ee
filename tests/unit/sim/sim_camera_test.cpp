// The simulated robot's stereo camera through the same camera driver a real
// ZED runs: config/sim.toml plus a [camera], driven in lockstep.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <cstdio>
#include <cstring>

#include "hal/mock/sim_clock.hpp"
#include "rtfuse/camera_info_t.hpp"
#include "rtfuse/image_t.hpp"
#include "runtime/devices/camera/camera_device.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/pipeline/tick_pipeline.hpp"
#include "sim/sim_robot.hpp"
#include "support/alloc_counter.hpp"
#include "runtime/devices/device_layout.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "runtime/replay/hal_replay.hpp"
#include "sim/sim_drive.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"
#include "support/device_values.hpp"
#include "support/sim_toml.hpp"

namespace sim_camera_test {

using namespace rtfuse;  // NOLINT
using test::find_device;
std::string errors(const ConfigLoadResult& r) { return test::config_errors(r); }
std::int64_t value(const DeviceStatus& d, const char* key) { return test::device_value(d, key); }

const std::string kSimToml = std::string(RTFUSE_SOURCE_DIR) + "/config/sim.toml";

// sim.toml's own camera; its mount (the left eye 0.3 m up at the front,
// looking forward) stays in the config when the table is taken out.
constexpr const char* kCamera = R"(
[camera]
calibration = "calibration/SN10000001.conf"
resolution = "VGA"
fps = 30
)";

// sim.toml without its [camera], which each test here writes itself.
std::string sim_toml() { return test::sim_toml_text(false); }

ConfigLoadResult load(const std::string& extra) {
  // Named after config/sim.toml so its relative paths (scenario, calibration) resolve from config/.
  return load_config_string(sim_toml() + extra, kSimToml);
}

TEST(SimCamera, LockstepDriveRectifiesEveryFrameAtTheConfiguredRate) {
  const ConfigLoadResult r = load(kCamera);
  ASSERT_TRUE(r.config) << errors(r);
  sim::DriveOptions options;
  options.scenario_path = std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/straight.toml";
  const sim::DriveResult d = sim::run_sim_drive(*r.config, options, nullptr);
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
  const sim::DriveResult d = sim::run_sim_drive(*r.config, options, nullptr);
  ASSERT_TRUE(d.ok) << d.error;
  EXPECT_EQ(d.recording_lost, 0);
  const DeviceStatus* live = find_device(d.final, "camera");
  ASSERT_NE(live, nullptr);

  transport::EventLogReader reader;
  std::string err;
  ASSERT_TRUE(reader.open(path, &err)) << err;
  HalRecording rec;
  ASSERT_TRUE(load_hal_recording(reader, {}, &rec, &err)) << err;
  EXPECT_EQ(rec.lost_frames, 0);
  // The calibration travels in the recording: the replay uses it even where
  // the file the config names does not exist.
  ASSERT_EQ(rec.info.files.size(), 1u);
  EXPECT_EQ(rec.info.files[0].key, "camera.calibration");
  EXPECT_EQ(rec.info.files[0].path, std::string(RTFUSE_SOURCE_DIR) + "/config/calibration/SN10000001.conf");
  RuntimeConfig elsewhere = *r.config;
  elsewhere.hardware.camera.calibration_file = "/nonexistent/SN10000001.conf";
  const HalReplayResult replay = replay_hal_recording(rec, elsewhere, nullptr, nullptr);
  std::remove(path.c_str());
  ASSERT_TRUE(replay.ok) << replay.error;
  EXPECT_FALSE(replay.ended_early) << replay.note;
  EXPECT_GT(replay.compared, 0);
  EXPECT_EQ(replay.identical, replay.compared) << replay.first_mismatch;
  const DeviceStatus* replayed = find_device(replay.final, "camera");
  ASSERT_NE(replayed, nullptr);
  EXPECT_EQ(value(*replayed, "frames"), value(*live, "frames"));
  EXPECT_GT(value(*replayed, "frames"), 500);
  // The same pairs, pixel for pixel, in the same order.
  EXPECT_EQ(value(*replayed, "pairs_digest"), value(*live, "pairs_digest"));
  EXPECT_NE(value(*live, "pairs_digest"), 0);
  EXPECT_EQ(value(*replayed, "rejected_size"), 0);
}

// Keeps the last message of each camera channel; allocates nothing while
// publishing (its buffers are reserved), so the test can count the outputs'.
class CapturingSink final : public MessageSink {
 public:
  CapturingSink() {
    preview.reserve(1 << 20);
    left.reserve(1 << 12);
    right.reserve(1 << 12);
  }
  bool publish(const char* channel, const std::uint8_t* data, int size, TimeNs) override {
    if (std::strcmp(channel, "rtfuse/camera/preview") == 0) preview.assign(data, data + size);
    if (std::strcmp(channel, "rtfuse/camera/info/left") == 0) left.assign(data, data + size);
    if (std::strcmp(channel, "rtfuse/camera/info/right") == 0) right.assign(data, data + size);
    ++messages;
    return true;
  }
  std::vector<std::uint8_t> preview, left, right;
  int messages = 0;
};

class NullSink final : public MessageSink {
 public:
  bool publish(const char*, const std::uint8_t*, int, TimeNs) override { return true; }
};

// The daemon's camera outputs: the newest rectified pair as a half-size
// side-by-side preview and each eye's rectified camera info, at the preview
// rate, from the frame pool by handle.
TEST(SimCamera, PreviewAndCameraInfoOfTheNewestPair) {
  const ConfigLoadResult r = load(kCamera);
  ASSERT_TRUE(r.config) << errors(r);
  const TimeNs t0 = 1'000'000'000;
  hal::mock::SimClock clock(t0);
  std::string err;
  auto robot = sim::SimRobot::create(*r.config, std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/straight.toml",
                                           clock, t0, &err);
  ASSERT_TRUE(robot) << err;
  NullSink null_sink;
  PipelineOptions options;
  options.sink = &null_sink;
  auto pipeline = TickPipeline::create(*r.config, robot->buses(), options, &err);
  ASSERT_TRUE(pipeline) << err;
  ASSERT_TRUE(pipeline->start(t0, &err)) << err;
  CameraDevice* camera = pipeline->hardware()->find<CameraDevice>("camera");
  ASSERT_NE(camera, nullptr);
  // The device's own outputs, as the live publisher thread asks for them.
  CameraDevice* outputs = camera;
  CapturingSink sink;
  // No pair yet: nothing to show.
  outputs->publish_due(t0, sink);
  EXPECT_EQ(sink.messages, 0);
  for (int i = 0; i < 3; ++i) camera->step(kDeviceStepTimeoutNs);
  ASSERT_EQ(camera->samples(), 3);
  std::size_t allocations = 0;
  {
    test::AllocScope allocs;
    outputs->publish_due(clock.now(), sink);
    allocations = allocs.count();
  }
  EXPECT_EQ(allocations, 0u);
  ASSERT_EQ(sink.messages, 3);
  rtfuse::image_t image;
  ASSERT_GT(image.decode(sink.preview.data(), 0, static_cast<int>(sink.preview.size())), 0);
  EXPECT_EQ(image.encoding, "mono8");
  EXPECT_EQ(image.width, 672);   // two VGA eyes at half size
  EXPECT_EQ(image.height, 188);
  EXPECT_EQ(image.header.frame_id, "camera_optical");
  // The third frame's capture time: three periods after the start.
  EXPECT_NEAR(static_cast<double>(image.header.utime), static_cast<double>((t0 + 3 * 33'333'333) / 1000), 1.0);
  // A rendered scene, not a blank or saturated picture.
  double sum = 0.0;
  for (std::uint8_t v : image.data) sum += v;
  const double mean = sum / static_cast<double>(image.data.size());
  EXPECT_GT(mean, 30.0);
  EXPECT_LT(mean, 230.0);
  rtfuse::camera_info_t left, right;
  ASSERT_GT(left.decode(sink.left.data(), 0, static_cast<int>(sink.left.size())), 0);
  ASSERT_GT(right.decode(sink.right.data(), 0, static_cast<int>(sink.right.size())), 0);
  const drivers::StereoRectification& rect = camera->rectified();
  EXPECT_EQ(left.width, 672);
  EXPECT_EQ(left.height, 376);
  EXPECT_DOUBLE_EQ(left.K[0], rect.fx);
  EXPECT_DOUBLE_EQ(left.P[3], 0.0);
  EXPECT_DOUBLE_EQ(right.P[3], -rect.fx * rect.baseline_m);
  EXPECT_NEAR(rect.baseline_m, 0.120, 0.001);  // the calibration file's 119.997 mm
  // Not again until the next period, and not for the same pair.
  outputs->publish_due(clock.now() + 500'000'000, sink);
  EXPECT_EQ(sink.messages, 3);
  outputs->publish_due(clock.now() + 1'000'000'000, sink);
  EXPECT_EQ(sink.messages, 3) << "no new pair since the last preview";
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
  const sim::DriveResult d = sim::run_sim_drive(*r.config, options, nullptr);
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
  const sim::DriveResult d = sim::run_sim_drive(*r.config, options, nullptr);
  EXPECT_FALSE(d.ok);
  EXPECT_NE(d.error.find("SN999.conf"), std::string::npos) << d.error;
}

}  // namespace sim_camera_test
