// The LCM input decoders (odometry_t, imu_t, pose and twist with covariance,
// the set_pose command, navsat_fix_t): bytes from anyone on the multicast
// group. The first byte picks the decoder. Property: a message is rejected
// with a reason, or everything it hands to the filter is finite with a
// unit-norm orientation and a known frame: no NaN ever reaches the estimate
// through here. A fix goes on as sent (the navsat transform judges it), so
// it is put through a NavsatTransform: refused with a reason, or a finite
// position and a covariance with a positive diagonal.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "estimation/navsat_transform.hpp"
#include "estimation/sensor_sample.hpp"
#include "fuzz_check.hpp"
#include "geometry/frame_tree.hpp"
#include "transport/sample_decoder.hpp"

namespace {

using rtfuse::est::SensorKind;
using rtfuse::est::SensorSample;
using rtfuse::transport::DecodeResult;

template <class M>
bool finite(const M& m) {
  return m.allFinite();
}

// The decoder keeps a quaternion within 1 % of unit norm as sent (as
// robot_localization does) and normalises the others.
bool unit(const Eigen::Quaterniond& q) { return std::abs(q.norm() - 1.0) <= 0.01 + 1e-12; }

void check_pose(const rtfuse::est::PoseSample& p) {
  FUZZ_CHECK(finite(p.position) && finite(p.orientation.coeffs()) && finite(p.covariance), "pose finite");
  FUZZ_CHECK(unit(p.orientation), "orientation normalised");
}

void check_twist(const rtfuse::est::TwistSample& t) {
  FUZZ_CHECK(finite(t.linear) && finite(t.angular) && finite(t.covariance), "twist finite");
}

const rtfuse::geometry::FrameTree& frames() {
  static const rtfuse::geometry::FrameTree tree = [] {
    rtfuse::geometry::FrameTree t;
    for (const char* name : {"odom", "base_link", "imu_link", "map", "camera"}) t.intern(name);
    return t;
  }();
  return tree;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static rtfuse::transport::SampleDecoder decoder(frames());
  const int n = static_cast<int>(size - 1);
  const std::uint8_t* msg = data + 1;
  const std::uint8_t which = data[0] % 6;
  if (which == 5) {
    SensorSample s;
    if (decoder.decode(SensorKind::kNavSatFix, msg, n, &s) != DecodeResult::kOk) return 0;
    FUZZ_CHECK(s.kind == SensorKind::kNavSatFix, "the kind asked for");
    FUZZ_CHECK(s.frame >= -1 && s.frame < frames().size(), "a known frame or none");
    // Fresh each input (no state carried between inputs): the fix as the
    // datum, and the fix against a configured datum far from it.
    rtfuse::est::NavsatTransform first_fix;
    first_fix.set_heading(Eigen::Quaterniond::Identity());
    rtfuse::est::NavsatParams p;
    p.manual_datum = true;
    p.datum = {47.3977, 8.5456, 0.0};
    rtfuse::est::NavsatTransform configured(p);
    for (rtfuse::est::NavsatTransform* t : {&first_fix, &configured}) {
      rtfuse::est::PoseSample pose;
      const auto r = t->convert(s.stamp, s.navsat, rtfuse::geometry::RigidTransform{}, &pose);
      FUZZ_CHECK(rtfuse::est::to_string(r) != nullptr, "every refusal has a name");
      if (r != rtfuse::est::NavsatRejection::kNone) continue;
      FUZZ_CHECK(finite(pose.position) && finite(pose.covariance), "an accepted fix is finite");
      for (int i = 0; i < 3; ++i) FUZZ_CHECK(pose.covariance(i, i) > 0.0, "a positive variance");
      const rtfuse::est::NavSatFixSample back = t->filtered_fix(pose.position, pose.covariance.topLeftCorner<3, 3>());
      const rtfuse::est::GeodeticPosition& g = back.position;
      FUZZ_CHECK(std::isfinite(g.altitude_m) && std::fabs(g.latitude_deg) <= 90.0 && std::fabs(g.longitude_deg) <= 180.0,
                 "the filtered fix is a position on the earth");
    }
    return 0;
  }
  if (which == 4) {
    rtfuse::est::PoseSample pose;
    rtfuse::TimeNs stamp = 0;
    std::int16_t frame = -1;
    if (decoder.decode_set_pose(msg, n, &pose, &stamp, &frame) == DecodeResult::kOk) {
      check_pose(pose);
      FUZZ_CHECK(frame >= 0 && frame < frames().size(), "a known frame");
      FUZZ_CHECK(stamp % 1000 == 0, "a stamp from whole microseconds, no overflow");
    }
    return 0;
  }
  const SensorKind kind = static_cast<SensorKind>(which);
  SensorSample s;
  const DecodeResult r = decoder.decode(kind, msg, n, &s);
  FUZZ_CHECK(rtfuse::transport::to_string(r) != nullptr, "every result has a name");
  if (r != DecodeResult::kOk) return 0;
  FUZZ_CHECK(s.kind == kind, "the kind asked for");
  FUZZ_CHECK(s.frame >= 0 && s.frame < frames().size(), "a known frame");
  FUZZ_CHECK(s.stamp % 1000 == 0, "a stamp from whole microseconds, no overflow");
  switch (kind) {
    case SensorKind::kOdometry:
      check_pose(s.pose);
      check_twist(s.twist);
      break;
    case SensorKind::kPose:
      check_pose(s.pose);
      break;
    case SensorKind::kTwist:
      check_twist(s.twist);
      break;
    case SensorKind::kNavSatFix: break;  // not selected here (which == 5 above)
    case SensorKind::kImu:
      if (s.imu.has_orientation) {
        FUZZ_CHECK(finite(s.imu.orientation.coeffs()) && finite(s.imu.orientation_covariance), "imu orientation");
        FUZZ_CHECK(unit(s.imu.orientation), "orientation normalised");
      }
      if (s.imu.has_angular_velocity)
        FUZZ_CHECK(finite(s.imu.angular_velocity) && finite(s.imu.angular_velocity_covariance), "imu gyro");
      if (s.imu.has_linear_acceleration)
        FUZZ_CHECK(finite(s.imu.linear_acceleration) && finite(s.imu.linear_acceleration_covariance), "imu accel");
      break;
  }
  return 0;
}
