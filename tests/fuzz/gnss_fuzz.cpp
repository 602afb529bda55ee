// A GNSS receiver's byte stream, as its serial port hands it over: through
// the NMEA framer and fix assembler and through the UBX framer and NAV-PVT
// decoder at once (a u-blox port often carries both). The first byte picks
// the assembler's configuration (RMC, GST awaited or not).
// Properties: framed sentences are printable, shorter than the buffer and
// free of "$"; UBX payloads fit theirs; every fix has its epoch within a
// day, a finite covariance with non-negative variances, a finite velocity,
// and, when it claims a position, one on the globe; a malformed sentence
// is named; the framers' counters never exceed the bytes they saw.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "drivers/gnss/nmea_fix_assembler.hpp"
#include "drivers/gnss/nmea_framer.hpp"
#include "drivers/gnss/ubx_framer.hpp"
#include "drivers/gnss/ubx_nav_pvt.hpp"
#include "fuzz_check.hpp"

namespace {

using namespace rtfuse::drivers;

void check_fix(const GnssFix& f) {
  FUZZ_CHECK(f.utc_ms_of_day >= -1 && f.utc_ms_of_day < 86'401'000, "epoch within a day, or unknown");
  for (double c : f.covariance_enu) FUZZ_CHECK(std::isfinite(c), "finite covariance");
  for (int i = 0; i < 3; ++i) FUZZ_CHECK(f.covariance_enu[4 * i] >= 0.0, "non-negative variances");
  for (double v : f.velocity_enu) FUZZ_CHECK(std::isfinite(v), "finite velocity");
  FUZZ_CHECK(std::isfinite(f.altitude_m), "finite altitude");
  if (f.status != GnssStatus::kNoFix) {
    FUZZ_CHECK(std::isfinite(f.latitude_deg) && std::fabs(f.latitude_deg) <= 90.0, "latitude on the globe");
    FUZZ_CHECK(std::isfinite(f.longitude_deg) && std::fabs(f.longitude_deg) <= 180.0, "longitude on the globe");
    FUZZ_CHECK(f.solution != GnssSolution::kNone && f.solution != GnssSolution::kDeadReckoning,
               "a fix is a measured solution");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  NmeaFixConfig config;
  config.use_rmc = (data[0] & 1) != 0;
  config.use_gst = (data[0] & 2) != 0;
  NmeaFramer nmea;
  NmeaFixAssembler assembler(config);
  UbxFramer ubx;
  std::int64_t dollars = 0;
  for (std::size_t i = 1; i < size; ++i) {
    const rtfuse::TimeNs stamp = static_cast<rtfuse::TimeNs>(i);
    dollars += data[i] == '$';
    NmeaFramer::Sentence s;
    if (nmea.push(data[i], stamp, &s)) {
      FUZZ_CHECK(s.text.size() <= NmeaFramer::kMaxSentence, "a sentence fits the buffer");
      for (char c : s.text) FUZZ_CHECK(c >= 0x20 && c <= 0x7e && c != '$', "printable, no '$'");
      FUZZ_CHECK(s.stamp <= stamp, "stamped at its start");
      GnssFix fix;
      if (assembler.add(s, &fix)) check_fix(fix);
      if (assembler.stats().malformed > 0) FUZZ_CHECK(std::strlen(assembler.last_malformed()) > 0, "named");
    }
    UbxFramer::Frame f;
    if (ubx.push(data[i], stamp, &f)) {
      FUZZ_CHECK(f.length <= UbxFramer::kMaxPayload, "a payload fits the buffer");
      if (f.msg_class == kUbxClassNav && f.msg_id == kUbxIdNavPvt) {
        GnssFix fix;
        const char* why = "";
        if (decode_nav_pvt(f.payload, f.length, f.stamp, &fix, &why)) {
          check_fix(fix);
        } else {
          FUZZ_CHECK(std::strlen(why) > 0, "a refused NAV-PVT says why");
        }
      }
    }
  }
  const NmeaFramerStats& n = nmea.stats();
  FUZZ_CHECK(n.sentences + n.bad_checksum + n.missing_checksum + n.overlong <= dollars, "one outcome per '$'");
  const UbxFramerStats& u = ubx.stats();
  FUZZ_CHECK(u.frames * 8 + u.skipped_bytes <= static_cast<std::int64_t>(size), "frames and skips fit the input");
  return 0;
}
