// An IMU's residual gyro bias learnt from the wheels' standstills, through
// the loop's real input path: encoded LCM messages -> InputRouter -> rings
// -> tick -> the filter's yaw and the diagnostics slot.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rtfuse/imu_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "support/alloc_counter.hpp"
#include "support/device_values.hpp"
#include "support/lcm_inputs.hpp"

namespace rtfuse {
namespace standstill_fusion_test {

// Wheels fusing forward speed only (a skid-steer base whose wheel yaw is
// not trusted), the IMU its yaw rate: the yaw is the gyro's alone.
std::string config(bool learner) {
  std::string text = R"(
[filter]
frequency = 50
sensor_timeout = 0.5

[[sensor]]
name = "odom0"
type = "odometry"
channel = "wheel_odom"
config = [false, false, false, false, false, false,
          true,  false, false, false, false, false,
          false, false, false]

[[sensor]]
name = "imu0"
type = "imu"
channel = "imu"
config = [false, false, false, false, false, false,
          false, false, false, false, false, true,
          false, false, false]
)";
  if (learner) text += "standstill_from = \"odom0\"\n";
  return text;
}

const auto load = test::load_config_text;

using test::encode;
const auto wheels = test::wheel_odometry;

std::vector<std::uint8_t> gyro(TimeNs t, double yaw_rate) {
  rtfuse::imu_t m{};
  m.header.utime = ns_to_utime(t);
  m.header.frame_id = "base_link";
  m.orientation = {0.0, 0.0, 0.0, 1.0};
  m.orientation_covariance[0] = -1;
  m.angular_velocity.z = yaw_rate;
  for (int i = 0; i < 3; ++i) m.angular_velocity_covariance[i * 4] = 1e-6;
  m.linear_acceleration_covariance[0] = -1;
  return encode(m);
}

struct DriveResult {
  double yaw_after_stand = 0.0;
  double yaw_end = 0.0;
  Snapshot last;
};

// 4 s standing, then 10 s driving straight at 0.5 m/s; the gyro reads a
// residual bias of 0.01 rad/s throughout (the base never turns).
DriveResult drive(bool learner) {
  std::string err;
  auto core = FusionCore::create(load(config(learner)), &err);
  EXPECT_TRUE(core) << err;
  DriveResult run;
  if (!core) return run;
  LoopStats loop;
  constexpr TimeNs kT0 = 1'000'000'000, kStep = 20'000'000;  // 50 Hz
  for (int k = 0; k < 700; ++k) {
    const TimeNs t = kT0 + k * kStep;
    const double vx = k < 200 ? 0.0 : 0.5;
    const auto w = wheels(t, vx);
    const auto g = gyro(t, 0.01);
    EXPECT_TRUE(core->input().on_message("wheel_odom", w.data(), static_cast<int>(w.size()), t));
    EXPECT_TRUE(core->input().on_message("imu", g.data(), static_cast<int>(g.size()), t));
    core->tick(t, loop);
    if (k == 199) run.yaw_after_stand = core->last_snapshot().state[5];
  }
  run.yaw_end = core->last_snapshot().state[5];
  run.last = core->last_snapshot();
  return run;
}

TEST(StandstillFusion, TheWheelsStandstillTakesTheGyrosResidualBiasOff) {
  const DriveResult plain = drive(false);
  const DriveResult taught = drive(true);
  std::printf("yaw after 4 s standing and 10 s driving: %.4f rad without the learner, %.4f with (%.4f of it "
              "while standing)\n",
              plain.yaw_end, taught.yaw_end, taught.yaw_after_stand);
  // Without it the yaw follows the bias: 0.01 rad/s for 14 s.
  EXPECT_GT(plain.yaw_end, 0.12);
  // With it the yaw drifts only until the first blocks are learnt, then
  // holds: the drive adds almost nothing.
  EXPECT_LT(std::fabs(taught.yaw_after_stand), 0.02);
  EXPECT_LT(std::fabs(taught.yaw_end - taught.yaw_after_stand), 0.002);

  // Its diagnostics slot: blocks learnt, the bias in urad/s.
  const DeviceStatus* d = test::find_device(taught.last, "gyro bias imu0");
  ASSERT_NE(d, nullptr);
  ASSERT_EQ(d->num_values, 7);
  EXPECT_GE(test::device_value(*d, "blocks"), 4);
  EXPECT_EQ(test::device_value(*d, "dropped"), 1);  // the block filling when the drive began
  EXPECT_NEAR(static_cast<double>(test::device_value(*d, "bias_z_urad_s")), 10000.0, 1.0);
  EXPECT_STREQ(d->state.c_str(), "learnt");
  // No slot without the learner.
  EXPECT_EQ(test::find_device(plain.last, "gyro bias imu0"), nullptr);
}

TEST(StandstillFusion, TheSlotSaysSoBeforeTheFirstStandstill) {
  std::string err;
  auto core = FusionCore::create(load(config(true)), &err);
  ASSERT_TRUE(core) << err;
  constexpr TimeNs t = 1'000'000'000;
  const auto w = wheels(t, 0.4);
  core->input().on_message("wheel_odom", w.data(), static_cast<int>(w.size()), t);
  core->tick(t, LoopStats{});
  const Snapshot& s = core->last_snapshot();
  ASSERT_EQ(s.num_devices, 1);
  EXPECT_STREQ(s.devices[0].name.c_str(), "gyro bias imu0");
  EXPECT_STREQ(s.devices[0].hardware_id.c_str(), "odom0");
  EXPECT_STREQ(s.devices[0].state.c_str(), "no standstill yet");
  EXPECT_EQ(test::device_value(s.devices[0], "blocks"), 0);
}

TEST(StandstillFusion, LearningAllocatesNothing) {
  std::string err;
  auto core = FusionCore::create(load(config(true)), &err);
  ASSERT_TRUE(core) << err;
  constexpr TimeNs kT0 = 1'000'000'000, kStep = 20'000'000;
  std::vector<std::vector<std::uint8_t>> w, g;
  for (int k = 0; k < 300; ++k) {
    w.push_back(wheels(kT0 + k * kStep, k < 150 ? 0.0 : 0.5));
    g.push_back(gyro(kT0 + k * kStep, 0.01));
  }
  const auto step = [&](int k) {
    const TimeNs t = kT0 + k * kStep;
    core->input().on_message("wheel_odom", w[k].data(), static_cast<int>(w[k].size()), t);
    core->input().on_message("imu", g[k].data(), static_cast<int>(g[k].size()), t);
    core->tick(t, LoopStats{});
  };
  for (int k = 0; k < 10; ++k) step(k);  // warm up: the first decodes size their strings
  test::AllocScope scope;
  for (int k = 10; k < 300; ++k) step(k);
  EXPECT_EQ(scope.count(), 0u);
  const DeviceStatus* d = test::find_device(core->last_snapshot(), "gyro bias imu0");
  ASSERT_NE(d, nullptr);
  EXPECT_GE(test::device_value(*d, "blocks"), 4);  // learnt inside the scope
}

std::string first_error(const std::string& text) {
  ConfigLoadResult r = load_config_string(text, "test.toml");
  return r.errors.empty() ? std::string() : r.errors.front().to_string();
}

TEST(StandstillFusion, TheConfigNamesAWheelSensorOfTheSameInstance) {
  std::string text = config(false) + "standstill_from = \"odom9\"\n";
  EXPECT_NE(first_error(text).find("no sensor is named 'odom9'"), std::string::npos) << first_error(text);
  text = config(false) + "standstill_from = \"imu0\"\n";
  EXPECT_NE(first_error(text).find("name the wheels' odometry or twist sensor"), std::string::npos)
      << first_error(text);
  text = config(false) + "standstill_block = 0.5\n";
  EXPECT_NE(first_error(text).find("needs standstill_from"), std::string::npos) << first_error(text);
  text = config(true) + "standstill_time_constant = 0.1\n";
  EXPECT_NE(first_error(text).find("time_constant must be at least the block"), std::string::npos)
      << first_error(text);
  // On the wheels' own table the keys mean nothing.
  text = config(false);
  text.insert(text.find("[[sensor]]\nname = \"imu0\""), "standstill_from = \"odom0\"\n\n");
  EXPECT_NE(first_error(text).find("only valid for type 'imu'"), std::string::npos) << first_error(text);
}

}  // namespace standstill_fusion_test
}  // namespace rtfuse
