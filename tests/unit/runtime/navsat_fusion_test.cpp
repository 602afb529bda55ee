// GNSS fixes through the loop's real input path (navsat_fix_t on LCM ->
// InputRouter -> ring -> FusionCore -> navsat transform -> EKF), with an
// IMU giving the datum's heading, as robot_localization's navsat_transform
// feeding an EKF does.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "estimation/geodesy.hpp"
#include "geometry/rotation.hpp"
#include "rtfuse/imu_t.hpp"
#include "rtfuse/navsat_fix_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/devices/device_layout.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "support/alloc_counter.hpp"
#include "support/lcm_inputs.hpp"

namespace rtfuse {
namespace navsat_fusion_test {

// Wheel odometry that under-reads its speed by 10 %, an IMU with yaw, and a
// GNSS antenna 0.5 m ahead of and 1 m above base_link.
constexpr const char* kConfig = R"(
[filter]
frequency = 50
sensor_timeout = 0.5
two_d_mode = true

[[sensor]]
name = "odom0"
type = "odometry"
channel = "wheel/odom"
config = [false, false, false, false, false, false,
          true,  true,  false, false, false, true,
          false, false, false]

[[sensor]]
name = "imu0"
type = "imu"
channel = "imu/data"
config = [false, false, false, false, false, true,
          false, false, false, false, false, false,
          false, false, false]

[[sensor]]
name = "gps0"
type = "navsat"
channel = "gps/fix"
config = [true,  true,  false, false, false, false,
          false, false, false, false, false, false,
          false, false, false]
frame = "gps"
heading_imu = "imu0"

[[static_transform]]
parent = "base_link"
child = "gps"
translation = [0.5, 0.0, 1.0]
rpy = [0.0, 0.0, 0.0]
)";

const est::GeodeticPosition kStart{47.3977, 8.5456, 488.0};

const auto load = test::load_config_text;

using test::encode;
const auto wheel = test::wheel_odometry;

std::vector<std::uint8_t> imu(TimeNs t, double yaw) {
  rtfuse::imu_t m{};
  m.header.utime = ns_to_utime(t);
  m.header.frame_id = "base_link";
  const Eigen::Quaterniond q = geometry::quaternion_from_rpy(0, 0, yaw);
  m.orientation = {q.x(), q.y(), q.z(), q.w()};
  for (int i = 0; i < 3; ++i) m.orientation_covariance[i * 4] = 1e-4;
  m.angular_velocity_covariance[0] = -1;
  m.linear_acceleration_covariance[0] = -1;
  return encode(m);
}

// The antenna's fix when base_link is at (east, north) facing east.
std::vector<std::uint8_t> fix(TimeNs t, double east, double north, double offset_east = 0.0) {
  est::LocalTangentPlane plane;
  plane.reset(kStart);
  const est::GeodeticPosition p = plane.reverse(Eigen::Vector3d(east + 0.5 + offset_east, north, 1.0));
  rtfuse::navsat_fix_t m{};
  m.header.utime = ns_to_utime(t);
  m.header.frame_id = "gps";
  m.status = rtfuse::navsat_fix_t::STATUS_FIX;
  m.latitude = p.latitude_deg;
  m.longitude = p.longitude_deg;
  m.altitude = p.altitude_m;
  m.position_covariance[0] = m.position_covariance[4] = 0.04;
  m.position_covariance[8] = 0.25;
  m.position_covariance_type = rtfuse::navsat_fix_t::COVARIANCE_TYPE_DIAGONAL_KNOWN;
  return encode(m);
}

struct Drive {
  explicit Drive(const std::string& config = kConfig) {
    std::string err;
    core = FusionCore::create(load(config), &err);
    EXPECT_TRUE(core) << err;
  }
  void send(const char* channel, const std::vector<std::uint8_t>& m, TimeNs t) {
    core->input().on_message(channel, m.data(), static_cast<int>(m.size()), t);
  }
  Snapshot snap() const {
    Snapshot s;
    core->snapshot().load(s);
    return s;
  }
  const DeviceStatus& navsat_device(const Snapshot& s) const {
    return s.devices[device_layout(core->config()).device_slots];
  }
  std::int64_t value(const DeviceStatus& d, const char* key) const {
    for (int i = 0; i < d.num_values; ++i) {
      if (std::string(d.keys[i]) == key) return d.values[i];
    }
    ADD_FAILURE() << "no key " << key;
    return -1;
  }
  std::unique_ptr<FusionCore> core;
};

TEST(NavsatFusion, FixesHoldTheEstimateWhereWheelsDrift) {
  Drive d;
  ASSERT_TRUE(d.core);
  LoopStats loop;
  // 1 m/s east for 30 s; the wheels say 0.9 m/s.
  for (int i = 0; i <= 1500; ++i) {
    const TimeNs t = 1'000'000'000 + i * 20'000'000LL;
    const double x = 0.02 * i;
    d.send("wheel/odom", wheel(t, 0.9), t);
    d.send("imu/data", imu(t, 0.0), t);
    if (i % 10 == 0) d.send("gps/fix", fix(t, x, 0.0), t);
    d.core->tick(t, loop);
  }
  const Snapshot s = d.snap();
  // Wheels alone would be 3 m short at 30 m.
  EXPECT_NEAR(s.state[est::kX], 30.0, 0.15);
  EXPECT_NEAR(s.state[est::kY], 0.0, 0.1);
  EXPECT_EQ(s.sensors[2].accepted, 151);
  const DeviceStatus& n = d.navsat_device(s);
  EXPECT_STREQ(n.name.c_str(), "navsat gps0");
  EXPECT_STREQ(n.state.c_str(), "datum set");
  EXPECT_EQ(n.level, DeviceLevel::kOk);
  EXPECT_EQ(d.value(n, "accepted"), 151);
  EXPECT_NE(std::string(n.message.c_str()).find("datum 47.39"), std::string::npos) << n.message.c_str();
}

TEST(NavsatFusion, WithoutAHeadingTheDatumWaitsAndSaysWhy) {
  Drive d;
  ASSERT_TRUE(d.core);
  LoopStats loop;
  for (int i = 0; i <= 50; ++i) {
    const TimeNs t = 1'000'000'000 + i * 20'000'000LL;
    d.send("wheel/odom", wheel(t, 0.0), t);
    if (i % 10 == 0) d.send("gps/fix", fix(t, 0.0, 0.0), t);
    d.core->tick(t, loop);
  }
  const Snapshot s = d.snap();
  const DeviceStatus& n = d.navsat_device(s);
  EXPECT_STREQ(n.state.c_str(), "waiting for a heading");
  EXPECT_EQ(n.level, DeviceLevel::kStale);
  EXPECT_EQ(d.value(n, "waiting_for_heading"), 6);
  EXPECT_EQ(s.sensors[2].rejected_invalid, 6);
  EXPECT_EQ(s.sensors[2].accepted, 0);
}

TEST(NavsatFusion, AMultipathJumpIsGatedAndCounted) {
  Drive d;
  ASSERT_TRUE(d.core);
  LoopStats loop;
  for (int i = 0; i <= 500; ++i) {
    const TimeNs t = 1'000'000'000 + i * 20'000'000LL;
    const double x = 0.02 * i;
    d.send("wheel/odom", wheel(t, 1.0), t);
    d.send("imu/data", imu(t, 0.0), t);
    // One fix 100 m east of the truth at 5 s.
    if (i % 10 == 0) d.send("gps/fix", fix(t, x, 0.0, i == 250 ? 100.0 : 0.0), t);
    d.core->tick(t, loop);
    if (i == 250) {
      const Snapshot s = d.snap();
      EXPECT_STREQ(d.navsat_device(s).message.c_str(), "last fix refused: jump");
      EXPECT_EQ(d.navsat_device(s).level, DeviceLevel::kWarn);
    }
  }
  const Snapshot s = d.snap();
  EXPECT_NEAR(s.state[est::kX], 10.0, 0.1);
  EXPECT_EQ(d.value(d.navsat_device(s), "jumps"), 1);
  EXPECT_EQ(d.navsat_device(s).level, DeviceLevel::kOk);
}

TEST(NavsatFusion, BadFixesAreCountedByReason) {
  Drive d;
  ASSERT_TRUE(d.core);
  LoopStats loop;
  TimeNs t = 1'000'000'000;
  d.send("imu/data", imu(t, 0.0), t);
  d.send("gps/fix", fix(t, 0.0, 0.0), t);
  d.core->tick(t, loop);
  rtfuse::navsat_fix_t bad{};
  bad.header.frame_id = "gps";
  bad.status = rtfuse::navsat_fix_t::STATUS_FIX;
  bad.position_covariance_type = 0;
  const auto send_bad = [&](double lat, double lon, std::int8_t status, std::int8_t type) {
    t += 200'000'000;
    bad.header.utime = ns_to_utime(t);
    bad.latitude = lat;
    bad.longitude = lon;
    bad.status = status;
    bad.position_covariance_type = type;
    d.send("gps/fix", encode(bad), t);
    d.core->tick(t, loop);
  };
  send_bad(NAN, 8.5, 0, 0);
  send_bad(95.0, 8.5, 0, 0);
  send_bad(47.3977, 8.5456, -1, 0);  // no fix
  send_bad(47.3977, 8.5456, 0, 9);   // no such covariance type
  send_bad(47.3977, 8.5456, 0, 2);   // diagonal known, all zero
  const Snapshot s = d.snap();
  const DeviceStatus& n = d.navsat_device(s);
  EXPECT_EQ(d.value(n, "invalid_position"), 2);
  EXPECT_EQ(d.value(n, "no_fix"), 1);
  EXPECT_EQ(d.value(n, "invalid_covariance"), 2);
  EXPECT_EQ(s.sensors[2].rejected_invalid, 5);
  for (int i = 0; i < est::kStateSize; ++i) EXPECT_TRUE(std::isfinite(s.state[i])) << i;
}

TEST(NavsatFusion, SteadyStateAllocatesNothing) {
  Drive d;
  ASSERT_TRUE(d.core);
  LoopStats loop;
  std::vector<std::vector<std::uint8_t>> fixes, wheels, imus;
  for (int i = 0; i <= 400; ++i) {
    const TimeNs t = 1'000'000'000 + i * 20'000'000LL;
    wheels.push_back(wheel(t, 1.0));
    imus.push_back(imu(t, 0.0));
    fixes.push_back(fix(t, 0.02 * i, 0.0));
  }
  const auto step = [&](int i) {
    const TimeNs t = 1'000'000'000 + i * 20'000'000LL;
    d.send("wheel/odom", wheels[static_cast<std::size_t>(i)], t);
    d.send("imu/data", imus[static_cast<std::size_t>(i)], t);
    if (i % 10 == 0) d.send("gps/fix", fixes[static_cast<std::size_t>(i)], t);
    d.core->tick(t, loop);
  };
  for (int i = 0; i < 100; ++i) step(i);
  test::AllocScope scope;
  for (int i = 100; i <= 400; ++i) step(i);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(d.snap().sensors[2].accepted, 30);
}

TEST(NavsatConfig, EachMistakeIsNamed) {
  const auto errors = [](const std::string& sensor) {
    const std::string text = std::string(R"(
[[sensor]]
name = "imu0"
type = "imu"
channel = "imu/data"
config = [false, false, false, false, false, true,
          false, false, false, false, false, false,
          false, false, false]

[[sensor]]
name = "gps0"
type = "navsat"
channel = "gps/fix"
)") + sensor;
    const ConfigLoadResult r = load_config_string(text, "t.toml");
    std::string all;
    for (const auto& e : r.errors) all += e.to_string() + "\n";
    return all;
  };
  const std::string xy = "config = [true, true, false, false, false, false, false, false, false, false, false, "
                         "false, false, false, false]\n";
  EXPECT_EQ(errors(xy + "heading_imu = \"imu0\"\n"), "");
  EXPECT_NE(errors(xy).find("the datum needs a heading"), std::string::npos) << errors(xy);
  EXPECT_NE(errors(xy + "heading_imu = \"imu9\"\n").find("no sensor is named 'imu9'"), std::string::npos);
  EXPECT_NE(errors(xy + "datum = [91.0, 8.0, 0.0]\n").find("latitude must be within"), std::string::npos);
  EXPECT_NE(errors(xy + "datum = [47.0, 8.0, 0.0]\nuse_odometry_yaw = true\n").find("give one heading source"),
            std::string::npos);
  const std::string with_yaw = "config = [true, true, false, false, false, true, false, false, false, false, "
                               "false, false, false, false, false]\nheading_imu = \"imu0\"\n";
  EXPECT_NE(errors(with_yaw).find("type 'navsat' cannot provide yaw"), std::string::npos) << errors(with_yaw);
  EXPECT_NE(errors(xy + "heading_imu = \"imu0\"\nmax_jump = -1\n").find("max_jump"), std::string::npos);
  // A navsat key on another type.
  const ConfigLoadResult r = load_config_string(R"(
[[sensor]]
name = "imu0"
type = "imu"
channel = "imu/data"
yaw_offset = 1.57
config = [false, false, false, false, false, true,
          false, false, false, false, false, false,
          false, false, false]
)", "t.toml");
  ASSERT_FALSE(r.config);
  EXPECT_NE(r.errors[0].to_string().find("only valid for type 'navsat'"), std::string::npos);
}

TEST(NavsatConfig, AnAntennaFrameOutsideTheTreeIsRefusedWithTheFix) {
  std::string text = kConfig;
  text = text.substr(0, text.find("[[static_transform]]"));
  std::string err;
  const auto core = FusionCore::create(load(text), &err);
  EXPECT_FALSE(core);
  EXPECT_NE(err.find("frame 'gps' is not connected to 'base_link'"), std::string::npos) << err;
}

}  // namespace navsat_fusion_test
}  // namespace rtfuse
