#include "transport/sample_decoder.hpp"

#include <algorithm>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <exception>
#include <initializer_list>
#include <limits>
#include <string_view>

#include "transport/lcm_wire.hpp"

namespace rtfuse::transport {
namespace {

// robot_localization normalises an orientation whose norm is off 1 by more than this.
constexpr double kQuaternionNormTolerance = 0.01;
// Below this a quaternion carries no direction worth normalising.
constexpr double kMinQuaternionNorm = 1e-6;
constexpr double kSymmetryTolerance = 1e-6;

// Every input type starts with its fingerprint and a header_t (utime, seq,
// frame_id); odometry_t follows it with child_frame_id: `strings` is how many
// of those leading strings there are, checked before lcm-gen's decoder sees
// them (transport/lcm_wire.hpp).
bool leading_strings_sane(const std::uint8_t* bytes, int size, int strings) {
  constexpr int kFirstStringAt = 8 + 8 + 4;  // fingerprint, header.utime, header.seq
  return wire::after_strings(bytes, size, kFirstStringAt, strings, std::numeric_limits<std::int32_t>::max()) >= 0;
}

template <class Msg>
DecodeResult decode_bytes(Msg& msg, const void* data, int size, int leading_strings) {
  if (data == nullptr || size < 8) return DecodeResult::kMalformed;
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  if (wire::load_i64(bytes) != Msg::getHash()) return DecodeResult::kWrongType;
  if (!leading_strings_sane(bytes, size, leading_strings)) return DecodeResult::kMalformed;
  try {
    if (msg.decode(data, 0, size) < 0) return DecodeResult::kMalformed;
  } catch (const std::exception&) {
    // Only if a type's layout changes under leading_strings_sane(): a message
    // must never take the LCM thread down.
    return DecodeResult::kMalformed;
  }
  if (!utime_in_range(msg.header.utime)) return DecodeResult::kMalformed;
  return DecodeResult::kOk;
}

bool all_finite(const double* v, int n) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return false;
  }
  return true;
}

bool finite(const rtfuse::vector3_t& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// robot_localization semantics: zero and very large variances are valid (the
// filter floors or simply trusts less); only what no covariance can be is refused.
template <int N>
DecodeResult check_covariance(const double (&c)[N * N]) {
  if (!all_finite(c, N * N)) return DecodeResult::kNonFinite;
  double scale = 0.0;
  for (double v : c) scale = std::max(scale, std::abs(v));
  for (int r = 0; r < N; ++r) {
    if (c[r * N + r] < 0.0) return DecodeResult::kBadCovariance;
    for (int k = r + 1; k < N; ++k) {
      if (std::abs(c[r * N + k] - c[k * N + r]) > kSymmetryTolerance * scale) {
        return DecodeResult::kBadCovariance;
      }
    }
  }
  // Symmetric with a non-negative diagonal can still describe a negative
  // variance along some direction, which would let the filter's covariance go
  // indefinite. A fixed-size eigen solve does not allocate and runs on the
  // input thread, not the loop.
  if (scale > 0.0) {
    const Eigen::Map<const Eigen::Matrix<double, N, N, Eigen::RowMajor>> m(c);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(m, Eigen::EigenvaluesOnly);
    if (es.info() != Eigen::Success || es.eigenvalues().minCoeff() < -1e-9 * scale) {
      return DecodeResult::kBadCovariance;
    }
  }
  return DecodeResult::kOk;
}

DecodeResult check_quaternion(const rtfuse::quaternion_t& q) {
  if (!(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w))) {
    return DecodeResult::kNonFinite;
  }
  // A norm that overflows (components beyond ~1e154) would normalise to a
  // zero quaternion: no orientation to recover, like one of norm zero.
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  return norm >= kMinQuaternionNorm && std::isfinite(norm) ? DecodeResult::kOk : DecodeResult::kNonFinite;
}

// Call after check_quaternion(). Like robot_localization, a quaternion close
// to unit norm is kept as sent, so a round trip through the filter is exact.
Eigen::Quaterniond to_quaternion(const rtfuse::quaternion_t& q) {
  Eigen::Quaterniond out(q.w, q.x, q.y, q.z);
  if (std::abs(out.norm() - 1.0) > kQuaternionNormTolerance) out.normalize();
  return out;
}

Eigen::Vector3d to_vector(const rtfuse::vector3_t& v) { return {v.x, v.y, v.z}; }

template <int N>
Eigen::Matrix<double, N, N> to_matrix(const double (&c)[N * N]) {
  return Eigen::Map<const Eigen::Matrix<double, N, N, Eigen::RowMajor>>(c);
}

// First failure wins, in the order the checks are listed.
DecodeResult first_failure(std::initializer_list<DecodeResult> results) {
  for (DecodeResult r : results) {
    if (r != DecodeResult::kOk) return r;
  }
  return DecodeResult::kOk;
}

DecodeResult check_pose(const rtfuse::pose_with_covariance_t& p) {
  return first_failure({finite(p.pose.position) ? DecodeResult::kOk : DecodeResult::kNonFinite,
                        check_quaternion(p.pose.orientation), check_covariance<6>(p.covariance)});
}

DecodeResult check_twist(const rtfuse::twist_with_covariance_t& t) {
  const bool ok = finite(t.twist.linear) && finite(t.twist.angular);
  return first_failure(
      {ok ? DecodeResult::kOk : DecodeResult::kNonFinite, check_covariance<6>(t.covariance)});
}

est::PoseSample to_pose(const rtfuse::pose_with_covariance_t& p) {
  est::PoseSample out;
  out.position = to_vector(p.pose.position);
  out.orientation = to_quaternion(p.pose.orientation);
  out.covariance = to_matrix<6>(p.covariance);
  return out;
}

est::TwistSample to_twist(const rtfuse::twist_with_covariance_t& t) {
  est::TwistSample out;
  out.linear = to_vector(t.twist.linear);
  out.angular = to_vector(t.twist.angular);
  out.covariance = to_matrix<6>(t.covariance);
  return out;
}

// sensor_msgs/Imu: covariance[0] == -1 marks the part as not provided.
bool provided(const double (&covariance)[9]) { return covariance[0] != -1.0; }

DecodeResult check_imu(const rtfuse::imu_t& m) {
  DecodeResult r = DecodeResult::kOk;
  if (provided(m.orientation_covariance)) {
    r = first_failure(
        {check_quaternion(m.orientation), check_covariance<3>(m.orientation_covariance)});
    if (r != DecodeResult::kOk) return r;
  }
  if (provided(m.angular_velocity_covariance)) {
    r = first_failure({finite(m.angular_velocity) ? DecodeResult::kOk : DecodeResult::kNonFinite,
                       check_covariance<3>(m.angular_velocity_covariance)});
    if (r != DecodeResult::kOk) return r;
  }
  if (provided(m.linear_acceleration_covariance)) {
    r = first_failure({finite(m.linear_acceleration) ? DecodeResult::kOk : DecodeResult::kNonFinite,
                       check_covariance<3>(m.linear_acceleration_covariance)});
  }
  return r;
}

est::ImuSample to_imu(const rtfuse::imu_t& m) {
  est::ImuSample out;
  out.has_orientation = provided(m.orientation_covariance);
  out.has_angular_velocity = provided(m.angular_velocity_covariance);
  out.has_linear_acceleration = provided(m.linear_acceleration_covariance);
  if (out.has_orientation) {
    out.orientation = to_quaternion(m.orientation);
    out.orientation_covariance = to_matrix<3>(m.orientation_covariance);
  }
  if (out.has_angular_velocity) {
    out.angular_velocity = to_vector(m.angular_velocity);
    out.angular_velocity_covariance = to_matrix<3>(m.angular_velocity_covariance);
  }
  if (out.has_linear_acceleration) {
    out.linear_acceleration = to_vector(m.linear_acceleration);
    out.linear_acceleration_covariance = to_matrix<3>(m.linear_acceleration_covariance);
  }
  return out;
}

// Everything but the caller's sensor index, reset so that no field of an
// earlier sample can leak into this one.
void reset_sample(est::SensorSample* out, est::SensorKind kind, std::int64_t utime,
                  std::int16_t frame, std::int16_t child_frame) {
  const std::uint8_t sensor = out->sensor;
  *out = est::SensorSample{};
  out->sensor = sensor;
  out->kind = kind;
  out->stamp = utime_to_ns(utime);
  out->frame = frame;
  out->child_frame = child_frame;
}

}  // namespace

const char* to_string(DecodeResult r) {
  switch (r) {
    case DecodeResult::kOk: return "ok";
    case DecodeResult::kMalformed: return "malformed message";
    case DecodeResult::kNonFinite: return "non-finite value";
    case DecodeResult::kBadCovariance: return "invalid covariance";
    case DecodeResult::kUnknownFrame: return "unknown frame";
    case DecodeResult::kWrongType: return "wrong message type";
  }
  return "unknown decode result";
}

SampleDecoder::SampleDecoder(const geometry::FrameTree& frames) : frames_(frames) {
  odometry_.header.frame_id.reserve(kStringReserve);
  odometry_.child_frame_id.reserve(kStringReserve);
  imu_.header.frame_id.reserve(kStringReserve);
  pose_.header.frame_id.reserve(kStringReserve);
  twist_.header.frame_id.reserve(kStringReserve);
  navsat_.header.frame_id.reserve(kStringReserve);
}

std::int16_t SampleDecoder::resolve(const std::string& frame_id) const {
  if (frame_id.empty()) return -1;
  return static_cast<std::int16_t>(frames_.find(std::string_view(frame_id)));
}

DecodeResult SampleDecoder::decode(est::SensorKind kind, const void* data, int size,
                                   est::SensorSample* out) {
  switch (kind) {
    case est::SensorKind::kOdometry: return decode_odometry(data, size, out);
    case est::SensorKind::kImu: return decode_imu(data, size, out);
    case est::SensorKind::kPose: return decode_pose(data, size, out);
    case est::SensorKind::kTwist: return decode_twist(data, size, out);
    case est::SensorKind::kNavSatFix: return decode_navsat(data, size, out);
  }
  return DecodeResult::kWrongType;
}

DecodeResult SampleDecoder::decode_odometry(const void* data, int size, est::SensorSample* out) {
  DecodeResult r = decode_bytes(odometry_, data, size, 2);
  if (r != DecodeResult::kOk) return r;
  const std::int16_t frame = resolve(odometry_.header.frame_id);
  const std::int16_t child = resolve(odometry_.child_frame_id);
  if (frame < 0 || child < 0) return DecodeResult::kUnknownFrame;
  r = first_failure({check_pose(odometry_.pose), check_twist(odometry_.twist)});
  if (r != DecodeResult::kOk) return r;
  reset_sample(out, est::SensorKind::kOdometry, odometry_.header.utime, frame, child);
  out->pose = to_pose(odometry_.pose);
  out->twist = to_twist(odometry_.twist);
  return DecodeResult::kOk;
}

DecodeResult SampleDecoder::decode_imu(const void* data, int size, est::SensorSample* out) {
  DecodeResult r = decode_bytes(imu_, data, size, 1);
  if (r != DecodeResult::kOk) return r;
  const std::int16_t frame = resolve(imu_.header.frame_id);
  if (frame < 0) return DecodeResult::kUnknownFrame;
  r = check_imu(imu_);
  if (r != DecodeResult::kOk) return r;
  reset_sample(out, est::SensorKind::kImu, imu_.header.utime, frame, -1);
  out->imu = to_imu(imu_);
  return DecodeResult::kOk;
}

DecodeResult SampleDecoder::decode_pose(const void* data, int size, est::SensorSample* out) {
  DecodeResult r = decode_bytes(pose_, data, size, 1);
  if (r != DecodeResult::kOk) return r;
  const std::int16_t frame = resolve(pose_.header.frame_id);
  if (frame < 0) return DecodeResult::kUnknownFrame;
  r = check_pose(pose_.pose);
  if (r != DecodeResult::kOk) return r;
  reset_sample(out, est::SensorKind::kPose, pose_.header.utime, frame, -1);
  out->pose = to_pose(pose_.pose);
  return DecodeResult::kOk;
}

DecodeResult SampleDecoder::decode_twist(const void* data, int size, est::SensorSample* out) {
  DecodeResult r = decode_bytes(twist_, data, size, 1);
  if (r != DecodeResult::kOk) return r;
  const std::int16_t frame = resolve(twist_.header.frame_id);
  if (frame < 0) return DecodeResult::kUnknownFrame;
  r = check_twist(twist_.twist);
  if (r != DecodeResult::kOk) return r;
  reset_sample(out, est::SensorKind::kTwist, twist_.header.utime, frame, -1);
  out->twist = to_twist(twist_.twist);
  return DecodeResult::kOk;
}

DecodeResult SampleDecoder::decode_navsat(const void* data, int size, est::SensorSample* out) {
  const DecodeResult r = decode_bytes(navsat_, data, size, 1);
  if (r != DecodeResult::kOk) return r;
  // The antenna's frame is the sensor's configured one (its lever arm is
  // fixed at configuration); an unknown or empty frame_id is no reason to
  // lose the fix, as navsat_transform_node takes it too.
  reset_sample(out, est::SensorKind::kNavSatFix, navsat_.header.utime, resolve(navsat_.header.frame_id), -1);
  est::NavSatFixSample& f = out->navsat;
  f.status = navsat_.status;
  f.covariance_type = static_cast<std::uint8_t>(navsat_.position_covariance_type);
  f.position = {navsat_.latitude, navsat_.longitude, navsat_.altitude};
  f.covariance = to_matrix<3>(navsat_.position_covariance);
  return DecodeResult::kOk;
}

DecodeResult SampleDecoder::decode_set_pose(const void* data, int size, est::PoseSample* out,
                                            TimeNs* stamp, std::int16_t* frame) {
  DecodeResult r = decode_bytes(pose_, data, size, 1);
  if (r != DecodeResult::kOk) return r;
  const std::int16_t f = resolve(pose_.header.frame_id);
  if (f < 0) return DecodeResult::kUnknownFrame;
  r = check_pose(pose_.pose);
  if (r != DecodeResult::kOk) return r;
  *out = to_pose(pose_.pose);
  *stamp = utime_to_ns(pose_.header.utime);
  *frame = f;
  return DecodeResult::kOk;
}

}  // namespace rtfuse::transport
