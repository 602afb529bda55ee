#include "drivers/gnss/ubx_nav_pvt.hpp"

#include <cmath>

namespace rtfuse::drivers {

namespace {

std::uint32_t u4(const std::uint8_t* p) noexcept {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}
std::int32_t i4(const std::uint8_t* p) noexcept { return static_cast<std::int32_t>(u4(p)); }
std::uint16_t u2(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>(p[0] | p[1] << 8);
}

// Payload offsets (u-blox M8/F9 interface description).
constexpr std::size_t kHour = 8, kMin = 9, kSec = 10, kValid = 11, kNano = 16, kFixType = 20, kFlags = 21,
                      kNumSv = 23, kLon = 24, kLat = 28, kHeight = 32, kHAcc = 40, kVAcc = 44, kVelN = 48,
                      kVelE = 52, kVelD = 56, kFlags3 = 78;

}  // namespace

bool decode_nav_pvt(const std::uint8_t* p, std::size_t length, TimeNs stamp, GnssFix* fix,
                    const char** why) noexcept {
  if (length != 92 && length != 84) return (*why = "NAV-PVT length is not 92 (or 84 for u-blox 7)"), false;
  *fix = GnssFix{};
  fix->stamp = stamp;
  const int fix_type = p[kFixType];
  const std::uint8_t flags = p[kFlags];
  if (fix_type > 5) return (*why = "NAV-PVT fixType beyond 5"), false;
  const double lat = i4(p + kLat) * 1e-7;
  const double lon = i4(p + kLon) * 1e-7;
  if (std::fabs(lat) > 90.0) return (*why = "NAV-PVT latitude beyond 90 degrees"), false;
  if (std::fabs(lon) > 180.0) return (*why = "NAV-PVT longitude beyond 180 degrees"), false;
  if (p[kHour] > 23 || p[kMin] > 59 || p[kSec] > 60) return (*why = "NAV-PVT time of day"), false;
  const std::int32_t nano = i4(p + kNano);
  if (nano < -1'000'000'000 || nano > 1'000'000'000) return (*why = "NAV-PVT nano"), false;
  if (p[kValid] & 0x02) {  // validTime
    const std::int64_t ms = (p[kHour] * 3600LL + p[kMin] * 60LL + p[kSec]) * 1000LL;
    // nano is signed: the epoch may fall just before the whole second.
    fix->utc_ms_of_day = (ms + (nano >= 0 ? (nano + 500'000) / 1'000'000 : -((-nano + 500'000) / 1'000'000)) +
                          86'400'000LL) % 86'400'000LL;
  }
  fix->satellites = p[kNumSv];
  const bool fix_ok = (flags & 0x01) != 0;
  const bool differential = (flags & 0x02) != 0;
  const int carrier = (flags >> 6) & 0x03;  // 1 float, 2 fixed
  const bool invalid_llh = length >= 80 && (u2(p + kFlags3) & 0x01) != 0;
  switch (fix_type) {
    case 1: fix->solution = GnssSolution::kDeadReckoning; break;
    case 2: case 3: case 4:
      fix->solution = carrier == 2 ? GnssSolution::kRtkFixed
                      : carrier == 1 ? GnssSolution::kRtkFloat
                      : differential ? GnssSolution::kDifferential
                                     : GnssSolution::kAutonomous;
      break;
    default: fix->solution = GnssSolution::kNone; break;  // 0 no fix, 5 time only
  }
  fix->two_d = fix_type == 2;
  fix->dead_reckoning = fix_type == 1 || fix_type == 4;
  const bool usable = fix_type >= 2 && fix_type <= 4 && fix_ok && !invalid_llh;
  if (usable) {
    fix->status = carrier != 0 ? GnssStatus::kGbasFix : differential ? GnssStatus::kSbasFix : GnssStatus::kFix;
  }
  fix->latitude_deg = lat;
  fix->longitude_deg = lon;
  fix->altitude_m = i4(p + kHeight) * 1e-3;
  fix->has_altitude = usable && fix_type != 2;
  const double h = u4(p + kHAcc) * 1e-3;
  const double v = u4(p + kVAcc) * 1e-3;
  fix->covariance_enu[0] = fix->covariance_enu[4] = h * h;
  fix->covariance_enu[8] = v * v;
  fix->covariance_type = GnssCovarianceType::kDiagonalKnown;
  fix->velocity_enu[0] = i4(p + kVelE) * 1e-3;
  fix->velocity_enu[1] = i4(p + kVelN) * 1e-3;
  fix->velocity_enu[2] = -(i4(p + kVelD) * 1e-3);  // negated as a double: -INT32_MIN overflows
  fix->has_velocity = usable;
  return true;
}

}  // namespace rtfuse::drivers
