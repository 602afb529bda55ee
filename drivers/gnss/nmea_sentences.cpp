#include "drivers/gnss/nmea_sentences.hpp"

#include <charconv>
#include <cmath>

namespace rtfuse::drivers {

namespace {

// A decimal number, the whole field (from_chars: no locale, no allocation).
bool number(std::string_view s, double* out) noexcept {
  if (s.empty()) return false;
  const char* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, *out, std::chars_format::fixed);
  return r.ec == std::errc() && r.ptr == end && std::isfinite(*out);
}

bool integer(std::string_view s, int* out) noexcept {
  if (s.empty()) return false;
  const char* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, *out);
  return r.ec == std::errc() && r.ptr == end;
}

// hhmmss(.sss) -> ms since midnight; an empty field is absent (-1).
bool utc_time(std::string_view s, std::int64_t* out) noexcept {
  *out = -1;
  if (s.empty()) return true;
  double v = 0.0;
  // Bounded before any conversion to int: the fuzzer sent 1.2e65.
  if (s.size() < 6 || !number(s, &v) || v < 0.0 || v >= 240000.0) return false;
  const int hh = static_cast<int>(v / 10000.0);
  const int mm = static_cast<int>(v / 100.0) % 100;
  const double ss = v - hh * 10000.0 - mm * 100.0;
  if (hh > 23 || mm > 59 || ss >= 61.0) return false;  // 60: a leap second
  *out = (hh * 3600LL + mm * 60LL) * 1000LL + std::llround(ss * 1000.0);
  return true;
}

// (d)ddmm.mmmm plus N/S or E/W. Both empty: absent (*present false).
bool angle(std::string_view value, std::string_view hemi, double max_deg, char positive, char negative,
           double* out, bool* present) noexcept {
  *present = false;
  if (value.empty() && hemi.empty()) return true;
  double v = 0.0;
  if (!number(value, &v) || v < 0.0 || hemi.size() != 1) return false;
  const double deg = std::floor(v / 100.0);
  const double min = v - deg * 100.0;
  if (min >= 60.0) return false;
  double a = deg + min / 60.0;
  if (a > max_deg) return false;
  if (hemi[0] == negative) {
    a = -a;
  } else if (hemi[0] != positive) {
    return false;
  }
  *out = a;
  *present = true;
  return true;
}

// An optional non-negative number: empty is absent.
bool optional_number(std::string_view s, double* out, bool* present) noexcept {
  *present = false;
  if (s.empty()) return true;
  if (!number(s, out) || *out < 0.0) return false;
  *present = true;
  return true;
}

std::string_view at(const NmeaFields& f, int i) noexcept { return i < f.count ? f.field[i] : std::string_view(); }

}  // namespace

bool split_nmea_fields(std::string_view text, NmeaFields* out) noexcept {
  out->count = 0;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    if (out->count == NmeaFields::kMax) return false;
    out->field[out->count++] = text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    if (comma == std::string_view::npos) return true;
    start = comma + 1;
  }
}

std::string_view nmea_sentence_type(const NmeaFields& f) noexcept {
  const std::string_view a = at(f, 0);
  if (a.size() < 5 || a[0] == 'P') return {};
  return a.substr(a.size() - 3);
}

bool parse_gga(const NmeaFields& f, NmeaGga* out, const char** why) noexcept {
  *out = NmeaGga{};
  // GGA,time,lat,N,lon,E,quality,sats,hdop,alt,M,sep,M,age,station
  if (f.count < 10) return (*why = "GGA: too few fields"), false;
  if (!utc_time(at(f, 1), &out->utc_ms_of_day)) return (*why = "GGA time"), false;
  bool lat = false, lon = false;
  if (!angle(at(f, 2), at(f, 3), 90.0, 'N', 'S', &out->latitude_deg, &lat)) return (*why = "GGA latitude"), false;
  if (!angle(at(f, 4), at(f, 5), 180.0, 'E', 'W', &out->longitude_deg, &lon)) return (*why = "GGA longitude"), false;
  out->has_position = lat && lon;
  if (!at(f, 6).empty() && (!integer(at(f, 6), &out->quality) || out->quality < 0 || out->quality > 9)) {
    return (*why = "GGA quality"), false;
  }
  if (!at(f, 7).empty() && (!integer(at(f, 7), &out->satellites) || out->satellites < 0 || out->satellites > 255)) {
    return (*why = "GGA satellites"), false;
  }
  bool has_hdop = false;
  if (!optional_number(at(f, 8), &out->hdop, &has_hdop)) return (*why = "GGA HDOP"), false;
  if (!has_hdop) out->hdop = -1.0;
  if (!at(f, 9).empty()) {
    if (!number(at(f, 9), &out->altitude_msl_m) || std::fabs(out->altitude_msl_m) > 1e6) {
      return (*why = "GGA altitude"), false;
    }
    out->has_altitude = true;
  }
  if (!at(f, 11).empty() &&
      (!number(at(f, 11), &out->geoid_separation_m) || std::fabs(out->geoid_separation_m) > 200.0)) {
    return (*why = "GGA geoid separation"), false;
  }
  if (lat != lon) return (*why = "GGA position: latitude without longitude or the reverse"), false;
  return true;
}

bool parse_rmc(const NmeaFields& f, NmeaRmc* out, const char** why) noexcept {
  *out = NmeaRmc{};
  // RMC,time,status,lat,N,lon,E,speed(kn),course,date,magvar,E/W[,mode[,navstatus]]
  if (f.count < 10) return (*why = "RMC: too few fields"), false;
  if (!utc_time(at(f, 1), &out->utc_ms_of_day)) return (*why = "RMC time"), false;
  const std::string_view status = at(f, 2);
  if (status != "A" && status != "V") return (*why = "RMC status"), false;
  out->valid = status == "A";
  bool lat = false, lon = false;
  if (!angle(at(f, 3), at(f, 4), 90.0, 'N', 'S', &out->latitude_deg, &lat)) return (*why = "RMC latitude"), false;
  if (!angle(at(f, 5), at(f, 6), 180.0, 'E', 'W', &out->longitude_deg, &lon)) return (*why = "RMC longitude"), false;
  if (lat != lon) return (*why = "RMC position: latitude without longitude or the reverse"), false;
  out->has_position = lat && lon;
  double knots = 0.0;
  if (!optional_number(at(f, 7), &knots, &out->has_speed) || knots > 2000.0) return (*why = "RMC speed"), false;
  out->speed_mps = knots * (1852.0 / 3600.0);
  if (!optional_number(at(f, 8), &out->course_deg, &out->has_course) || out->course_deg > 360.0) {
    return (*why = "RMC course"), false;
  }
  const std::string_view mode = at(f, 12);
  if (mode.size() > 1) return (*why = "RMC mode"), false;
  out->mode = mode.empty() ? '\0' : mode[0];
  return true;
}

bool parse_gst(const NmeaFields& f, NmeaGst* out, const char** why) noexcept {
  *out = NmeaGst{};
  // GST,time,rms,semi-major,semi-minor,orientation,sigma lat,sigma lon,sigma alt
  if (f.count < 9) return (*why = "GST: too few fields"), false;
  if (!utc_time(at(f, 1), &out->utc_ms_of_day)) return (*why = "GST time"), false;
  bool present = false;
  if (!optional_number(at(f, 6), &out->sigma_latitude_m, &present) || out->sigma_latitude_m > 1e6) {
    return (*why = "GST latitude sigma"), false;
  }
  if (!present) out->sigma_latitude_m = -1.0;
  if (!optional_number(at(f, 7), &out->sigma_longitude_m, &present) || out->sigma_longitude_m > 1e6) {
    return (*why = "GST longitude sigma"), false;
  }
  if (!present) out->sigma_longitude_m = -1.0;
  if (!optional_number(at(f, 8), &out->sigma_altitude_m, &present) || out->sigma_altitude_m > 1e6) {
    return (*why = "GST altitude sigma"), false;
  }
  if (!present) out->sigma_altitude_m = -1.0;
  return true;
}

}  // namespace rtfuse::drivers
