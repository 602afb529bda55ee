// Two filter instances in one loop, as robot_localization's dual EKF: a local
// one in odom (wheels + IMU) and a global one in map (the same plus GNSS),
// which publishes map -> odom. Through the real input path (LCM bytes ->
// InputRouter -> one ring per input -> FusionCore) and the real Publisher.
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "estimation/geodesy.hpp"
#include "geometry/rotation.hpp"
#include "rtfuse/imu_t.hpp"
#include "rtfuse/navsat_fix_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "rtfuse/pose_with_covariance_stamped_t.hpp"
#include "rtfuse/tf_t.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/fusion/fusion_core.hpp"
#include "runtime/pipeline/publisher.hpp"
#include "support/alloc_counter.hpp"
#include "support/lcm_inputs.hpp"

namespace rtfuse {
namespace filter_instances_test {

// Wheels that under-read their speed by 10 %, an IMU with yaw, a GNSS
// antenna 0.5 m ahead of and 1 m above base_link.
constexpr const char* kLocal = R"(
[filter]
frequency = 50
sensor_timeout = 0.5
two_d_mode = true

[publish]
accept_set_pose = true

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

[[static_transform]]
parent = "base_link"
child = "gps"
translation = [0.5, 0.0, 1.0]
rpy = [0.0, 0.0, 0.0]
)";

constexpr const char* kGlobal = R"(
[[instance]]
name = "global"
world_frame = "map"
process_noise_covariance = [0.1, 0.1, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015]

[[instance.sensor]]
name = "odom0"
type = "odometry"
channel = "wheel/odom"
config = [false, false, false, false, false, false,
          true,  true,  false, false, false, true,
          false, false, false]

[[instance.sensor]]
name = "imu0"
type = "imu"
channel = "imu/data"
config = [false, false, false, false, false, true,
          false, false, false, false, false, false,
          false, false, false]

[[instance.sensor]]
name = "gps0"
type = "navsat"
channel = "gps/fix"
config = [true,  true,  false, false, false, false,
          false, false, false, false, false, false,
          false, false, false]
frame = "gps"
heading_imu = "imu0"
pose_rejection_threshold = 5.0
)";

const est::GeodeticPosition kStart{47.3977, 8.5456, 488.0};
constexpr TimeNs kT0 = 1'000'000'000;
constexpr TimeNs kStep = 20'000'000;  // 50 Hz

using test::encode;
const auto wheel = test::wheel_odometry;

std::vector<std::uint8_t> imu(TimeNs t) {
  rtfuse::imu_t m{};
  m.header.utime = ns_to_utime(t);
  m.header.frame_id = "base_link";
  m.orientation = {0.0, 0.0, 0.0, 1.0};
  for (int i = 0; i < 3; ++i) m.orientation_covariance[i * 4] = 1e-4;
  m.angular_velocity_covariance[0] = -1;
  m.linear_acceleration_covariance[0] = -1;
  return encode(m);
}

// The antenna's fix when base_link is at (east, 0) facing east.
std::vector<std::uint8_t> fix(TimeNs t, double east) {
  est::LocalTangentPlane plane;
  plane.reset(kStart);
  const est::GeodeticPosition p = plane.reverse(Eigen::Vector3d(east + 0.5, 0.0, 1.0));
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
  std::vector<Msg> all(const std::string& channel) const {
    std::vector<Msg> out;
    auto it = messages.find(channel);
    if (it == messages.end()) return out;
    for (const auto& bytes : it->second) {
      Msg m;
      EXPECT_EQ(m.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
      out.push_back(m);
    }
    return out;
  }
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> messages;
};

const auto load = test::load_config_text;

std::string errors_of(const std::string& text) {
  const ConfigLoadResult r = load_config_string(text, "t.toml");
  std::string all;
  for (const auto& e : r.errors) all += e.to_string() + "\n";
  return all;
}

struct Dual {
  explicit Dual(const std::string& text = std::string(kLocal) + kGlobal) : cfg(load(text)) {
    std::string err;
    core = FusionCore::create(cfg, &err);
    EXPECT_TRUE(core) << err;
    publisher = std::make_unique<Publisher>(core->config());
  }
  void send(const char* channel, const std::vector<std::uint8_t>& m, TimeNs t) {
    core->input().on_message(channel, m.data(), static_cast<int>(m.size()), t);
  }
  // One 50 Hz step at 1 m/s east (the wheels say 0.9), a fix every 10th
  // step when `fixes`; publishes what is due.
  void step(int i, bool fixes) {
    const TimeNs t = kT0 + i * kStep;
    send("wheel/odom", wheel(t, 0.9), t);
    send("imu/data", imu(t), t);
    if (fixes && i % 10 == 0) send("gps/fix", fix(t, 0.02 * i), t);
    core->tick(t, loop);
    publisher->poll(core->last_snapshot(), t, sink);
  }
  Snapshot snap() const {
    Snapshot s;
    core->snapshot().load(s);
    return s;
  }
  RuntimeConfig cfg;
  std::unique_ptr<FusionCore> core;
  std::unique_ptr<Publisher> publisher;
  CaptureSink sink;
  LoopStats loop;
};

TEST(FilterInstances, OneInputFeedsBothAndOnlyTheGlobalOneTakesFixes) {
  Dual d;
  ASSERT_TRUE(d.core);
  ASSERT_EQ(d.cfg.num_instances, 2);
  ASSERT_EQ(d.cfg.num_sensors, 5);
  // The global instance's odom0 and imu0 read the local ones' rings.
  EXPECT_EQ(sensor_input(d.cfg, 2), 0);
  EXPECT_EQ(sensor_input(d.cfg, 3), 1);
  EXPECT_EQ(sensor_input(d.cfg, 4), 4);
  EXPECT_STREQ(qualified_sensor_name(d.cfg, 4).c_str(), "global/gps0");
  for (int i = 0; i <= 1500; ++i) d.step(i, true);
  const Snapshot s = d.snap();
  // Wheels alone: 27 m after 30 s at a true 1 m/s.
  EXPECT_NEAR(s.state[est::kX], 27.0, 0.1);
  const InstanceSnapshot& g = s.instances[1];
  EXPECT_NEAR(g.state[est::kX], 30.0, 0.15);
  EXPECT_NEAR(g.state[est::kY], 0.0, 0.1);
  EXPECT_EQ(g.fixes_fused, 151);
  // One message, counted received once per input, fused once per instance.
  EXPECT_EQ(s.sensors[0].received, 1501);
  EXPECT_EQ(s.sensors[2].received, 1501);
  EXPECT_EQ(s.sensors[0].accepted, s.sensors[2].accepted);
  EXPECT_EQ(s.sensors[4].accepted, 151);
  // map -> odom = map -> base_link * (odom -> base_link)^-1: the 3 m the
  // wheels lost.
  ASSERT_TRUE(g.has_map_odom);
  EXPECT_NEAR(g.map_odom_translation[0], g.state[est::kX] - s.state[est::kX], 1e-6);
  EXPECT_NEAR(g.map_odom_translation[0], 3.0, 0.15);
  EXPECT_NEAR(g.map_odom_rotation[3], 1.0, 1e-6);
}

TEST(FilterInstances, TheLocalOutputNeverJumpsAndTheGlobalOneHasItsOwnChannels) {
  Dual d;
  ASSERT_TRUE(d.core);
  for (int i = 0; i <= 1000; ++i) d.step(i, true);
  const auto local = d.sink.all<rtfuse::odometry_t>("rtfuse/odometry");
  const auto global = d.sink.all<rtfuse::odometry_t>("rtfuse/global/odometry");
  ASSERT_GT(local.size(), 900u);
  ASSERT_GT(global.size(), 900u);
  EXPECT_EQ(global.front().header.frame_id, "map");
  EXPECT_EQ(local.front().header.frame_id, "odom");
  // 50 Hz outputs at 0.9 m/s (what the wheels say): 18 mm apart, never more.
  double largest = 0.0;
  for (std::size_t i = 1; i < local.size(); ++i) {
    largest = std::max(largest, std::abs(local[i].pose.pose.position.x - local[i - 1].pose.pose.position.x));
  }
  EXPECT_LT(largest, 0.02);
  EXPECT_GT(d.sink.count("rtfuse/global/pose"), 900u);
  EXPECT_GT(d.sink.count("rtfuse/global/state"), 150u);
  EXPECT_EQ(d.sink.count("rtfuse/gps/filtered"), 0u);
  const auto fixes = d.sink.all<rtfuse::navsat_fix_t>("rtfuse/global/gps/filtered");
  ASSERT_GT(fixes.size(), 150u);
  // The global estimate as a fix: base_link's position, 20 m east at the end.
  est::LocalTangentPlane plane;
  plane.reset(kStart);
  const Eigen::Vector3d enu = plane.forward({fixes.back().latitude, fixes.back().longitude, fixes.back().altitude});
  EXPECT_NEAR(enu.x(), 20.0, 0.2);
  EXPECT_NEAR(enu.y(), 0.0, 0.1);
  // tf: odom -> base_link from the local instance, map -> odom from the
  // global one, on the one tf channel.
  int map_odom = 0, odom_base = 0;
  for (const auto& m : d.sink.all<rtfuse::tf_t>("rtfuse/tf")) {
    const auto& t = m.transforms[0];
    if (t.header.frame_id == "map" && t.child_frame_id == "odom") ++map_odom;
    if (t.header.frame_id == "odom" && t.child_frame_id == "base_link") ++odom_base;
    EXPECT_FALSE(t.header.frame_id == "map" && t.child_frame_id == "base_link");
  }
  EXPECT_GT(map_odom, 900);
  EXPECT_GT(odom_base, 900);
}

TEST(FilterInstances, TheGlobalInstancePublishesNothingBeforeItsFirstFix) {
  Dual d;
  ASSERT_TRUE(d.core);
  for (int i = 0; i <= 200; ++i) d.step(i, false);
  Snapshot s = d.snap();
  EXPECT_TRUE(s.instances[1].initialized);
  EXPECT_TRUE(s.instances[1].awaiting_fix);
  EXPECT_FALSE(s.instances[1].has_map_odom);
  EXPECT_GT(d.sink.count("rtfuse/odometry"), 150u);
  EXPECT_EQ(d.sink.count("rtfuse/global/odometry"), 0u);
  EXPECT_EQ(d.sink.count("rtfuse/global/pose"), 0u);
  EXPECT_EQ(d.sink.count("rtfuse/global/gps/filtered"), 0u);
  for (const auto& m : d.sink.all<rtfuse::tf_t>("rtfuse/tf")) EXPECT_NE(m.transforms[0].header.frame_id, "map");
  // The first fix anchors it.
  for (int i = 201; i <= 260; ++i) d.step(i, true);
  s = d.snap();
  EXPECT_FALSE(s.instances[1].awaiting_fix);
  EXPECT_TRUE(s.instances[1].has_map_odom);
  EXPECT_GT(d.sink.count("rtfuse/global/odometry"), 0u);
}

TEST(FilterInstances, SetPoseResetsTheInstanceWhoseWorldFrameItNames) {
  Dual d;
  ASSERT_TRUE(d.core);
  for (int i = 0; i <= 300; ++i) d.step(i, true);
  const double global_x = d.snap().instances[1].state[est::kX];
  rtfuse::pose_with_covariance_stamped_t m{};
  m.header.utime = ns_to_utime(kT0 + 300 * kStep);
  m.header.frame_id = "odom";
  m.pose.pose.position.x = -5.0;
  m.pose.pose.orientation.w = 1.0;
  for (int i = 0; i < 6; ++i) m.pose.covariance[i * 7] = 1e-3;
  const auto bytes = encode(m);
  d.send("rtfuse/set_pose", bytes, kT0 + 300 * kStep);
  d.core->tick(kT0 + 300 * kStep + 1, d.loop);
  const Snapshot s = d.snap();
  EXPECT_NEAR(s.state[est::kX], -5.0, 1e-6);
  EXPECT_NEAR(s.instances[1].state[est::kX], global_x, 0.05);
  EXPECT_EQ(s.set_pose_count, 1);
  EXPECT_EQ(s.set_pose_rejected, 0);
}

TEST(FilterInstances, SteadyStateWithTwoInstancesAllocatesNothing) {
  Dual d;
  ASSERT_TRUE(d.core);
  std::vector<std::vector<std::uint8_t>> wheels, imus, fixes;
  for (int i = 0; i <= 400; ++i) {
    const TimeNs t = kT0 + i * kStep;
    wheels.push_back(wheel(t, 0.9));
    imus.push_back(imu(t));
    fixes.push_back(fix(t, 0.02 * i));
  }
  struct Counting : MessageSink {
    bool publish(const char*, const std::uint8_t*, int, TimeNs) override { return ++n > 0; }
    long n = 0;
  } sink;
  const auto step = [&](int i) {
    const TimeNs t = kT0 + i * kStep;
    d.send("wheel/odom", wheels[static_cast<std::size_t>(i)], t);
    d.send("imu/data", imus[static_cast<std::size_t>(i)], t);
    if (i % 10 == 0) d.send("gps/fix", fixes[static_cast<std::size_t>(i)], t);
    d.core->tick(t, d.loop);
    d.publisher->poll(d.core->last_snapshot(), t, sink);
  };
  for (int i = 0; i < 100; ++i) step(i);
  test::AllocScope scope;
  for (int i = 100; i <= 400; ++i) step(i);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(sink.n, 1000);
}

TEST(FilterInstancesConfig, WithoutInstancesTheConfigIsTheFirstInstanceAlone) {
  const RuntimeConfig cfg = load(kLocal);
  EXPECT_EQ(cfg.num_instances, 1);
  EXPECT_STREQ(cfg.instances[0].name.c_str(), "local");
  EXPECT_EQ(sensor_input(cfg, 1), 1);
  const RuntimeConfig named = load(std::string(kLocal).replace(std::string(kLocal).find("[filter]\n"), 9,
                                                               "[filter]\nname = \"odom_ekf\"\n"));
  EXPECT_STREQ(named.instances[0].name.c_str(), "odom_ekf");
}

TEST(FilterInstancesConfig, AnInstanceInheritsFilterKeysItDoesNotSet) {
  const RuntimeConfig cfg = load(std::string(kLocal) + kGlobal);
  ASSERT_EQ(cfg.num_instances, 2);
  const est::FilterParams& g = cfg.instances[1].filter;
  EXPECT_TRUE(g.two_d_mode);
  EXPECT_DOUBLE_EQ(g.sensor_timeout_s, 0.5);
  EXPECT_DOUBLE_EQ(g.process_noise(0, 0), 0.1);
  EXPECT_DOUBLE_EQ(cfg.filter.process_noise(0, 0), 0.05);
  EXPECT_STREQ(cfg.instances[1].odometry_channel.c_str(), "rtfuse/global/odometry");
  EXPECT_STREQ(cfg.instances[1].filtered_fix_channel.c_str(), "rtfuse/global/gps/filtered");
  EXPECT_EQ(cfg.sensors[4].instance, 1);
}

TEST(FilterInstancesConfig, EachMistakeIsNamed) {
  const std::string base = std::string(kLocal) + kGlobal;
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string t = base;
    const std::size_t at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return errors_of(t.replace(at, from.size(), to));
  };
  EXPECT_EQ(errors_of(base), "");
  EXPECT_NE(with("name = \"global\"", "name = \"Global/1\"").find("instance[0].name: must be 1 to 15 characters"),
            std::string::npos);
  EXPECT_NE(with("name = \"global\"", "name = \"local\"").find("instance name 'local' is also the first instance's"),
            std::string::npos);
  EXPECT_NE(with("world_frame = \"map\"", "world_frame = \"earth\"").find("instance[0].world_frame: must equal"),
            std::string::npos);
  // The same channel as a local sensor, of another type.
  const std::string e = with("name = \"imu0\"\ntype = \"imu\"\nchannel = \"imu/data\"\nconfig = [false, false, false, "
                             "false, false, true,\n          false, false, false, false, false, false,\n          "
                             "false, false, false]\n\n[[instance.sensor]]",
                             "name = \"imu0\"\ntype = \"odometry\"\nchannel = \"imu/data\"\nconfig = [false, false, "
                             "false, false, false, true,\n          false, false, false, false, false, false,\n          "
                             "false, false, false]\n\n[[instance.sensor]]");
  EXPECT_NE(e.find("instance[0].sensor[1].channel: channel 'imu/data' is sensor[1] of type 'imu'"), std::string::npos)
      << e;
  // heading_imu names a sensor of its own instance.
  const std::string h = with("heading_imu = \"imu0\"\npose", "heading_imu = \"imu7\"\npose");
  EXPECT_NE(h.find("no sensor in instance 'global' is named 'imu7'"), std::string::npos) << h;
  EXPECT_NE(errors_of(base + "[[instance]]\nname = \"third\"\nworld_frame = \"map\"\n").find("missing"),
            std::string::npos);
  EXPECT_NE(errors_of(base + "[[instance]]\nname = \"g2\"\nbogus = 1\n[[instance.sensor]]\n").find("bogus"),
            std::string::npos);
  std::string too_many = base;
  for (const char* n : {"b", "c", "d"}) {
    too_many += std::string("[[instance]]\nname = \"") + n +
                "\"\n[[instance.sensor]]\nname = \"w\"\ntype = \"odometry\"\nchannel = \"wheel/odom\"\n"
                "config = [false, false, false, false, false, false, true, false, false, false, false, false, "
                "false, false, false]\n";
  }
  EXPECT_NE(errors_of(too_many).find("instance: at most 2 entries"), std::string::npos) << errors_of(too_many);
}

}  // namespace filter_instances_test
}  // namespace rtfuse
