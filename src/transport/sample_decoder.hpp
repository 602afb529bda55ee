#pragma once
// LCM bytes of the external input types -> est::SensorSample, with the
// validation robot_localization applies before fusing. Runs on the LCM-in
// thread; it allocates only at construction (and if a frame id ever exceeds
// kStringReserve), so a steady stream of messages never touches the heap.
#include <cstddef>
#include <cstdint>

#include "core/time.hpp"
#include "estimation/sensor_sample.hpp"
#include "geometry/frame_tree.hpp"
#include "rtfuse/imu_t.hpp"
#include "rtfuse/navsat_fix_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "rtfuse/pose_with_covariance_stamped_t.hpp"
#include "rtfuse/twist_with_covariance_stamped_t.hpp"

namespace rtfuse::transport {

enum class DecodeResult {
  kOk,
  kMalformed,      // truncated or inconsistent bytes, or a stamp out of range
  kNonFinite,      // NaN/Inf in a used field, or a zero-norm orientation
  kBadCovariance,  // asymmetric (relative 1e-6) or a negative diagonal entry
  kUnknownFrame,   // empty frame id, or one the frame tree does not know
  kWrongType,      // the fingerprint is not the expected message type's
};

const char* to_string(DecodeResult r);

class SampleDecoder {
 public:
  static constexpr std::size_t kStringReserve = 256;

  // frames must outlive the decoder; it is only read (find()).
  explicit SampleDecoder(const geometry::FrameTree& frames);

  // kind selects the expected type: kOdometry odometry_t, kImu imu_t, kPose
  // pose_with_covariance_stamped_t, kTwist twist_with_covariance_stamped_t,
  // kNavSatFix navsat_fix_t. A fix's values are passed on as they are: the
  // navsat transform judges them (status, NaN, range, covariance type) and
  // counts each refusal by its reason.
  // *out is written only on kOk, and then entirely except out->sensor, which
  // belongs to the caller; the parts the kind does not use are reset.
  DecodeResult decode(est::SensorKind kind, const void* data, int size, est::SensorSample* out);

  // The set_pose command (a pose_with_covariance_stamped_t). Outputs are
  // written only on kOk.
  DecodeResult decode_set_pose(const void* data, int size, est::PoseSample* out, TimeNs* stamp,
                               std::int16_t* frame);

 private:
  DecodeResult decode_odometry(const void* data, int size, est::SensorSample* out);
  DecodeResult decode_imu(const void* data, int size, est::SensorSample* out);
  DecodeResult decode_pose(const void* data, int size, est::SensorSample* out);
  DecodeResult decode_twist(const void* data, int size, est::SensorSample* out);
  DecodeResult decode_navsat(const void* data, int size, est::SensorSample* out);
  // Index of a known frame, -1 for an empty or unknown id.
  std::int16_t resolve(const std::string& frame_id) const;

  const geometry::FrameTree& frames_;
  // One persistent object per type: decoding into it reuses string capacity.
  rtfuse::odometry_t odometry_{};
  rtfuse::imu_t imu_{};
  rtfuse::pose_with_covariance_stamped_t pose_{};
  rtfuse::navsat_fix_t navsat_{};
  rtfuse::twist_with_covariance_stamped_t twist_{};
};

}  // namespace rtfuse::transport
