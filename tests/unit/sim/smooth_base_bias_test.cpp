// The IMU's gyro bias on a smooth base (config/scenarios/slow_turns.toml):
// two slow arcs between standstills with no vibration, run on
// config/sim.toml in lockstep through the real drivers and FusionCore.
// With the driver's IMU-only stillness learner the arcs are learnt as
// bias; with it off and the wheels' standstills teaching the bias in the
// loop (standstill_from), they are not.
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include "runtime/config/config_loader.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "runtime/replay/hal_replay.hpp"
#include "sim/sim_drive.hpp"
#include "support/device_values.hpp"
#include "support/sim_toml.hpp"
#include "transport/event_log.hpp"

namespace rtfuse::sim {
namespace smooth_base_bias_test {

const std::string kSimToml = RTFUSE_SOURCE_DIR "/config/sim.toml";
const std::string kSlowTurns = RTFUSE_SOURCE_DIR "/config/scenarios/slow_turns.toml";

// config/sim.toml without the camera; with `wheels_teach`, the driver's
// learner off and the imu sensor learning from the wheels.
std::string robot_text(bool wheels_teach) {
  std::string text = test::sim_toml_text(false);
  if (wheels_teach) {
    const std::size_t attitude = text.find("[mpu.attitude]\n");
    EXPECT_NE(attitude, std::string::npos);
    text.insert(attitude + 15, "stillness_bias = false\n");
    const std::size_t imu = text.find("name = \"imu\"");
    EXPECT_NE(imu, std::string::npos);
    text.insert(text.find("\n\n", imu), "\nstandstill_from = \"wheels\"");
  }
  return text;
}

RuntimeConfig robot(bool wheels_teach) {
  const ConfigLoadResult r = load_config_string(robot_text(wheels_teach), kSimToml);
  for (const auto& e : r.errors) ADD_FAILURE() << e.to_string();
  return r.ok() ? *r.config : RuntimeConfig{};
}

DriveResult drive(bool wheels_teach) {
  DriveOptions opt;
  opt.scenario_path = kSlowTurns;
  return run_sim_drive(robot(wheels_teach), opt, nullptr);
}

TEST(SmoothBaseBias, TheWheelsStandstillsTeachTheGyroBiasWhereTheImuAloneCannot) {
  const DriveResult imu_alone = drive(false);
  const DriveResult wheels = drive(true);
  ASSERT_TRUE(imu_alone.ok) << imu_alone.error;
  ASSERT_TRUE(wheels.ok) << wheels.error;
  std::printf("slow turns, 92 s: the IMU's own learner %.3f m final (%.3f rms), yaw %.4f rad; the wheels' "
              "standstills %.3f m (%.3f rms), yaw %.4f rad\n",
              imu_alone.final_error_m, imu_alone.rms_error_m, imu_alone.final_yaw_error_rad, wheels.final_error_m,
              wheels.rms_error_m, wheels.final_yaw_error_rad);
  // The trap: metres off after 40 m.
  EXPECT_GT(imu_alone.final_error_m, 2.0);
  EXPECT_GT(imu_alone.final_yaw_error_rad, 0.1);
  // Out of it.
  EXPECT_LT(wheels.final_error_m, 0.25);
  EXPECT_LT(wheels.final_yaw_error_rad, 0.01);

  // The learner's slot: blocks from the three standstills, the bias it
  // took off (the scenario's -0.2 deg/s on z, in urad/s, within what its
  // averaging leaves).
  const DeviceStatus* d = test::find_device(wheels.final, "gyro bias imu");
  ASSERT_NE(d, nullptr);
  EXPECT_GE(test::device_value(*d, "blocks"), 10);
  EXPECT_NEAR(static_cast<double>(test::device_value(*d, "bias_z_urad_s")), -3491.0, 300.0);
}

TEST(SmoothBaseBias, TheLearningReplaysBitForBit) {
  // The loop's learner decides on the order the loop took the wheels' and
  // the IMU's samples in, which a HAL recording fixes: its replay learns
  // the same bits and publishes the same outputs.
  const std::string path = testing::TempDir() + "rtfuse_smooth_base_" + std::to_string(::getpid()) + ".lcm";
  const std::string text = robot_text(true);
  const RuntimeConfig cfg = robot(true);
  DriveOptions opt;
  opt.scenario_path = kSlowTurns;
  opt.record_path = path;
  opt.config_text = text;
  const DriveResult drive = run_sim_drive(cfg, opt, nullptr);
  ASSERT_TRUE(drive.ok) << drive.error;
  ASSERT_EQ(drive.recording_lost, 0);
  transport::EventLogReader reader;
  std::string err;
  ASSERT_TRUE(reader.open(path, &err)) << err;
  HalRecording rec;
  ASSERT_TRUE(load_hal_recording(reader, {}, &rec, &err)) << err;
  const HalReplayResult r = replay_hal_recording(rec, cfg, nullptr, nullptr);
  std::remove(path.c_str());
  ASSERT_TRUE(r.ok) << r.error << r.note;
  EXPECT_FALSE(r.diverged);
  EXPECT_GT(r.compared, 9000);  // 92 s of 50 Hz odometry, pose, tf, raw wheels
  EXPECT_EQ(r.identical, r.compared) << r.first_mismatch;
  EXPECT_EQ(std::memcmp(r.final.state, drive.final.state, sizeof r.final.state), 0);
  // The learner's slot, every counter and the bias, as recorded.
  ASSERT_EQ(r.final.num_devices, drive.final.num_devices);
  const DeviceStatus* replayed = test::find_device(r.final, "gyro bias imu");
  const DeviceStatus* recorded = test::find_device(drive.final, "gyro bias imu");
  ASSERT_NE(replayed, nullptr);
  ASSERT_NE(recorded, nullptr);
  EXPECT_GT(test::device_value(*recorded, "blocks"), 0);
  for (int k = 0; k < recorded->num_values; ++k) {
    EXPECT_EQ(replayed->values[k], recorded->values[k]) << recorded->keys[k];
  }
}

}  // namespace smooth_base_bias_test
}  // namespace rtfuse::sim
