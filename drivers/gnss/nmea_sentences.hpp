#pragma once
// The fields of the NMEA 0183 sentences a fix is made of, from a sentence
// the framer validated: GGA (position, quality, satellites, HDOP, altitude),
// RMC (validity, speed and course, mode) and GST (the receiver's own error
// estimate). Any talker (GP, GN, GL, GA, GB, BD...). Empty fields are what
// receivers send without a fix and are "absent", not errors; a field that
// is present but not a number, or out of its range, makes the sentence
// malformed, with the field named.
#include <cstdint>
#include <string_view>

namespace rtfuse::drivers {

struct NmeaFields {
  static constexpr int kMax = 32;
  std::string_view field[kMax];  // field[0] is the address ("GPGGA")
  int count = 0;
};

// False when the sentence has more than kMax fields.
bool split_nmea_fields(std::string_view text, NmeaFields* out) noexcept;
// "GGA" of "GPGGA"; empty for proprietary ("P...") or short addresses.
std::string_view nmea_sentence_type(const NmeaFields& f) noexcept;

struct NmeaGga {
  std::int64_t utc_ms_of_day = -1;
  bool has_position = false;
  double latitude_deg = 0.0, longitude_deg = 0.0;
  int quality = 0;  // 0 invalid, 1 GPS, 2 DGPS/SBAS, 3 PPS, 4 RTK fixed, 5 RTK float, 6 dead reckoning, 7 manual, 8 simulator
  int satellites = 0;
  double hdop = -1.0;
  bool has_altitude = false;
  double altitude_msl_m = 0.0;
  double geoid_separation_m = 0.0;  // ellipsoid height = MSL + separation
};

struct NmeaRmc {
  std::int64_t utc_ms_of_day = -1;
  bool valid = false;  // status A
  bool has_position = false;
  double latitude_deg = 0.0, longitude_deg = 0.0;
  bool has_speed = false;
  double speed_mps = 0.0;
  bool has_course = false;
  double course_deg = 0.0;  // over ground, clockwise from true north
  char mode = '\0';         // NMEA 2.3: A autonomous, D differential, E estimated (dead reckoning), N not valid...
};

struct NmeaGst {
  std::int64_t utc_ms_of_day = -1;
  double sigma_latitude_m = -1.0;  // < 0 absent
  double sigma_longitude_m = -1.0;
  double sigma_altitude_m = -1.0;
};

// Each returns false with *why naming the bad field ("GGA latitude").
bool parse_gga(const NmeaFields& f, NmeaGga* out, const char** why) noexcept;
bool parse_rmc(const NmeaFields& f, NmeaRmc* out, const char** why) noexcept;
bool parse_gst(const NmeaFields& f, NmeaGst* out, const char** why) noexcept;

}  // namespace rtfuse::drivers
