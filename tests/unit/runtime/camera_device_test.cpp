// The camera thread device on a MockVideoStream: its diagnostics slot says
// what the driver counted, the digest of the published pairs, and the last
// error in words ("" until there is one, kept after the camera recovers).
#include "runtime/devices/camera/camera_device.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <iterator>
#include <memory>
#include <string>

#include "hal/mock/frame_generator.hpp"
#include "hal/mock/mock_video_stream.hpp"
#include "hal/mock/sim_clock.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/devices/device_layout.hpp"

namespace rtfuse {
namespace camera_device_test {

constexpr int kEyeW = 672;  // VGA
constexpr int kEyeH = 376;
constexpr TimeNs kStart = 1'000'000'000;
constexpr TimeNs kPeriod = 33'333'333;  // 30 fps

// Named after a file in config/ so the calibration path resolves from there.
const std::string kConfigPath = std::string(RTFUSE_SOURCE_DIR) + "/config/camera_device_test.toml";

constexpr const char* kConfig = R"(
[filter]
frequency = 200
world_frame = "odom"

[hardware]
backend = "linux"

[camera]
calibration = "calibration/SN10000001.conf"
resolution = "VGA"
fps = 30
)";

// A grey frame every kPeriod, its shade from the sequence number.
class ShadeSource final : public hal::mock::FrameGenerator {
 public:
  TimeNs next_frame_time() noexcept override { return kStart + static_cast<TimeNs>(taken_) * kPeriod; }
  std::uint32_t fill(TimeNs, std::uint32_t sequence, std::uint8_t* data, std::uint32_t capacity) noexcept override {
    ++taken_;
    if (data != nullptr) std::memset(data, static_cast<int>(40 + (sequence * 13) % 160), capacity);
    return data != nullptr ? capacity : 0;
  }

 private:
  std::int64_t taken_ = 0;
};

std::int64_t value(const DeviceStatus& d, const char* key) {
  for (int i = 0; i < d.num_values; ++i) {
    if (std::strcmp(d.keys[i], key) == 0) return d.values[i];
  }
  ADD_FAILURE() << "no key " << key;
  return -1;
}

struct CameraRig {
  CameraRig() : stream(clock, source, hal::mock::yuyv_format(2 * kEyeW, kEyeH, 30)) {
    ConfigLoadResult r = load_config_string(kConfig, kConfigPath);
    for (const ConfigError& e : r.errors) ADD_FAILURE() << e.to_string();
    if (!r.config) return;
    core = FusionCore::create(*r.config, &error);
    if (!core) return;
    DeviceBuses buses;
    buses.video = &stream;
    buses.clock = &clock;
    camera = CameraDevice::create(buses, *core, 0, false, &error);
    s.num_devices = describe_devices(core->config(), s.devices, kMaxDevices);
  }
  const DeviceStatus& status() {
    camera->fill_snapshot(s);
    return s.devices[0];
  }

  hal::mock::SimClock clock{kStart - kPeriod / 2};
  ShadeSource source;
  hal::mock::MockVideoStream stream;
  std::unique_ptr<FusionCore> core;
  std::unique_ptr<CameraDevice> camera;
  std::string error;
  Snapshot s;
};

TEST(CameraDevice, StatusCarriesEveryCounterAndThePairsDigest) {
  CameraRig rig;
  ASSERT_TRUE(rig.camera) << rig.error;
  ASSERT_EQ(rig.s.num_devices, 1);
  const int key_count = static_cast<int>(std::size(kCameraKeys));
  EXPECT_LE(key_count, kMaxDeviceValues);
  for (int i = 0; i < 3; ++i) rig.camera->step(2 * kPeriod);
  const DeviceStatus& d = rig.status();
  EXPECT_STREQ(d.name.c_str(), "camera");
  EXPECT_EQ(d.num_values, key_count) << "every key has its value";
  EXPECT_STREQ(d.keys[key_count - 1], "pairs_digest");
  EXPECT_EQ(value(d, "frames"), 3);
  const std::uint64_t digest = rig.camera->stats().pairs_digest;
  EXPECT_NE(digest, 0u);
  EXPECT_EQ(static_cast<std::uint64_t>(value(d, "pairs_digest")), digest);

  // Another camera fed the same frames publishes the same digest.
  CameraRig again;
  ASSERT_TRUE(again.camera) << again.error;
  for (int i = 0; i < 3; ++i) again.camera->step(2 * kPeriod);
  EXPECT_EQ(value(again.status(), "pairs_digest"), value(d, "pairs_digest"));
}

// One step, then the slot's state word and message.
void expect_step(CameraRig& rig, const char* state, const char* message) {
  rig.camera->step(2 * kPeriod);
  const DeviceStatus& d = rig.status();
  EXPECT_STREQ(d.state.c_str(), state);
  EXPECT_STREQ(d.message.c_str(), message);
}

TEST(CameraDevice, MessageIsEmptyUntilAFailureThenSaysWhatFailed) {
  CameraRig rig;
  ASSERT_TRUE(rig.camera) << rig.error;
  constexpr const char* kCorrupted = "zed camera: frame 1 flagged as corrupted by the device; dropped";
  expect_step(rig, "frame", "");
  rig.stream.corrupt_next();
  expect_step(rig, "rejected", kCorrupted);
  // Back to frames: the state says so, the message keeps the last error.
  expect_step(rig, "frame", kCorrupted);

  rig.stream.unplug();
  rig.camera->step(2 * kPeriod);
  EXPECT_STREQ(rig.status().state.c_str(), "lost");
  EXPECT_EQ(rig.status().level, DeviceLevel::kError);
  const std::string lost = rig.status().message.c_str();
  EXPECT_EQ(lost.rfind("zed camera: the camera went away", 0), 0u) << lost;
  EXPECT_NE(lost.find("reopening in 250 ms"), std::string::npos) << lost;
}

}  // namespace camera_device_test
}  // namespace rtfuse
