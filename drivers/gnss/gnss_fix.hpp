#pragma once
// One navigation epoch of a GNSS receiver, whatever protocol it spoke: what
// sensor_msgs/NavSatFix carries (and navsat_fix_t mirrors), plus what the
// protocols say that NavSatFix cannot (dead reckoning, 2-D, RTK, velocity).
#include <cstdint>

#include "core/time.hpp"

namespace rtfuse::drivers {

// sensor_msgs/NavSatStatus.status values.
enum class GnssStatus : std::int8_t { kNoFix = -1, kFix = 0, kSbasFix = 1, kGbasFix = 2 };

// sensor_msgs/NavSatFix.position_covariance_type values.
enum class GnssCovarianceType : std::uint8_t { kUnknown = 0, kApproximated = 1, kDiagonalKnown = 2, kKnown = 3 };

// How the receiver solved the epoch. Only the solutions from kAutonomous on
// measure an absolute position; dead reckoning alone extrapolates one.
enum class GnssSolution : std::uint8_t {
  kNone,           // no fix (or time only)
  kDeadReckoning,  // the receiver's own dead reckoning, no satellites: not a measurement
  kAutonomous,     // standalone GNSS
  kDifferential,   // SBAS or DGPS corrections
  kRtkFloat,
  kRtkFixed,
};

const char* to_string(GnssSolution s) noexcept;

struct GnssFix {
  // CLOCK_MONOTONIC receive time of the first byte of the epoch's first
  // message: the receiver sends it a fixed-ish latency after the epoch.
  TimeNs stamp = 0;
  // The epoch in receiver time: UTC milliseconds since midnight, -1 unknown.
  std::int64_t utc_ms_of_day = -1;

  GnssStatus status = GnssStatus::kNoFix;
  GnssSolution solution = GnssSolution::kNone;
  bool two_d = false;           // altitude held, not measured
  bool dead_reckoning = false;  // the receiver blended in its own dead reckoning (u-blox fixType 4)

  double latitude_deg = 0.0;   // WGS84, + north
  double longitude_deg = 0.0;  // WGS84, + east
  double altitude_m = 0.0;     // above the WGS84 ellipsoid (as NavSatFix)
  bool has_altitude = false;

  // Row-major 3x3 in east, north, up (m^2), as NavSatFix.
  double covariance_enu[9] = {};
  GnssCovarianceType covariance_type = GnssCovarianceType::kUnknown;

  int satellites = 0;
  double hdop = -1.0;  // < 0 unknown

  bool has_velocity = false;
  double velocity_enu[3] = {};  // m/s
};

}  // namespace rtfuse::drivers
