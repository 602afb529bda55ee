// FusionCore through its real input path: encoded LCM messages -> InputRouter
// -> rings -> tick -> snapshot.
#include "runtime/fusion/fusion_core.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "geometry/rotation.hpp"
#include "rtfuse/odometry_t.hpp"
#include "rtfuse/pose_with_covariance_stamped_t.hpp"
#include "runtime/config/config_loader.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse {
namespace fusion_core_test {

constexpr const char* kTwoYawSources = R"(
[filter]
frequency = 100
sensor_timeout = 0.5

[[sensor]]
name = "odom0"
type = "odometry"
channel = "odom"
config = [false, false, false, false, false, true,
          true,  false, false, false, false, true,
          false, false, false]

[[sensor]]
name = "odom1"
type = "odometry"
channel = "compass"
config = [false, false, false, false, false, true,
          false, false, false, false, false, false,
          false, false, false]
queue_size = 2
)";

RuntimeConfig load(const char* text) {
  ConfigLoadResult r = load_config_string(text, "test.toml");
  if (!r.config) {
    for (const auto& e : r.errors) ADD_FAILURE() << e.to_string();
  }
  return *r.config;
}

std::vector<std::uint8_t> odometry(TimeNs t, double yaw, double vx) {
  rtfuse::odometry_t m{};
  m.header.utime = ns_to_utime(t);
  m.header.frame_id = "odom";
  m.child_frame_id = "base_link";
  const Eigen::Quaterniond q = geometry::quaternion_from_rpy(0, 0, yaw);
  m.pose.pose.orientation = {q.x(), q.y(), q.z(), q.w()};
  for (int i = 0; i < 6; ++i) {
    m.pose.covariance[i * 7] = 0.01;
    m.twist.covariance[i * 7] = 0.01;
  }
  m.twist.twist.linear.x = vx;
  std::vector<std::uint8_t> buf(m.getEncodedSize());
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

Snapshot snap(const FusionCore& core) {
  Snapshot s;
  core.snapshot().load(s);
  return s;
}

TEST(FusionCore, ConflictingAbsoluteYawIsGatedNotAveraged) {
  std::string err;
  auto core = FusionCore::create(load(kTwoYawSources), &err);
  ASSERT_TRUE(core) << err;
  LoopStats loop;
  TimeNs t = 1'000'000'000;
  for (int i = 0; i < 200; ++i, t += 10'000'000) {
    auto a = odometry(t, 0.0, 0.0);
    ASSERT_TRUE(core->input().on_message("odom", a.data(), static_cast<int>(a.size()), t));
    if (i % 5 == 0) {
      auto b = odometry(t, 1.0, 0.0);  // a compass 1 rad off
      core->input().on_message("compass", b.data(), static_cast<int>(b.size()), t);
    }
    core->tick(t, loop);
    EXPECT_LT(std::abs(snap(*core).state[5]), 0.05) << "yaw pulled away at step " << i;
  }
  const Snapshot s = snap(*core);
  EXPECT_GE(s.sensors[1].yaw_conflicts, 39);
  EXPECT_EQ(s.sensors[0].yaw_conflicts, 0);
}

TEST(FusionCore, MessageOlderThanThePreviousOfItsSensorIsRejected) {
  std::string err;
  auto core = FusionCore::create(load(kTwoYawSources), &err);
  ASSERT_TRUE(core) << err;
  LoopStats loop;
  auto m1 = odometry(2'000'000'000, 0.0, 1.0);
  auto m0 = odometry(1'000'000'000, 0.0, 1.0);  // time goes backwards
  core->input().on_message("odom", m1.data(), static_cast<int>(m1.size()), 2'000'000'000);
  core->tick(2'000'000'000, loop);
  core->input().on_message("odom", m0.data(), static_cast<int>(m0.size()), 2'005'000'000);
  core->tick(2'010'000'000, loop);
  const Snapshot s = snap(*core);
  EXPECT_EQ(s.sensors[0].accepted, 1);
  EXPECT_EQ(s.sensors[0].rejected_invalid, 1);
}

TEST(FusionCore, RingOverflowIsCountedNotHidden) {
  std::string err;
  auto core = FusionCore::create(load(kTwoYawSources), &err);
  ASSERT_TRUE(core) << err;
  // Within the compass's rate (2 x queue_size x 100 Hz = 400 Hz), faster
  // than the loop drains: the ring (2 x queue_size = 4) overflows.
  for (int i = 0; i < 10; ++i) {
    auto b = odometry(1'000'000'000 + i, 0.0, 0.0);
    core->input().on_message("compass", b.data(), static_cast<int>(b.size()), 1'000'000'000 + i * 2'500'000LL);
  }
  core->tick(1'100'000'000, LoopStats{});
  const Snapshot s = snap(*core);
  EXPECT_EQ(s.sensors[1].received, 10);
  EXPECT_EQ(s.sensors[1].rejected_overflow, 6);
  EXPECT_EQ(s.sensors[1].accepted, 4);
}

std::vector<std::uint8_t> set_pose_message(TimeNs t) {
  rtfuse::pose_with_covariance_stamped_t p{};
  p.header.utime = ns_to_utime(t);
  p.header.frame_id = "odom";
  p.pose.pose.position = {5.0, -2.0, 0.0};
  const Eigen::Quaterniond q = geometry::quaternion_from_rpy(0, 0, 0.5);
  p.pose.pose.orientation = {q.x(), q.y(), q.z(), q.w()};
  for (int i = 0; i < 6; ++i) p.pose.covariance[i * 7] = 0.1;
  std::vector<std::uint8_t> buf(p.getEncodedSize());
  p.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

TEST(FusionCore, SetPoseChannelResetsTheEstimate) {
  std::string err;
  RuntimeConfig cfg = load(kTwoYawSources);
  cfg.publish.accept_set_pose = true;
  auto core = FusionCore::create(cfg, &err);
  ASSERT_TRUE(core) << err;
  TimeNs t = 1'000'000'000;
  for (int i = 0; i < 100; ++i, t += 10'000'000) {
    auto a = odometry(t, 0.0, 1.0);
    core->input().on_message("odom", a.data(), static_cast<int>(a.size()), t);
    core->tick(t, LoopStats{});
  }
  EXPECT_GT(snap(*core).state[0], 0.9);  // drove ~1 m

  const std::vector<std::uint8_t> buf = set_pose_message(t);
  const char* channel = cfg.publish.set_pose_channel.c_str();
  ASSERT_TRUE(core->input().on_message(channel, buf.data(), static_cast<int>(buf.size()), t));
  core->tick(t, LoopStats{});
  const Snapshot s = snap(*core);
  EXPECT_NEAR(s.state[0], 5.0, 1e-9);
  EXPECT_NEAR(s.state[1], -2.0, 1e-9);
  EXPECT_NEAR(s.state[5], 0.5, 1e-9);
  EXPECT_EQ(s.state[6], 0.0);  // velocities restart at zero
  EXPECT_NEAR(s.covariance[0], 0.1, 1e-12);
  EXPECT_EQ(s.set_pose_count, 1);
}

TEST(FusionCore, SetPoseIsIgnoredAndCountedUnlessAccepted) {
  // LCM has no authentication: by default a set_pose from anyone on the
  // group changes nothing, and diagnostics count it.
  std::string err;
  const RuntimeConfig cfg = load(kTwoYawSources);
  ASSERT_FALSE(cfg.publish.accept_set_pose);
  auto core = FusionCore::create(cfg, &err);
  ASSERT_TRUE(core) << err;
  const std::vector<std::uint8_t> buf = set_pose_message(1'000'000'000);
  EXPECT_TRUE(core->input().on_message("rtfuse/set_pose", buf.data(), static_cast<int>(buf.size()), 1'000'000'000));
  core->tick(1'000'000'000, LoopStats{});
  const Snapshot s = snap(*core);
  EXPECT_EQ(s.set_pose_count, 0);
  EXPECT_EQ(s.set_pose_ignored, 1);
  EXPECT_EQ(s.state[0], 0.0);
}

TEST(FusionCore, SetPoseBeyondItsRingIsCountedAsRejected) {
  // Six between two ticks: the ring holds four, the other two are counted.
  std::string err;
  RuntimeConfig cfg = load(kTwoYawSources);
  cfg.publish.accept_set_pose = true;
  auto core = FusionCore::create(cfg, &err);
  ASSERT_TRUE(core) << err;
  const TimeNs t = 1'000'000'000;
  for (int i = 0; i < 6; ++i) {
    const std::vector<std::uint8_t> buf = set_pose_message(t + i);
    core->input().on_message("rtfuse/set_pose", buf.data(), static_cast<int>(buf.size()), t + i);
  }
  core->tick(t + 10, LoopStats{});
  const Snapshot s = snap(*core);
  EXPECT_EQ(s.set_pose_count, 4);
  EXPECT_EQ(s.set_pose_rejected, 2);
}

TEST(FusionCore, AFloodIsRateLimitedBeforeDecodingAndOversizeMessagesAreDropped) {
  // odom: queue_size 10 at 100 Hz, so 2000 messages/s with a burst of 20.
  std::string err;
  const RuntimeConfig cfg = load(kTwoYawSources);
  EXPECT_DOUBLE_EQ(cfg.sensors[0].max_rate_hz, 2000.0);
  auto core = FusionCore::create(cfg, &err);
  ASSERT_TRUE(core) << err;
  const TimeNs t0 = 1'000'000'000;
  // 1000 copies in one millisecond: the burst of 20 and the 2 the rate adds.
  for (int i = 0; i < 1000; ++i) {
    auto a = odometry(t0 + i, 0.0, 1.0);
    core->input().on_message("odom", a.data(), static_cast<int>(a.size()), t0 + i * 1000);
  }
  // Then one message well over [lcm] max_message_bytes (4096 by default).
  std::vector<std::uint8_t> big = odometry(t0 + 2'000'000, 0.0, 1.0);
  big.resize(5000, 0);
  core->input().on_message("odom", big.data(), static_cast<int>(big.size()), t0 + 2'000'000);
  core->tick(t0 + 2'000'000, LoopStats{});
  const Snapshot s = snap(*core);
  EXPECT_EQ(s.sensors[0].received, 1001);
  EXPECT_EQ(s.sensors[0].rejected_rate, 1000 - 21);
  EXPECT_EQ(s.sensors[0].rejected_oversize, 1);
  EXPECT_EQ(s.sensors[0].rejected_overflow, 1);  // the 21st: the ring holds 20 and the loop has not ticked
  EXPECT_EQ(s.sensors[0].decode_errors, 0);

  // At its rate again, every message passes.
  for (int i = 0; i < 100; ++i) {
    const TimeNs t = t0 + 1'000'000'000 + i * 10'000'000LL;
    auto a = odometry(t, 0.0, 1.0);
    core->input().on_message("odom", a.data(), static_cast<int>(a.size()), t);
    core->tick(t, LoopStats{});
  }
  EXPECT_EQ(snap(*core).sensors[0].rejected_rate, 1000 - 21);
}

TEST(FusionCore, AStampFurtherAheadOfItsArrivalThanTheWindowIsDropped) {
  // The daemon_input fuzzer's finding: one sender stamping in the future
  // moved the filter's time on and made the honest sensors stale.
  std::string err;
  auto core = FusionCore::create(load(kTwoYawSources), &err);  // [lcm] max_stamp_ahead: 0.5 s by default
  ASSERT_TRUE(core) << err;
  const TimeNs t0 = 1'000'000'000;
  auto honest = odometry(t0, 0.0, 1.0);
  auto early = odometry(t0 + 500'000'000, 0.0, 1.0);        // at the window's edge: taken
  auto future = odometry(t0 + 501'000'000 + 10'000'000, 0.0, 1.0);  // 1 ms beyond it: dropped
  auto far = odometry(t0 + 3600LL * 1'000'000'000, 0.0, 1.0);
  core->input().on_message("odom", honest.data(), static_cast<int>(honest.size()), t0);
  core->input().on_message("odom", early.data(), static_cast<int>(early.size()), t0);
  core->input().on_message("odom", future.data(), static_cast<int>(future.size()), t0 + 10'000'000);
  core->input().on_message("odom", far.data(), static_cast<int>(far.size()), t0 + 10'000'000);
  core->tick(t0 + 600'000'000, LoopStats{});
  Snapshot s = snap(*core);
  EXPECT_EQ(s.sensors[0].received, 4);
  EXPECT_EQ(s.sensors[0].accepted, 2);
  EXPECT_EQ(s.sensors[0].rejected_invalid, 2);
  // The filter's time did not jump an hour: a message of now is still fused.
  for (int i = 1; i <= 10; ++i) {
    const TimeNs t = t0 + 600'000'000 + i * 10'000'000LL;
    auto a = odometry(t, 0.0, 1.0);
    core->input().on_message("odom", a.data(), static_cast<int>(a.size()), t);
    core->tick(t, LoopStats{});
  }
  s = snap(*core);
  EXPECT_EQ(s.sensors[0].accepted, 12);
  EXPECT_EQ(s.sensors[0].rejected_stale, 0);
}

TEST(FusionCore, TheStampWindowIsConfigurable) {
  std::string text = kTwoYawSources;
  text = "[lcm]\nmax_stamp_ahead = 0.05\n" + text;
  const RuntimeConfig cfg = load(text.c_str());
  EXPECT_EQ(cfg.lcm_max_stamp_ahead_ns, 50'000'000);
  std::string err;
  auto core = FusionCore::create(cfg, &err);
  ASSERT_TRUE(core) << err;
  const TimeNs t0 = 1'000'000'000;
  auto a = odometry(t0 + 60'000'000, 0.0, 1.0);
  core->input().on_message("odom", a.data(), static_cast<int>(a.size()), t0);
  core->tick(t0 + 100'000'000, LoopStats{});
  EXPECT_EQ(snap(*core).sensors[0].rejected_invalid, 1);
  const ConfigLoadResult bad = load_config_string("[lcm]\nmax_stamp_ahead = 0\n" + std::string(kTwoYawSources), "t.toml");
  ASSERT_FALSE(bad.config);
  EXPECT_NE(bad.errors[0].to_string().find("max_stamp_ahead"), std::string::npos) << bad.errors[0].to_string();
}

TEST(FusionCore, UnknownChannelIsCounted) {
  std::string err;
  auto core = FusionCore::create(load(kTwoYawSources), &err);
  ASSERT_TRUE(core) << err;
  const std::uint8_t junk[4] = {1, 2, 3, 4};
  EXPECT_FALSE(core->input().on_message("nobody/listens", junk, 4, 1));
  core->tick(1, LoopStats{});
  EXPECT_EQ(snap(*core).unknown_channel_messages, 1);
}

TEST(FusionCore, SteadyStateTicksDoNotAllocate) {
  std::string err;
  auto core = FusionCore::create(load(kTwoYawSources), &err);
  ASSERT_TRUE(core) << err;
  std::vector<std::vector<std::uint8_t>> msgs;
  for (int i = 0; i < 300; ++i) msgs.push_back(odometry(1'000'000'000 + i * 10'000'000LL, 0.01 * i, 1.0));
  for (int i = 0; i < 10; ++i) {  // warm up: first decode sizes the strings
    core->input().on_message("odom", msgs[i].data(), static_cast<int>(msgs[i].size()), 1'000'000'000 + i * 10'000'000LL);
    core->tick(1'000'000'000 + i * 10'000'000LL, LoopStats{});
  }
  test::AllocScope scope;
  for (int i = 10; i < 300; ++i) {
    core->input().on_message("odom", msgs[i].data(), static_cast<int>(msgs[i].size()), 1'000'000'000 + i * 10'000'000LL);
    core->tick(1'000'000'000 + i * 10'000'000LL, LoopStats{});
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(snap(*core).sensors[0].accepted, 300);
}

// A driver-fed sensor: the loop's device hook pushes samples into the
// sensor's ring before the drain, the tick fuses them in the same tick, the
// consumed counters say how many each ring gave (what a recording stores per
// tick), and the hook's device statuses reach the snapshot.
class FakeWheels final : public TickDevices {
 public:
  explicit FakeWheels(FusionCore& core) : core_(core) {}
  int slot_count() const noexcept override { return 0; }
  void before_drain(TimeNs now) noexcept override {
    ++polls;
    if (polls % 2 != 0) return;  // a sample every other tick, like a slower SYNC
    est::SensorSample s;
    s.stamp = now;
    s.sensor = 0;
    s.kind = est::SensorKind::kTwist;
    s.frame = static_cast<std::int16_t>(core_.frames().find("base_link"));
    s.twist.linear.x() = 1.0;
    s.twist.covariance = est::Matrix6::Identity() * 1e-4;
    core_.input().ring(0).try_push(s);
  }
  void fill_snapshot(Snapshot& s) noexcept override {
    s.devices[0] = DeviceStatus{};
    s.devices[0].name = "fake wheels";
    s.devices[0].level = DeviceLevel::kOk;
    s.devices[0].add("polls", polls);
    s.num_devices = 1;
  }
  std::int64_t polls = 0;

 private:
  FusionCore& core_;
};

TEST(FusionCore, DeviceHookFeedsItsSensorInTheSameTick) {
  const char* text = R"(
[filter]
frequency = 100
two_d_mode = true
[hardware]
backend = "sim"
scenario = "none.toml"
[can]
[[can.node]]
node_id = 1
side = "left"
[[can.node]]
node_id = 2
side = "right"
[wheel_odometry]
track_width = 0.5
wheel_radius = 0.1
counts_per_rev = 1000
[[sensor]]
name = "wheels"
type = "twist"
source = "wheel_odometry"
config = [false, false, false, false, false, false, true, true, false, false, false, true, false, false, false]
)";
  std::string err;
  auto core = FusionCore::create(load(text), &err);
  ASSERT_TRUE(core) << err;
  FakeWheels wheels(*core);
  core->set_devices(&wheels);
  LoopStats loop;
  TimeNs t = 1'000'000'000;
  for (int i = 0; i < 100; ++i, t += 10'000'000) core->tick(t, loop);
  EXPECT_EQ(core->consumed()[0], 50);
  const Snapshot s = snap(*core);
  EXPECT_TRUE(s.initialized);
  EXPECT_NEAR(s.state[6], 1.0, 1e-3);  // vx
  EXPECT_EQ(s.sensors[0].accepted, 50);
  ASSERT_EQ(s.num_devices, 1);
  EXPECT_STREQ(s.devices[0].name.c_str(), "fake wheels");
  EXPECT_EQ(s.devices[0].values[0], 100);
}

}  // namespace fusion_core_test
}  // namespace rtfuse
