// u-blox UBX: the framer and NAV-PVT. Two frames with checksums worked out by
// hand (the CFG-RATE and MON-VER polls: B5 62 06 08 00 00 0E 30 and
// B5 62 0A 04 00 00 0E 34) check the framer's Fletcher sum against someone
// else's arithmetic; NAV-PVT frames are built field by field.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "drivers/gnss/nmea_framer.hpp"
#include "drivers/gnss/ubx_framer.hpp"
#include "drivers/gnss/ubx_nav_pvt.hpp"
#include "support/alloc_counter.hpp"
#include "support/gnss_bytes.hpp"

namespace rtfuse::drivers {
namespace gnss_ubx_test {

using Bytes = std::vector<std::uint8_t>;

void put(Bytes& b, std::size_t at, std::int64_t v, int n) {
  for (int i = 0; i < n; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
}

Bytes frame(std::uint8_t cls, std::uint8_t id, const Bytes& payload) { return test::ubx_frame(cls, id, payload); }

struct Pvt {
  int fix_type = 3;
  int flags = 0x01;  // gnssFixOK
  int flags3 = 0;
  int valid = 0x07;
  double lat = 48.1173, lon = 11.5166667;
  std::int64_t height_mm = 592300, h_acc = 1500, v_acc = 2500;
  std::int64_t vel_n = 1000, vel_e = -500, vel_d = 200;
  std::int64_t nano = 200'000'000;
  int hour = 12, min = 35, sec = 19, sats = 12;
  std::size_t length = 92;
};

Bytes pvt_payload(const Pvt& p) {
  Bytes b(p.length, 0);
  put(b, 0, 45319200, 4);  // iTOW
  put(b, 4, 2026, 2);
  b[6] = 11;
  b[7] = 26;
  b[8] = static_cast<std::uint8_t>(p.hour);
  b[9] = static_cast<std::uint8_t>(p.min);
  b[10] = static_cast<std::uint8_t>(p.sec);
  b[11] = static_cast<std::uint8_t>(p.valid);
  put(b, 16, p.nano, 4);
  b[20] = static_cast<std::uint8_t>(p.fix_type);
  b[21] = static_cast<std::uint8_t>(p.flags);
  b[23] = static_cast<std::uint8_t>(p.sats);
  put(b, 24, static_cast<std::int64_t>(p.lon * 1e7), 4);
  put(b, 28, static_cast<std::int64_t>(p.lat * 1e7), 4);
  put(b, 32, p.height_mm, 4);
  put(b, 36, p.height_mm - 46900, 4);
  put(b, 40, p.h_acc, 4);
  put(b, 44, p.v_acc, 4);
  put(b, 48, p.vel_n, 4);
  put(b, 52, p.vel_e, 4);
  put(b, 56, p.vel_d, 4);
  if (p.length >= 80) put(b, 78, p.flags3, 2);
  return b;
}

std::vector<UbxFramer::Frame> feed(UbxFramer& f, const Bytes& bytes, std::vector<Bytes>* payloads = nullptr) {
  std::vector<UbxFramer::Frame> out;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    UbxFramer::Frame fr;
    if (f.push(bytes[i], static_cast<TimeNs>(i), &fr)) {
      out.push_back(fr);
      if (payloads) payloads->emplace_back(fr.payload, fr.payload + fr.length);
    }
  }
  return out;
}

TEST(UbxFramer, HandWorkedChecksumsPass) {
  UbxFramer f;
  const auto frames = feed(f, {0xB5, 0x62, 0x06, 0x08, 0x00, 0x00, 0x0E, 0x30,   // CFG-RATE poll
                               0xB5, 0x62, 0x0A, 0x04, 0x00, 0x00, 0x0E, 0x34});  // MON-VER poll
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].msg_class, 0x06);
  EXPECT_EQ(frames[0].msg_id, 0x08);
  EXPECT_EQ(frames[1].msg_class, 0x0A);
  EXPECT_EQ(frames[1].stamp, 8);
  EXPECT_EQ(f.stats().bad_checksum, 0);
  EXPECT_EQ(f.stats().skipped_bytes, 0);
}

TEST(UbxFramer, ABadChecksumOrAnImpossibleLengthLosesOnlyItsOwnFrame) {
  UbxFramer f;
  const Bytes good = frame(0x01, 0x07, pvt_payload(Pvt{}));
  Bytes corrupt = good;
  corrupt[30] ^= 0x40;  // a latitude bit flipped on the wire
  const Bytes huge = {0xB5, 0x62, 0x01, 0x07, 0xFF, 0xFF};  // 65535 bytes claimed
  Bytes stream = corrupt;
  stream.insert(stream.end(), huge.begin(), huge.end());
  stream.insert(stream.end(), good.begin(), good.end());
  const char* nmea = "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n";
  stream.insert(stream.end(), nmea, nmea + std::strlen(nmea));  // an NMEA sentence on the same port
  stream.insert(stream.end(), good.begin(), good.end());
  std::vector<Bytes> payloads;
  const auto frames = feed(f, stream, &payloads);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(payloads[0], pvt_payload(Pvt{}));
  EXPECT_EQ(f.stats().bad_checksum, 1);
  EXPECT_EQ(f.stats().oversize, 1);
  EXPECT_EQ(f.stats().skipped_bytes, static_cast<std::int64_t>(std::strlen(nmea)));

  // And the NMEA framer on the same stream finds its sentence among the binary.
  NmeaFramer n;
  int sentences = 0;
  for (std::uint8_t b : stream) {
    NmeaFramer::Sentence s;
    sentences += n.push(b, 0, &s) ? 1 : 0;
  }
  EXPECT_EQ(sentences, 1);
}

TEST(UbxNavPvt, A3dFixDecodesToTheFieldsItWasBuiltFrom) {
  GnssFix fix;
  const char* why = "";
  const Bytes p = pvt_payload(Pvt{});
  ASSERT_TRUE(decode_nav_pvt(p.data(), p.size(), 777, &fix, &why)) << why;
  EXPECT_EQ(fix.stamp, 777);
  EXPECT_EQ(fix.status, GnssStatus::kFix);
  EXPECT_EQ(fix.solution, GnssSolution::kAutonomous);
  EXPECT_FALSE(fix.two_d);
  EXPECT_NEAR(fix.latitude_deg, 48.1173, 1e-7);
  EXPECT_NEAR(fix.longitude_deg, 11.5166667, 1e-7);
  EXPECT_TRUE(fix.has_altitude);
  EXPECT_DOUBLE_EQ(fix.altitude_m, 592.3);
  EXPECT_EQ(fix.utc_ms_of_day, 45319200);
  EXPECT_EQ(fix.satellites, 12);
  EXPECT_EQ(fix.covariance_type, GnssCovarianceType::kDiagonalKnown);
  EXPECT_DOUBLE_EQ(fix.covariance_enu[0], 1.5 * 1.5);
  EXPECT_DOUBLE_EQ(fix.covariance_enu[4], 1.5 * 1.5);
  EXPECT_DOUBLE_EQ(fix.covariance_enu[8], 2.5 * 2.5);
  ASSERT_TRUE(fix.has_velocity);
  EXPECT_DOUBLE_EQ(fix.velocity_enu[0], -0.5);
  EXPECT_DOUBLE_EQ(fix.velocity_enu[1], 1.0);
  EXPECT_DOUBLE_EQ(fix.velocity_enu[2], -0.2);
}

TEST(UbxNavPvt, FixTypeAndFlagsDecideWhetherItIsAFix) {
  const auto decode = [](const Pvt& p) {
    GnssFix fix;
    const char* why = "";
    const Bytes b = pvt_payload(p);
    EXPECT_TRUE(decode_nav_pvt(b.data(), b.size(), 0, &fix, &why)) << why;
    return fix;
  };
  Pvt p;
  p.flags = 0;  // gnssFixOK clear: outside the receiver's accuracy masks
  EXPECT_EQ(decode(p).status, GnssStatus::kNoFix);
  p = Pvt{};
  p.flags = 0x01 | 0x02;  // differential
  EXPECT_EQ(decode(p).status, GnssStatus::kSbasFix);
  p.flags = 0x01 | (2 << 6);  // carrier solution fixed
  EXPECT_EQ(decode(p).solution, GnssSolution::kRtkFixed);
  EXPECT_EQ(decode(p).status, GnssStatus::kGbasFix);
  p.flags = 0x01 | (1 << 6);
  EXPECT_EQ(decode(p).solution, GnssSolution::kRtkFloat);
  p = Pvt{};
  p.fix_type = 1;  // dead reckoning only
  EXPECT_EQ(decode(p).status, GnssStatus::kNoFix);
  EXPECT_TRUE(decode(p).dead_reckoning);
  p.fix_type = 4;  // GNSS + dead reckoning: a fix, flagged
  EXPECT_EQ(decode(p).status, GnssStatus::kFix);
  EXPECT_TRUE(decode(p).dead_reckoning);
  p.fix_type = 2;
  EXPECT_TRUE(decode(p).two_d);
  EXPECT_FALSE(decode(p).has_altitude);
  p.fix_type = 5;  // time only
  EXPECT_EQ(decode(p).status, GnssStatus::kNoFix);
  p = Pvt{};
  p.flags3 = 0x01;  // invalidLlh
  EXPECT_EQ(decode(p).status, GnssStatus::kNoFix);
  p = Pvt{};
  p.length = 84;  // u-blox 7
  EXPECT_EQ(decode(p).status, GnssStatus::kFix);
  p = Pvt{};
  p.valid = 0x01;  // no valid time
  EXPECT_EQ(decode(p).utc_ms_of_day, -1);
  p = Pvt{};
  p.hour = 23, p.min = 59, p.sec = 59, p.nano = -100'000'000;  // just before the whole second
  EXPECT_EQ(decode(p).utc_ms_of_day, 86'399'000 - 100);
}

TEST(UbxNavPvt, ImpossiblePayloadsAreRefusedWithTheReason) {
  GnssFix fix;
  const char* why = "";
  Bytes b = pvt_payload(Pvt{});
  EXPECT_FALSE(decode_nav_pvt(b.data(), 50, 0, &fix, &why));
  EXPECT_STREQ(why, "NAV-PVT length is not 92 (or 84 for u-blox 7)");
  Pvt p;
  p.lat = 95.0;
  b = pvt_payload(p);
  EXPECT_FALSE(decode_nav_pvt(b.data(), b.size(), 0, &fix, &why));
  EXPECT_STREQ(why, "NAV-PVT latitude beyond 90 degrees");
  p = Pvt{};
  p.fix_type = 9;
  b = pvt_payload(p);
  EXPECT_FALSE(decode_nav_pvt(b.data(), b.size(), 0, &fix, &why));
  p = Pvt{};
  p.vel_d = INT32_MIN;  // the one value whose integer negation overflows
  b = pvt_payload(p);
  ASSERT_TRUE(decode_nav_pvt(b.data(), b.size(), 0, &fix, &why));
  EXPECT_DOUBLE_EQ(fix.velocity_enu[2], 2147483.648);
}

TEST(UbxFramer, NothingIsAllocatedPerByte) {
  Bytes stream;
  for (int i = 0; i < 50; ++i) {
    const Bytes f = frame(0x01, 0x07, pvt_payload(Pvt{}));
    stream.insert(stream.end(), f.begin(), f.end());
  }
  UbxFramer f;
  int fixes = 0;
  test::AllocScope scope;
  for (std::uint8_t b : stream) {
    UbxFramer::Frame fr;
    GnssFix fix;
    const char* why = "";
    if (f.push(b, 0, &fr) && decode_nav_pvt(fr.payload, fr.length, fr.stamp, &fix, &why)) ++fixes;
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(fixes, 50);
}

}  // namespace gnss_ubx_test
}  // namespace rtfuse::drivers
