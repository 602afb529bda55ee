// config/sim_lcm.toml (the LCM-level simulated robot): it loads, it matches the simulated robot it configures,
// and the fusion it asks for does better than the robot's own odometry.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "geometry/rotation.hpp"
#include "rtfuse/odometry_t.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "sim/sim_lcm_robot.hpp"

namespace rtfuse::sim {
namespace sim_config_test {

constexpr TimeNs kSec = 1'000'000'000;
constexpr double kPi = 3.14159265358979323846;

RuntimeConfig load_sim_toml() {
  const ConfigLoadResult r = load_config_file(RTFUSE_SOURCE_DIR "/config/sim_lcm.toml");
  for (const auto& e : r.errors) ADD_FAILURE() << e.to_string();
  return r.ok() ? *r.config : RuntimeConfig{};
}

int sensor_index(const RuntimeConfig& cfg, std::string_view name) {
  for (int i = 0; i < cfg.num_sensors; ++i)
    if (cfg.sensors[i].name == name) return i;
  return -1;
}

TEST(SimToml, LoadsWithoutErrorsAndMatchesTheSimulatedRobot) {
  const ConfigLoadResult r = load_config_file(RTFUSE_SOURCE_DIR "/config/sim_lcm.toml");
  for (const auto& e : r.errors) ADD_FAILURE() << e.to_string();
  ASSERT_TRUE(r.ok());
  const RuntimeConfig& cfg = *r.config;
  EXPECT_TRUE(cfg.sim.enabled);
  EXPECT_EQ(cfg.rate_hz, 200.0);
  EXPECT_EQ(cfg.world_frame, "odom");
  EXPECT_EQ(cfg.filter.sensor_timeout_s, 0.1);
  ASSERT_EQ(cfg.num_sensors, 2);

  // The sensors listen where the simulated robot talks.
  const int odom = sensor_index(cfg, "odom0"), imu = sensor_index(cfg, "imu0");
  ASSERT_GE(odom, 0);
  ASSERT_GE(imu, 0);
  EXPECT_EQ(cfg.sensors[odom].channel, cfg.sim.odom_channel);
  EXPECT_EQ(cfg.sensors[imu].channel, cfg.sim.imu_channel);
  EXPECT_EQ(cfg.sensors[odom].params.kind, est::SensorKind::kOdometry);
  EXPECT_EQ(cfg.sensors[imu].params.kind, est::SensorKind::kImu);
  EXPECT_EQ(cfg.sensors[odom].params.update_mask,
            est::mask_bit(est::kVx) | est::mask_bit(est::kVy) | est::mask_bit(est::kVyaw));
}

struct Rms {
  double sum_sq = 0.0;
  int n = 0;
  void add(double e) {
    sum_sq += e * e;
    ++n;
  }
  double value() const { return n ? std::sqrt(sum_sq / n) : 0.0; }
};

// Drives the sim through the same FusionCore as the daemon, in lockstep, and
// compares both the estimate and the raw wheel odometry with the truth.
TEST(SimToml, FusedEstimateBeatsRawWheelOdometry) {
  const RuntimeConfig cfg = load_sim_toml();
  ASSERT_TRUE(cfg.sim.enabled);
  std::string error;
  auto core = FusionCore::create(cfg, &error);
  ASSERT_NE(core, nullptr) << error;

  const TimeNs start = 500 * kSec;
  SimLcmRobot robot(cfg.sim, start);
  const TimeNs tick = sec_to_ns(1.0 / cfg.rate_hz);
  // Five laps (about three minutes): long enough for wheel odometry's heading
  // to wander well away while the AHRS yaw stays bounded.
  const TimeNs end = start + sec_to_ns(5 * robot.period_s());

  Rms est_pos, est_yaw, odom_pos, odom_yaw;
  double est_final = 0.0, odom_final = 0.0;
  SimMessage m{};
  for (TimeNs now = start; now <= end; now += tick) {
    while (robot.next_due(now, &m)) {
      if (cfg.sim.odom_channel == m.channel) {
        rtfuse::odometry_t o;
        ASSERT_GT(o.decode(m.data, 0, m.size), 0);
        const TruthPose t = robot.truth(m.stamp);
        const double yaw = geometry::rpy_from_quaternion(Eigen::Quaterniond(
            o.pose.pose.orientation.w, o.pose.pose.orientation.x, o.pose.pose.orientation.y,
            o.pose.pose.orientation.z)).z();
        odom_final = std::hypot(o.pose.pose.position.x - t.x, o.pose.pose.position.y - t.y);
        odom_pos.add(odom_final);
        odom_yaw.add(std::remainder(yaw - t.yaw, 2 * kPi));
      }
      core->input().on_message(m.channel, m.data, m.size, now);
    }
    core->tick(now, LoopStats{});
    Snapshot s;
    core->snapshot().load(s);
    if (!s.initialized || (now - start) % (20 * tick) != 0) continue;
    const TruthPose t = robot.truth(s.stamp_ns);
    est_final = std::hypot(s.state[est::kX] - t.x, s.state[est::kY] - t.y);
    est_pos.add(est_final);
    est_yaw.add(std::remainder(s.state[est::kYaw] - t.yaw, 2 * kPi));
  }
  std::printf("over %.0f s: position rms estimate %.3f m, odometry %.3f m (final %.3f vs %.3f); "
              "yaw rms estimate %.4f rad, odometry %.4f rad\n",
              ns_to_sec(end - start), est_pos.value(), odom_pos.value(), est_final, odom_final,
              est_yaw.value(), odom_yaw.value());
  ASSERT_GT(est_pos.n, 100);
  EXPECT_EQ(core->filter().initialized(), true);
  EXPECT_LT(est_pos.value(), odom_pos.value());
  EXPECT_LT(est_yaw.value(), odom_yaw.value());
}

}  // namespace sim_config_test
}  // namespace rtfuse::sim
