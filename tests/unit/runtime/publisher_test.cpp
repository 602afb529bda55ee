#include "runtime/pipeline/publisher.hpp"
#include "runtime/devices/device_layout.hpp"
#include "runtime/devices/device_registry.hpp"
#include "runtime/devices/wheel_encoders/wheel_encoder_device.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "geometry/rotation.hpp"
#include "rtfuse/diagnostics_t.hpp"
#include "rtfuse/filter_state_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "rtfuse/pose_with_covariance_stamped_t.hpp"
#include "rtfuse/tf_t.hpp"
#include "support/alloc_counter.hpp"
#include "support/eigen_no_malloc.hpp"

namespace rtfuse {
namespace publisher_test {

constexpr TimeNs kMs = 1'000'000;
// Copies: gtest binds by reference, and lcm-gen declares these constants
// in-class without a definition to bind to.
constexpr std::int8_t kOk = rtfuse::sensor_status_t::OK;
constexpr std::int8_t kWarn = rtfuse::sensor_status_t::WARN;
constexpr std::int8_t kError = rtfuse::sensor_status_t::ERROR;
constexpr std::int8_t kStale = rtfuse::sensor_status_t::STALE;

// Keeps every message's bytes, per channel, for decoding afterwards.
class CaptureSink : public MessageSink {
 public:
  bool publish(const char* channel, const std::uint8_t* data, int size, TimeNs) override {
    messages[channel].emplace_back(data, data + size);
    return true;
  }
  std::size_t count(const std::string& channel) const {
    auto it = messages.find(channel);
    return it == messages.end() ? 0 : it->second.size();
  }
  template <class Msg>
  Msg decode(const std::string& channel, std::size_t index) const {
    const auto& bytes = messages.at(channel).at(index);
    Msg m;
    EXPECT_EQ(m.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
    return m;
  }
  template <class Msg>
  Msg last(const std::string& channel) const {
    return decode<Msg>(channel, count(channel) - 1);
  }
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> messages;
};

// Allocation-free, for the steady-state check.
class CountingSink : public MessageSink {
 public:
  bool publish(const char*, const std::uint8_t*, int size, TimeNs) override {
    ++messages;
    bytes += size;
    return true;
  }
  long messages = 0;
  long bytes = 0;
};

RuntimeConfig two_sensor_config() {
  RuntimeConfig cfg;
  cfg.num_sensors = 2;
  cfg.sensors[0].name = "odom0";
  cfg.sensors[0].channel = "wheel/odom";
  cfg.sensors[1].name = "imu0";
  cfg.sensors[1].channel = "imu/data";
  return cfg;
}

// Distinct, recognisable values: state i = 0.1 * (i + 1), P(r, c) = r * 100 + c.
Snapshot known_snapshot() {
  Snapshot s;
  s.initialized = true;
  s.stamp_ns = 12'345'678'901;
  s.tick_time_ns = 12'350'000'000;
  for (int i = 0; i < 15; ++i) s.state[i] = 0.1 * (i + 1);
  s.state[5] = -2.5;  // a yaw far from zero catches roll/yaw mix-ups
  for (int r = 0; r < 15; ++r)
    for (int c = 0; c < 15; ++c) s.covariance[r * 15 + c] = r * 100 + c;
  s.num_sensors = 2;
  return s;
}

TEST(Publisher, OdometryCarriesPoseTwistAndCovarianceBlocks) {
  const RuntimeConfig cfg = two_sensor_config();
  Publisher pub(cfg);
  CaptureSink sink;
  const Snapshot s = known_snapshot();
  pub.poll(s, 20'000 * kMs, sink);

  ASSERT_EQ(sink.count("rtfuse/odometry"), 1u);
  const auto o = sink.last<rtfuse::odometry_t>("rtfuse/odometry");
  EXPECT_EQ(o.header.utime, 12'345'678);  // the estimate's stamp, not `now`
  EXPECT_EQ(o.header.seq, 0);
  EXPECT_EQ(o.header.frame_id, "odom");
  EXPECT_EQ(o.child_frame_id, "base_link");
  EXPECT_DOUBLE_EQ(o.pose.pose.position.x, 0.1);
  EXPECT_DOUBLE_EQ(o.pose.pose.position.y, 0.2);
  EXPECT_DOUBLE_EQ(o.pose.pose.position.z, s.state[2]);

  const Eigen::Quaterniond q(o.pose.pose.orientation.w, o.pose.pose.orientation.x,
                             o.pose.pose.orientation.y, o.pose.pose.orientation.z);
  EXPECT_NEAR(q.norm(), 1.0, 1e-12);
  const Eigen::Vector3d rpy = geometry::rpy_from_quaternion(q);
  EXPECT_NEAR(rpy.x(), s.state[3], 1e-12);
  EXPECT_NEAR(rpy.y(), s.state[4], 1e-12);
  EXPECT_NEAR(rpy.z(), -2.5, 1e-12);

  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      EXPECT_EQ(o.pose.covariance[r * 6 + c], r * 100 + c) << r << "," << c;
      EXPECT_EQ(o.twist.covariance[r * 6 + c], (r + 6) * 100 + (c + 6)) << r << "," << c;
    }
  }
  EXPECT_DOUBLE_EQ(o.twist.twist.linear.x, s.state[6]);
  EXPECT_DOUBLE_EQ(o.twist.twist.linear.y, s.state[7]);
  EXPECT_DOUBLE_EQ(o.twist.twist.linear.z, s.state[8]);
  EXPECT_DOUBLE_EQ(o.twist.twist.angular.x, s.state[9]);
  EXPECT_DOUBLE_EQ(o.twist.twist.angular.y, s.state[10]);
  EXPECT_DOUBLE_EQ(o.twist.twist.angular.z, s.state[11]);
  EXPECT_EQ(pub.encode_failures(), 0);
}

TEST(Publisher, PoseTfAndStateMatchTheSnapshot) {
  Publisher pub(two_sensor_config());
  CaptureSink sink;
  const Snapshot s = known_snapshot();
  EXPECT_EQ(pub.poll(s, 1 * kMs, sink), 5);  // first poll: every enabled output

  const auto odom = sink.last<rtfuse::odometry_t>("rtfuse/odometry");
  const auto pose = sink.last<rtfuse::pose_with_covariance_stamped_t>("rtfuse/pose");
  EXPECT_EQ(pose.header.utime, 12'345'678);
  EXPECT_EQ(pose.header.frame_id, "odom");
  EXPECT_EQ(pose.pose.pose.position.x, odom.pose.pose.position.x);
  EXPECT_EQ(pose.pose.pose.orientation.z, odom.pose.pose.orientation.z);
  for (int i = 0; i < 36; ++i) EXPECT_EQ(pose.pose.covariance[i], odom.pose.covariance[i]);

  const auto tf = sink.last<rtfuse::tf_t>("rtfuse/tf");
  ASSERT_EQ(tf.num_transforms, 1);
  EXPECT_EQ(tf.transforms[0].header.frame_id, "odom");
  EXPECT_EQ(tf.transforms[0].child_frame_id, "base_link");
  EXPECT_EQ(tf.transforms[0].header.utime, 12'345'678);
  EXPECT_EQ(tf.transforms[0].transform.translation.x, 0.1);
  EXPECT_EQ(tf.transforms[0].transform.translation.y, 0.2);
  EXPECT_EQ(tf.transforms[0].transform.rotation.w, odom.pose.pose.orientation.w);
  EXPECT_EQ(tf.transforms[0].transform.rotation.z, odom.pose.pose.orientation.z);

  const auto st = sink.last<rtfuse::filter_state_t>("rtfuse/state");
  EXPECT_TRUE(st.initialized);
  EXPECT_EQ(st.header.frame_id, "odom");
  EXPECT_EQ(st.child_frame_id, "base_link");
  for (int i = 0; i < 15; ++i) EXPECT_EQ(st.state[i], s.state[i]);
  for (int i = 0; i < 225; ++i) EXPECT_EQ(st.covariance[i], s.covariance[i]);
}

TEST(Publisher, RatesAreHonouredOverASimulatedSecond) {
  RuntimeConfig cfg = two_sensor_config();
  cfg.publish.odometry_rate_hz = 50.0;
  cfg.publish.pose_rate_hz = 30.0;  // not a divisor of the poll rate
  cfg.publish.tf_rate_hz = 0.0;     // disabled
  cfg.publish.state_rate_hz = 10.0;
  cfg.publish.diagnostics_rate_hz = 2.0;
  Publisher pub(cfg);
  CaptureSink sink;
  const Snapshot s = known_snapshot();
  const TimeNs start = 7'000 * kMs;
  int returned = 0;
  for (int i = 0; i < 1000; ++i) returned += pub.poll(s, start + i * kMs, sink);

  EXPECT_NEAR(static_cast<double>(sink.count("rtfuse/odometry")), 50.0, 1.0);
  EXPECT_NEAR(static_cast<double>(sink.count("rtfuse/pose")), 30.0, 1.0);
  EXPECT_EQ(sink.count("rtfuse/tf"), 0u);
  EXPECT_NEAR(static_cast<double>(sink.count("rtfuse/state")), 10.0, 1.0);
  EXPECT_NEAR(static_cast<double>(sink.count("rtfuse/diagnostics")), 2.0, 1.0);
  std::size_t total = 0;
  for (const auto& kv : sink.messages) total += kv.second.size();
  EXPECT_EQ(static_cast<std::size_t>(returned), total);

  // seq counts each output's own messages.
  const std::size_t n = sink.count("rtfuse/odometry");
  for (std::size_t i = 0; i < n; ++i)
    EXPECT_EQ(sink.decode<rtfuse::odometry_t>("rtfuse/odometry", i).header.seq, static_cast<int>(i));
  EXPECT_EQ(sink.last<rtfuse::filter_state_t>("rtfuse/state").header.seq,
            static_cast<int>(sink.count("rtfuse/state")) - 1);
}

TEST(Publisher, PublishTfFalseDisablesTf) {
  RuntimeConfig cfg = two_sensor_config();
  cfg.publish.publish_tf = false;
  cfg.publish.diagnostics_rate_hz = 0.0;
  Publisher pub(cfg);
  CaptureSink sink;
  const Snapshot s = known_snapshot();
  for (int i = 0; i < 500; ++i) pub.poll(s, i * kMs, sink);
  EXPECT_EQ(sink.count("rtfuse/tf"), 0u);
  EXPECT_EQ(sink.count("rtfuse/diagnostics"), 0u);
  EXPECT_NEAR(static_cast<double>(sink.count("rtfuse/odometry")), 25.0, 1.0);
}

TEST(Publisher, NothingButDiagnosticsBeforeInitialisation) {
  Publisher pub(two_sensor_config());
  CaptureSink sink;
  Snapshot s = known_snapshot();
  s.initialized = false;
  for (int i = 0; i < 1500; ++i) pub.poll(s, i * kMs, sink);
  EXPECT_EQ(sink.messages.size(), 1u);
  EXPECT_EQ(sink.count("rtfuse/diagnostics"), 2u);  // 1 Hz over 1.5 s: t = 0 and t = 1 s

  // The first initialised snapshot goes out at once, with seq 0.
  s.initialized = true;
  pub.poll(s, 1500 * kMs, sink);
  ASSERT_EQ(sink.count("rtfuse/odometry"), 1u);
  EXPECT_EQ(sink.last<rtfuse::odometry_t>("rtfuse/odometry").header.seq, 0);
  EXPECT_EQ(sink.count("rtfuse/pose"), 1u);
  EXPECT_EQ(sink.count("rtfuse/tf"), 1u);
  EXPECT_EQ(sink.count("rtfuse/state"), 1u);
}

TEST(Publisher, DiagnosticsLevelsAndNames) {
  RuntimeConfig cfg = two_sensor_config();
  cfg.num_sensors = 4;
  cfg.sensors[2].name = "pose0";
  cfg.sensors[2].channel = "vo/pose";
  cfg.sensors[3].name = "twist0";
  cfg.sensors[3].channel = "vo/twist";
  Publisher pub(cfg);
  CaptureSink sink;
  Snapshot s = known_snapshot();
  s.num_sensors = 4;
  s.loop.ticks = 1234;
  s.loop.overruns = 2;
  s.loop.jitter_max_ns = 5555;
  s.unknown_channel_messages = 7;
  s.set_pose_count = 1;
  // 0: healthy; 1: timed out; 2: rejecting; 3: never heard from.
  s.sensors[0].received = s.sensors[0].accepted = 100;
  s.sensors[0].last_stamp_ns = 999'999'999;
  s.sensors[0].rate_hz = 50.0;
  s.sensors[1].received = 10;
  s.sensors[1].timed_out = true;
  s.sensors[1].timeouts = 1;
  s.sensors[2].received = 20;
  s.sensors[2].rejected_mahalanobis = 3;

  const TimeNs t0 = 42'000 * kMs;
  pub.poll(s, t0, sink);
  auto d = sink.last<rtfuse::diagnostics_t>("rtfuse/diagnostics");
  EXPECT_EQ(d.header.utime, ns_to_utime(t0));  // diagnostics are stamped now
  EXPECT_EQ(d.loop.ticks, 1234);
  EXPECT_EQ(d.loop.overruns, 2);
  EXPECT_EQ(d.loop.jitter_max_ns, 5555);
  EXPECT_EQ(d.unknown_channel_messages, 7);
  EXPECT_EQ(d.set_pose_count, 1);
  ASSERT_EQ(d.num_sensors, 4);
  ASSERT_EQ(d.sensors.size(), 4u);
  EXPECT_EQ(d.sensors[0].name, "odom0");
  EXPECT_EQ(d.sensors[0].channel, "wheel/odom");
  EXPECT_EQ(d.sensors[3].name, "twist0");
  EXPECT_EQ(d.sensors[3].channel, "vo/twist");
  EXPECT_EQ(d.sensors[0].level, kOk);
  EXPECT_EQ(d.sensors[0].last_stamp_utime, 999'999);
  EXPECT_EQ(d.sensors[0].rate_hz, 50.0);
  EXPECT_EQ(d.sensors[0].accepted, 100);
  EXPECT_EQ(d.sensors[1].level, kError);
  EXPECT_TRUE(d.sensors[1].timed_out);
  EXPECT_EQ(d.sensors[2].level, kWarn);
  EXPECT_EQ(d.sensors[2].rejected_mahalanobis, 3);
  EXPECT_EQ(d.sensors[3].level, kStale);

  // No new rejections since the previous message: back to OK.
  pub.poll(s, t0 + 1000 * kMs, sink);
  d = sink.last<rtfuse::diagnostics_t>("rtfuse/diagnostics");
  EXPECT_EQ(d.header.seq, 1);
  EXPECT_EQ(d.sensors[2].level, kOk);

  // Any kind of rejection counts.
  s.sensors[2].rejected_stale = 1;
  pub.poll(s, t0 + 2000 * kMs, sink);
  EXPECT_EQ(sink.last<rtfuse::diagnostics_t>("rtfuse/diagnostics").sensors[2].level,
            kWarn);
}

TEST(Publisher, SteadyStatePollNeverAllocates) {
  RuntimeConfig cfg = two_sensor_config();
  cfg.publish.diagnostics_rate_hz = 100.0;  // exercise every output often
  cfg.publish.state_rate_hz = 100.0;
  Publisher pub(cfg);
  CountingSink sink;
  Snapshot s = known_snapshot();
  for (int i = 0; i < 10; ++i) pub.poll(s, i * kMs, sink);  // warm-up

  std::size_t allocations = 0;
  {
    test::EigenMallocForbidden eigen_no_malloc;
    test::AllocScope scope;
    for (int i = 10; i < 5000; ++i) {
      s.state[0] = 0.001 * i;
      s.sensors[1].rejected_invalid = i / 100;
      pub.poll(s, i * kMs, sink);
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(sink.messages, 1000);

  // The counter is live in this executable: a sink that stores does allocate.
  test::AllocScope probe;
  CaptureSink capture;
  pub.poll(s, 100'000 * kMs, capture);
  EXPECT_GT(probe.count(), 0u);
  EXPECT_EQ(pub.encode_failures(), 0);
}

// A robot with two encoder nodes and an IMU: the diagnostics carry one
// device_status_t per device with fixed keys, and only values, level, state
// and message change from message to message, without allocating.
TEST(Publisher, DeviceStatusesFollowTheSnapshot) {
  RuntimeConfig cfg = two_sensor_config();
  cfg.publish.diagnostics_rate_hz = 100.0;
  HardwareConfig& hw = cfg.hardware;
  hw.backend = HalBackend::kLinux;
  hw.can.enabled = true;
  hw.can.num_nodes = 2;
  hw.can.nodes[0].node_id = 1;
  hw.can.nodes[1].node_id = 2;
  hw.can.nodes[1].side = WheelSideConfig::kRight;
  hw.source_sensor[find_device_source("wheel_odometry")] = 0;
  hw.mpu.enabled = true;
  hw.source_sensor[find_device_source("mpu")] = 1;
  Publisher pub(cfg);

  Snapshot s = known_snapshot();
  s.num_devices = describe_devices(cfg, s.devices, kMaxDevices);
  ASSERT_EQ(s.num_devices, 5);  // bus, 2 nodes, wheel odometry, imu
  const int can = device_layout(cfg).first_slot[find_device_type("wheel_encoders")];
  const int imu = device_layout(cfg).first_slot[find_device_type("imu")];
  DeviceStatus& right = s.devices[can + 2];  // after the bus and the left node
  right.level = DeviceLevel::kError;
  right.state = "silent";
  right.values[0] = 123456;  // counts
  right.values[5] = 2;       // silent_events
  set_device_message(right.message, "node 2: no heartbeat for more than 350 ms");
  s.devices[imu].level = DeviceLevel::kOk;
  s.devices[imu].state = "sampling";

  CaptureSink sink;
  pub.poll(s, 1000 * kMs, sink);
  auto d = sink.last<rtfuse::diagnostics_t>("rtfuse/diagnostics");
  ASSERT_EQ(d.num_devices, 5);
  EXPECT_EQ(d.devices[0].name, "can bus");
  EXPECT_EQ(d.devices[0].hardware_id, "can0");
  EXPECT_EQ(d.devices[2].name, "wheel right node 2");
  EXPECT_EQ(d.devices[2].hardware_id, "can0 node 0x02");
  EXPECT_EQ(d.devices[2].level, kError);
  EXPECT_EQ(d.devices[2].state, "silent");
  ASSERT_EQ(d.devices[2].num_values, static_cast<int>(std::size(kEncoderNodeKeys)));
  EXPECT_EQ(d.devices[2].keys[0], "counts");
  EXPECT_EQ(d.devices[2].values[0], 123456);
  EXPECT_EQ(d.devices[2].keys[5], "silent_events");
  EXPECT_EQ(d.devices[2].values[5], 2);
  EXPECT_EQ(d.devices[2].message, "node 2: no heartbeat for more than 350 ms");
  EXPECT_EQ(d.devices[1].message, "") << "no error yet";
  EXPECT_EQ(d.devices[4].name, "imu");
  EXPECT_EQ(d.devices[4].hardware_id, "/dev/i2c-1 0x68");
  EXPECT_EQ(d.devices[4].state, "sampling");
  EXPECT_EQ(d.devices[4].level, kOk);

  // The node recovers: a longer state word, new values, a message as long
  // as a message gets (a longer text is cut, "..." at its end), no allocation.
  right.level = DeviceLevel::kOk;
  right.state = "operational-recovered";
  right.values[8] = 1;  // recoveries
  const std::string long_text = "node 2: " + std::string(300, 'x');
  set_device_message(right.message, long_text.c_str());
  ASSERT_EQ(right.message.size(), DeviceMessage::max_size());
  CountingSink counting;
  std::size_t allocations = 0;
  {
    test::AllocScope scope;
    for (int i = 0; i < 10; ++i) pub.poll(s, (1010 + 10 * i) * kMs, counting);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GE(counting.messages, 10);
  pub.poll(s, 2000 * kMs, sink);
  d = sink.last<rtfuse::diagnostics_t>("rtfuse/diagnostics");
  EXPECT_EQ(d.devices[2].state, "operational-recovered");
  EXPECT_EQ(d.devices[2].values[8], 1);
  EXPECT_EQ(d.devices[2].message, long_text.substr(0, DeviceMessage::max_size() - 3) + "...");
  // And back to a short one.
  set_device_message(right.message, "node 2: EMCY error code 0x8130, error register 0x11");
  pub.poll(s, 3000 * kMs, sink);
  d = sink.last<rtfuse::diagnostics_t>("rtfuse/diagnostics");
  EXPECT_EQ(d.devices[2].message, "node 2: EMCY error code 0x8130, error register 0x11");
  EXPECT_EQ(pub.encode_failures(), 0);
}

TEST(Publisher, RawWheelOdometryOncePerNewSample) {
  RuntimeConfig cfg = two_sensor_config();
  cfg.hardware.can.enabled = true;
  cfg.hardware.source_sensor[find_device_source("wheel_odometry")] = 0;
  cfg.hardware.wheel_odometry.raw_rate_hz = 1000.0;
  Publisher pub(cfg);
  CaptureSink sink;
  Snapshot s = known_snapshot();
  pub.poll(s, 0, sink);
  EXPECT_EQ(sink.count("rtfuse/wheel_odometry"), 0u);  // nothing valid yet
  s.wheel_odometry = WheelOdometrySnapshot{true, 5'000'000'000, 1.5, -2.0, 0.5, 0.8, 0.1, 1e-4, 4e-4};
  pub.poll(s, 10 * kMs, sink);
  pub.poll(s, 20 * kMs, sink);  // same sample: not repeated
  ASSERT_EQ(sink.count("rtfuse/wheel_odometry"), 1u);
  const auto o = sink.last<rtfuse::odometry_t>("rtfuse/wheel_odometry");
  EXPECT_EQ(o.header.utime, 5'000'000);
  EXPECT_EQ(o.header.frame_id, "odom");
  EXPECT_EQ(o.child_frame_id, "base_link");
  EXPECT_DOUBLE_EQ(o.pose.pose.position.x, 1.5);
  EXPECT_DOUBLE_EQ(o.pose.pose.position.y, -2.0);
  EXPECT_NEAR(2 * std::atan2(o.pose.pose.orientation.z, o.pose.pose.orientation.w), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(o.twist.twist.linear.x, 0.8);
  EXPECT_DOUBLE_EQ(o.twist.twist.angular.z, 0.1);
  EXPECT_DOUBLE_EQ(o.twist.covariance[35], 4e-4);
}

}  // namespace publisher_test
}  // namespace rtfuse
