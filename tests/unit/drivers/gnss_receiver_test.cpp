// GnssReceiver on the mock serial port: fixes out of a UBX or NMEA byte
// stream stamped with their arrival, and the receiver faults its health
// reports (no fix, silence, unplugged, a clock running backwards).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "drivers/gnss/gnss_receiver.hpp"
#include "hal/mock/mock_serial_port.hpp"
#include "hal/mock/sim_clock.hpp"
#include "support/alloc_counter.hpp"
#include "support/gnss_bytes.hpp"

namespace rtfuse::drivers {
namespace gnss_receiver_test {

constexpr TimeNs kMs = 1'000'000;

std::string sentence(const std::string& body) { return test::nmea_sentence(body); }

std::vector<std::uint8_t> nav_pvt(int hour, int min, int sec, int fix_type, int flags) {
  std::vector<std::uint8_t> p(92, 0);
  p[8] = static_cast<std::uint8_t>(hour);
  p[9] = static_cast<std::uint8_t>(min);
  p[10] = static_cast<std::uint8_t>(sec);
  p[11] = 0x07;
  p[20] = static_cast<std::uint8_t>(fix_type);
  p[21] = static_cast<std::uint8_t>(flags);
  const std::int32_t lat = 481173000, lon = 115166667;
  for (int i = 0; i < 4; ++i) {
    p[24 + i] = static_cast<std::uint8_t>(lon >> (8 * i));
    p[28 + i] = static_cast<std::uint8_t>(lat >> (8 * i));
  }
  return test::ubx_frame(0x01, 0x07, p);
}

struct Rig {
  hal::mock::SimClock clock{1000 * kMs};
  hal::mock::MockSerialPort port{clock};
  GnssReceiver receiver;
  explicit Rig(const GnssReceiverConfig& c) : receiver(port, clock, c) {}
  void feed(const std::vector<std::uint8_t>& bytes, TimeNs at) {
    ASSERT_TRUE(port.feed(bytes.data(), static_cast<int>(bytes.size()), at));
  }
  void feed(const std::string& text, TimeNs at) {
    ASSERT_TRUE(port.feed(reinterpret_cast<const std::uint8_t*>(text.data()), static_cast<int>(text.size()), at));
  }
  // Polls until the clock reaches `until`; every fix on the way.
  std::vector<GnssFix> run(TimeNs until) {
    std::vector<GnssFix> fixes;
    GnssFix out[4];
    while (clock.now() < until) {
      const TimeNs before = clock.now();
      const TimeNs step = std::min<TimeNs>(100 * kMs, until - before);
      const int n = receiver.poll(step, out, 4);
      fixes.insert(fixes.end(), out, out + n);
      // A closed port answers at once: wait as the device thread would.
      if (n == 0 && clock.now() == before) clock.sleep_until(before + step);
    }
    return fixes;
  }
};

TEST(GnssReceiver, UbxFixesComeStampedWithTheirArrival) {
  Rig r(GnssReceiverConfig{});
  r.feed(nav_pvt(12, 0, 0, 3, 1), 1200 * kMs);
  r.feed(nav_pvt(12, 0, 1, 3, 1), 2200 * kMs);
  const auto fixes = r.run(2500 * kMs);
  ASSERT_EQ(fixes.size(), 2u);
  EXPECT_EQ(fixes[0].stamp, 1200 * kMs);
  EXPECT_EQ(fixes[1].stamp, 2200 * kMs);
  EXPECT_EQ(fixes[1].status, GnssStatus::kFix);
  EXPECT_EQ(r.receiver.health(), GnssHealth::kFix);
  EXPECT_EQ(r.receiver.stats().epochs, 2);
}

TEST(GnssReceiver, NmeaOnAUbxReceiverIsSkippedNotAnError) {
  Rig r(GnssReceiverConfig{});
  r.feed(sentence("GPGGA,120000,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), 1100 * kMs);
  r.feed(nav_pvt(12, 0, 0, 3, 1), 1200 * kMs);
  const auto fixes = r.run(1500 * kMs);
  EXPECT_EQ(fixes.size(), 1u);
  EXPECT_GT(r.receiver.ubx_framer().skipped_bytes, 60);
  EXPECT_EQ(r.receiver.stats().read_errors, 0);
}

TEST(GnssReceiver, NmeaEpochsBecomeFixes) {
  GnssReceiverConfig c;
  c.protocol = GnssProtocol::kNmea;
  Rig r(c);
  r.feed(sentence("GPRMC,120000.00,A,4807.038,N,01131.000,E,001.0,090.0,261126,,,A") +
             sentence("GPGGA,120000.00,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"),
         1150 * kMs);
  r.feed(sentence("GPRMC,120001.00,V,,,,,,,261126,,,N") + sentence("GPGGA,120001.00,,,,,0,00,99.99,,,,,,"),
         2150 * kMs);
  const auto fixes = r.run(2500 * kMs);
  ASSERT_EQ(fixes.size(), 2u);
  EXPECT_EQ(fixes[0].status, GnssStatus::kFix);
  EXPECT_EQ(fixes[0].stamp, 1150 * kMs);
  EXPECT_EQ(fixes[1].status, GnssStatus::kNoFix);
  EXPECT_EQ(r.receiver.health(), GnssHealth::kNoFix);
  EXPECT_EQ(r.receiver.stats().no_fix_epochs, 1);
}

TEST(GnssReceiver, SilenceThenUnplugAreReportedAndItRecovers) {
  Rig r(GnssReceiverConfig{});
  r.feed(nav_pvt(12, 0, 0, 3, 1), 1100 * kMs);
  r.run(1200 * kMs);
  EXPECT_EQ(r.receiver.health(), GnssHealth::kFix);
  r.run(3000 * kMs);  // 1.9 s without a byte: not yet
  EXPECT_EQ(r.receiver.health(), GnssHealth::kFix);
  r.run(3200 * kMs);
  EXPECT_EQ(r.receiver.health(), GnssHealth::kSilent);
  EXPECT_EQ(r.receiver.stats().silent_events, 1);
  r.run(6000 * kMs);
  EXPECT_EQ(r.receiver.stats().silent_events, 1);  // one event per silence
  r.feed(nav_pvt(12, 0, 5, 3, 1), 6100 * kMs);
  r.run(6200 * kMs);
  EXPECT_EQ(r.receiver.health(), GnssHealth::kFix);
  r.port.unplug();
  r.run(6300 * kMs);
  EXPECT_EQ(r.receiver.health(), GnssHealth::kClosed);
  r.port.replug();
  r.feed(nav_pvt(12, 0, 7, 3, 1), 6400 * kMs);
  r.run(6500 * kMs);
  EXPECT_EQ(r.receiver.health(), GnssHealth::kFix);
}

TEST(GnssReceiver, AnEpochBeforeThePreviousIsATimeJumpButMidnightIsNot) {
  Rig r(GnssReceiverConfig{});
  r.feed(nav_pvt(23, 59, 59, 3, 1), 1100 * kMs);
  r.feed(nav_pvt(0, 0, 0, 3, 1), 1200 * kMs);  // midnight
  r.feed(nav_pvt(0, 0, 1, 3, 1), 1300 * kMs);
  r.feed(nav_pvt(0, 0, 0, 3, 1), 1400 * kMs);  // backwards
  r.run(1500 * kMs);
  EXPECT_EQ(r.receiver.stats().time_jumps, 1);
  EXPECT_EQ(r.receiver.stats().epochs, 4);
}

TEST(GnssReceiver, AnImpossibleNavPvtIsRefusedWithItsReason) {
  Rig r(GnssReceiverConfig{});
  r.feed(nav_pvt(12, 0, 0, 9, 1), 1100 * kMs);
  const auto fixes = r.run(1200 * kMs);
  EXPECT_TRUE(fixes.empty());
  EXPECT_EQ(r.receiver.stats().refused, 1);
  EXPECT_STREQ(r.receiver.last_refusal(), "NAV-PVT fixType beyond 5");
}

TEST(GnssReceiver, PollAllocatesNothing) {
  Rig r(GnssReceiverConfig{});
  for (int i = 0; i < 20; ++i) r.feed(nav_pvt(12, 0, i, 3, 1), (1100 + 100 * i) * kMs);
  test::AllocScope scope;
  GnssFix out[4];
  int fixes = 0;
  while (r.clock.now() < 3200 * kMs) fixes += r.receiver.poll(100 * kMs, out, 4);
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(fixes, 20);
}

}  // namespace gnss_receiver_test
}  // namespace rtfuse::drivers
