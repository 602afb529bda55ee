// The IMU's gyro bias on a smooth base (config/scenarios/slow_turns.toml):
// two slow arcs between standstills with no vibration, run on
// config/sim.toml in lockstep through the real drivers and FusionCore.
// With the driver's IMU-only stillness learner the arcs are learnt as
// bias; with it off and the wheels' standstills teaching the bias in the
// loop (standstill_from), they are not.
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "runtime/config/config_loader.hpp"
#include "sim/sim_drive.hpp"
#include "support/sim_toml.hpp"

namespace rtfuse::sim {
namespace smooth_base_bias_test {

const std::string kSimToml = RTFUSE_SOURCE_DIR "/config/sim.toml";
const std::string kSlowTurns = RTFUSE_SOURCE_DIR "/config/scenarios/slow_turns.toml";

// config/sim.toml without the camera; with `wheels_teach`, the driver's
// learner off and the imu sensor learning from the wheels.
RuntimeConfig robot(bool wheels_teach) {
  std::string text = test::sim_toml_text(false);
  if (wheels_teach) {
    const std::size_t attitude = text.find("[mpu.attitude]\n");
    EXPECT_NE(attitude, std::string::npos);
    text.insert(attitude + 15, "stillness_bias = false\n");
    const std::size_t imu = text.find("name = \"imu\"");
    EXPECT_NE(imu, std::string::npos);
    text.insert(text.find("\n\n", imu), "\nstandstill_from = \"wheels\"");
  }
  const ConfigLoadResult r = load_config_string(text, kSimToml);
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
  const Snapshot& s = wheels.final;
  int slot = -1;
  for (int i = 0; i < s.num_devices; ++i) {
    if (std::string(s.devices[i].name.view()) == "gyro bias imu") slot = i;
  }
  ASSERT_GE(slot, 0);
  const DeviceStatus& d = s.devices[slot];
  EXPECT_GE(d.values[0], 10) << "blocks";
  EXPECT_NEAR(static_cast<double>(d.values[6]), -3491.0, 300.0) << "bias_z_urad_s";
}

}  // namespace smooth_base_bias_test
}  // namespace rtfuse::sim
