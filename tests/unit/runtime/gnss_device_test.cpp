// The GNSS receiver as a thread device on the mock serial port: fixes into
// the navsat sensor's ring at their epoch, health into diagnostics, and a
// receiver that is unplugged and comes back.
#include "runtime/devices/gnss/gnss_device.hpp"

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "hal/mock/mock_serial_port.hpp"
#include "hal/mock/sim_clock.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/devices/device_layout.hpp"
#include "support/alloc_counter.hpp"
#include "support/gnss_bytes.hpp"

namespace rtfuse {
namespace gnss_device_test {

constexpr TimeNs kMs = 1'000'000;

constexpr const char* kConfig = R"(
[hardware]
backend = "linux"

[gnss]
device = "/dev/ttyACM0"
latency = 0.12
silent_after = 1.0
reopen_backoff = 0.5
reopen_backoff_max = 2.0

[[sensor]]
name = "gps0"
type = "navsat"
source = "gnss"
use_odometry_yaw = true
config = [true,  true,  false, false, false, false,
          false, false, false, false, false, false,
          false, false, false]
)";

void put4(std::vector<std::uint8_t>& p, int at, std::int64_t v) {
  for (int i = 0; i < 4; ++i) p[static_cast<std::size_t>(at + i)] = static_cast<std::uint8_t>(v >> (8 * i));
}

// A u-blox NAV-PVT: 3-D fix, gnssFixOK, 1.5 m horizontal and 3 m vertical accuracy.
std::vector<std::uint8_t> nav_pvt(int sec, int fix_type = 3, int satellites = 14) {
  std::vector<std::uint8_t> p(92, 0);
  p[8] = 12;
  p[10] = static_cast<std::uint8_t>(sec);
  p[11] = 0x07;
  p[20] = static_cast<std::uint8_t>(fix_type);
  p[21] = 0x01;
  p[23] = static_cast<std::uint8_t>(satellites);
  put4(p, 24, 85456000);   // 8.5456 E
  put4(p, 28, 473977000);  // 47.3977 N
  put4(p, 32, 488000);     // 488 m
  put4(p, 40, 1500);
  put4(p, 44, 3000);
  return test::ubx_frame(0x01, 0x07, p);
}

struct Rig {
  Rig() {
    ConfigLoadResult r = load_config_string(kConfig, "gnss.toml");
    for (const auto& e : r.errors) ADD_FAILURE() << e.to_string();
    std::string err;
    core = FusionCore::create(*r.config, &err);
    EXPECT_TRUE(core) << err;
    slot = device_layout(core->config()).first_slot[find_device_type("gnss")];
    DeviceBuses buses;
    buses.serial = &port;
    buses.clock = &clock;
    device = GnssDevice::create(buses, *core, slot, &err);
    EXPECT_TRUE(device) << err;
  }
  void feed(const std::vector<std::uint8_t>& b, TimeNs at) {
    ASSERT_TRUE(port.feed(b.data(), static_cast<int>(b.size()), at));
  }
  // Steps as the device thread does until the clock reaches `until`.
  void run(TimeNs until) {
    while (clock.now() < until) {
      const TimeNs before = clock.now();
      device->step(std::min<TimeNs>(50 * kMs, until - before));
      if (clock.now() == before) clock.sleep_until(before + std::min<TimeNs>(50 * kMs, until - before));
    }
  }
  std::vector<est::SensorSample> drain() {
    std::vector<est::SensorSample> out;
    est::SensorSample s;
    while (core->input().ring(0).try_pop(s)) out.push_back(s);
    return out;
  }
  DeviceStatus status() {
    Snapshot s;
    device->fill_snapshot(s);
    return s.devices[slot];
  }
  std::int64_t value(const DeviceStatus& d, const char* key) {
    for (int i = 0; i < d.num_values; ++i) {
      if (std::string(d.keys[i]) == key) return d.values[i];
    }
    ADD_FAILURE() << "no key " << key;
    return -1;
  }
  hal::mock::SimClock clock{1000 * kMs};
  hal::mock::MockSerialPort port{clock};
  std::unique_ptr<FusionCore> core;
  int slot = -1;
  std::unique_ptr<GnssDevice> device;
};

TEST(GnssDevice, FixesReachTheNavsatRingAtTheirEpoch) {
  Rig r;
  ASSERT_TRUE(r.device);
  r.feed(nav_pvt(0), 1300 * kMs);
  r.feed(nav_pvt(1), 2300 * kMs);
  r.run(2500 * kMs);
  const std::vector<est::SensorSample> got = r.drain();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(r.device->samples(), 2);
  const est::SensorSample& s = got[0];
  EXPECT_EQ(s.kind, est::SensorKind::kNavSatFix);
  EXPECT_EQ(s.stamp, 1300 * kMs - 120 * kMs);  // arrival less the receiver's latency
  EXPECT_EQ(s.navsat.status, 0);
  EXPECT_NEAR(s.navsat.position.latitude_deg, 47.3977, 1e-9);
  EXPECT_NEAR(s.navsat.position.longitude_deg, 8.5456, 1e-9);
  EXPECT_NEAR(s.navsat.position.altitude_m, 488.0, 1e-9);
  EXPECT_EQ(s.navsat.covariance_type, 2);
  EXPECT_NEAR(s.navsat.covariance(0, 0), 2.25, 1e-12);
  EXPECT_NEAR(s.navsat.covariance(2, 2), 9.0, 1e-12);
  const DeviceStatus d = r.status();
  EXPECT_STREQ(d.name.c_str(), "");  // names come from the layout (Hardware fills them)
  EXPECT_STREQ(d.state.c_str(), "fix");
  EXPECT_EQ(d.level, DeviceLevel::kOk);
  EXPECT_EQ(r.value(d, "epochs"), 2);
  EXPECT_EQ(r.value(d, "fixes"), 2);
  EXPECT_EQ(r.value(d, "satellites"), 14);
}

TEST(GnssDevice, ATwoDFixHoldsNoAltitudeAndDeadReckoningIsNoFix) {
  Rig r;
  ASSERT_TRUE(r.device);
  r.feed(nav_pvt(0, 2), 1300 * kMs);
  r.feed(nav_pvt(1, 1), 2300 * kMs);  // the receiver's own dead reckoning
  r.run(2500 * kMs);
  const std::vector<est::SensorSample> got = r.drain();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].navsat.status, 0);
  EXPECT_GE(got[0].navsat.covariance(2, 2), 1e6);
  EXPECT_EQ(got[1].navsat.status, -1);
  const DeviceStatus d = r.status();
  EXPECT_EQ(r.value(d, "two_d"), 1);
  EXPECT_EQ(r.value(d, "dead_reckoning"), 1);
}

TEST(GnssDevice, AnUnpluggedReceiverIsReopenedWithBackoff) {
  Rig r;
  ASSERT_TRUE(r.device);
  r.feed(nav_pvt(0), 1100 * kMs);
  r.run(1200 * kMs);
  r.port.unplug();
  r.run(1300 * kMs);
  DeviceStatus d = r.status();
  EXPECT_STREQ(d.state.c_str(), "closed");
  EXPECT_EQ(d.level, DeviceLevel::kError);
  r.run(4000 * kMs);  // tries at +0.5, +1.0 (+0.5), +2.0 (+1.0) s: all fail
  EXPECT_EQ(r.value(r.status(), "reopens"), 0);
  r.port.replug();
  r.feed(nav_pvt(5), 6500 * kMs);
  r.run(7000 * kMs);
  d = r.status();
  EXPECT_EQ(r.value(d, "reopens"), 1);
  EXPECT_STREQ(d.state.c_str(), "fix");
  EXPECT_EQ(r.value(d, "epochs"), 2);
  EXPECT_EQ(r.drain().size(), 2u);
}

TEST(GnssDevice, ASilentReceiverSaysSo) {
  Rig r;
  ASSERT_TRUE(r.device);
  r.feed(nav_pvt(0), 1100 * kMs);
  r.run(3000 * kMs);
  const DeviceStatus d = r.status();
  EXPECT_STREQ(d.state.c_str(), "silent");
  EXPECT_EQ(d.level, DeviceLevel::kError);
  EXPECT_EQ(r.value(d, "silent_events"), 1);
}

TEST(GnssDevice, StepsAllocateNothing) {
  Rig r;
  ASSERT_TRUE(r.device);
  std::vector<std::vector<std::uint8_t>> frames;
  for (int i = 0; i < 40; ++i) frames.push_back(nav_pvt(i % 60));
  r.feed(frames[0], 1100 * kMs);
  r.run(1200 * kMs);
  r.drain();
  test::AllocScope scope;
  for (int i = 1; i < 40; ++i) {
    r.port.feed(frames[static_cast<std::size_t>(i)].data(), static_cast<int>(frames[0].size()), (1100 + 200 * i) * kMs);
    r.run((1150 + 200 * i) * kMs);
    est::SensorSample s;
    while (r.core->input().ring(0).try_pop(s)) {
    }
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(r.device->samples(), 40);
}

TEST(GnssConfig, MistakesAreNamed) {
  const auto first_error = [](const std::string& gnss) {
    const std::string text = "[hardware]\nbackend = \"linux\"\n[gnss]\n" + gnss + R"(
[[sensor]]
name = "gps0"
type = "navsat"
source = "gnss"
use_odometry_yaw = true
config = [true, true, false, false, false, false, false, false, false, false, false, false, false, false, false]
)";
    const ConfigLoadResult r = load_config_string(text, "g.toml");
    return r.errors.empty() ? std::string() : r.errors[0].to_string();
  };
  EXPECT_EQ(first_error(""), "");
  EXPECT_NE(first_error("baud = 115201\n").find("must be one of 4800, 9600"), std::string::npos);
  EXPECT_NE(first_error("protocol = \"sirf\"\n").find("ubx (u-blox NAV-PVT) or nmea"), std::string::npos);
  EXPECT_NE(first_error("use_gst = true\n").find("only valid with protocol = \"nmea\""), std::string::npos);
  EXPECT_EQ(first_error("protocol = \"nmea\"\nuse_gst = true\n"), "");
  EXPECT_NE(first_error("latency = 3.0\n").find("latency"), std::string::npos);
  // The sensor must be a navsat one.
  const ConfigLoadResult r = load_config_string(R"(
[hardware]
backend = "linux"
[gnss]
[[sensor]]
name = "gps0"
type = "pose"
source = "gnss"
config = [true, true, false, false, false, false, false, false, false, false, false, false, false, false, false]
)",
                                                "g.toml");
  ASSERT_FALSE(r.errors.empty());
  EXPECT_NE(r.errors[0].to_string().find("source 'gnss' produces type 'navsat'"), std::string::npos)
      << r.errors[0].to_string();
}

}  // namespace gnss_device_test
}  // namespace rtfuse
