#include "drivers/gnss/nmea_fix_assembler.hpp"

#include <cmath>

namespace rtfuse::drivers {

namespace {

GnssSolution solution_of(int quality) noexcept {
  switch (quality) {
    case 1: case 3: return GnssSolution::kAutonomous;  // 3: PPS (military) fix
    case 2: case 9: return GnssSolution::kDifferential;  // 9: WAAS on some receivers
    case 4: return GnssSolution::kRtkFixed;
    case 5: return GnssSolution::kRtkFloat;
    case 6: return GnssSolution::kDeadReckoning;
    default: return GnssSolution::kNone;  // 0 invalid, 7 manual input, 8 simulator: not a measurement
  }
}

GnssStatus status_of(GnssSolution s) noexcept {
  switch (s) {
    case GnssSolution::kAutonomous: return GnssStatus::kFix;
    case GnssSolution::kDifferential: return GnssStatus::kSbasFix;
    case GnssSolution::kRtkFloat: case GnssSolution::kRtkFixed: return GnssStatus::kGbasFix;
    default: return GnssStatus::kNoFix;
  }
}

}  // namespace

void NmeaFixAssembler::open(std::int64_t utc_ms, TimeNs stamp) noexcept {
  pending_ = Pending{};
  pending_.open = true;
  pending_.utc_ms = utc_ms;
  pending_.stamp = stamp;
}

bool NmeaFixAssembler::complete() const noexcept {
  return pending_.has_gga && (!config_.use_rmc || pending_.has_rmc) && (!config_.use_gst || pending_.has_gst);
}

bool NmeaFixAssembler::add(const NmeaFramer::Sentence& sentence, GnssFix* fix) noexcept {
  if (!split_nmea_fields(sentence.text, &fields_)) {
    ++stats_.malformed;
    last_malformed_ = "more than 32 fields";
    return false;
  }
  const std::string_view type = nmea_sentence_type(fields_);
  const char* why = "";
  NmeaGga gga;
  NmeaRmc rmc;
  NmeaGst gst;
  std::int64_t utc = -1;
  if (type == "GGA") {
    if (!parse_gga(fields_, &gga, &why)) goto malformed;
    utc = gga.utc_ms_of_day;
  } else if (type == "RMC" && config_.use_rmc) {
    if (!parse_rmc(fields_, &rmc, &why)) goto malformed;
    utc = rmc.utc_ms_of_day;
  } else if (type == "GST" && config_.use_gst) {
    if (!parse_gst(fields_, &gst, &why)) goto malformed;
    utc = gst.utc_ms_of_day;
  } else {
    ++stats_.other_sentences;
    return false;
  }
  {
    bool emitted = false;
    if (pending_.open && pending_.utc_ms != utc) {
      // A newer epoch: the pending one will get nothing more.
      if (pending_.has_gga) {
        build(fix);
        ++stats_.incomplete_epochs;
        ++stats_.fixes;
        emitted = true;
      } else {
        ++stats_.dropped_epochs;
      }
      pending_.open = false;
    }
    if (!pending_.open) open(utc, sentence.stamp);
    if (type == "GGA") {
      pending_.gga = gga;
      pending_.has_gga = true;
    } else if (type == "RMC") {
      pending_.rmc = rmc;
      pending_.has_rmc = true;
    } else {
      pending_.gst = gst;
      pending_.has_gst = true;
    }
    // At most one fix per sentence: a completed epoch here means the
    // closed one above had no GGA, or this sentence alone completes it
    // (GGA only), in which case nothing was pending.
    if (!emitted && complete()) {
      build(fix);
      ++stats_.fixes;
      pending_.open = false;
      return true;
    }
    return emitted;
  }
malformed:
  ++stats_.malformed;
  last_malformed_ = why;
  return false;
}

void NmeaFixAssembler::build(GnssFix* fix) const noexcept {
  const Pending& p = pending_;
  *fix = GnssFix{};
  fix->stamp = p.stamp;
  fix->utc_ms_of_day = p.utc_ms;
  fix->satellites = p.gga.satellites;
  fix->hdop = p.gga.hdop;
  fix->solution = solution_of(p.gga.quality);
  if (p.has_rmc && p.rmc.mode == 'E') fix->solution = GnssSolution::kDeadReckoning;
  const bool rmc_says_invalid = p.has_rmc && (!p.rmc.valid || p.rmc.mode == 'N');
  fix->status = (p.gga.has_position && !rmc_says_invalid) ? status_of(fix->solution) : GnssStatus::kNoFix;
  fix->dead_reckoning = fix->solution == GnssSolution::kDeadReckoning;
  if (p.gga.has_position) {
    fix->latitude_deg = p.gga.latitude_deg;
    fix->longitude_deg = p.gga.longitude_deg;
  }
  if (p.gga.has_altitude) {
    fix->altitude_m = p.gga.altitude_msl_m + p.gga.geoid_separation_m;
    fix->has_altitude = true;
  }
  const NmeaGst& g = p.gst;
  if (p.has_gst && g.sigma_latitude_m >= 0.0 && g.sigma_longitude_m >= 0.0 && g.sigma_altitude_m >= 0.0) {
    fix->covariance_enu[0] = g.sigma_longitude_m * g.sigma_longitude_m;
    fix->covariance_enu[4] = g.sigma_latitude_m * g.sigma_latitude_m;
    fix->covariance_enu[8] = g.sigma_altitude_m * g.sigma_altitude_m;
    fix->covariance_type = GnssCovarianceType::kDiagonalKnown;
  } else if (p.gga.hdop >= 0.0) {
    const double h = p.gga.hdop * config_.epe_m[p.gga.quality];
    fix->covariance_enu[0] = fix->covariance_enu[4] = h * h;
    fix->covariance_enu[8] = 4.0 * h * h;
    fix->covariance_type = GnssCovarianceType::kApproximated;
  }
  if (p.has_rmc && p.rmc.has_speed && (p.rmc.has_course || p.rmc.speed_mps == 0.0)) {
    // Horizontal only: NMEA has no vertical speed.
    const double c = p.rmc.course_deg * (M_PI / 180.0);
    fix->velocity_enu[0] = p.rmc.speed_mps * std::sin(c);
    fix->velocity_enu[1] = p.rmc.speed_mps * std::cos(c);
    fix->has_velocity = true;
  }
}

}  // namespace rtfuse::drivers
