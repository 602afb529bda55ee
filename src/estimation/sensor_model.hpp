#pragma once
// Turns one decoded sensor sample into state-space measurements the way
// robot_localization's RosFilter prepares them: into the world / base_link
// frames through static transforms, relative and differential modes, gravity
// removal, two_d_mode. One instance per configured sensor; it keeps the
// memory relative/differential modes need.
#include <cstdint>

#include "estimation/filter_params.hpp"
#include "estimation/measurement.hpp"
#include "estimation/navsat_transform.hpp"
#include "estimation/sensor_sample.hpp"
#include "geometry/frame_tree.hpp"

namespace rtfuse::est {

enum class SampleRejection : std::uint8_t {
  kNone,
  kNoTransform,   // a frame the sample names is not connected to world/base_link
  kWrongKind,     // sample kind does not match the sensor's type
  kNavsat,        // the navsat transform refused the fix (its stats say why)
};

struct FusionFrames {
  const geometry::FrameTree* tree = nullptr;
  int world = -1;
  int base_link = -1;
};

// Up to three measurements per sample: pose, twist, acceleration parts.
struct MeasurementBatch {
  Measurement items[3];
  int count = 0;
};

class SensorModel {
 public:
  SensorModel() = default;
  SensorModel(std::uint8_t index, const SensorParams& sensor, const FilterParams& filter);

  // Forgets relative/differential references (set_pose, reset).
  void reset() noexcept;
  // state: the filter's current estimate (lever arms, gravity without orientation).
  SampleRejection convert(const SensorSample& s, const StateVector& state, const FusionFrames& frames,
                          MeasurementBatch* out) noexcept;

  const SensorParams& params() const noexcept { return sensor_; }
  bool fuses_absolute_yaw() const noexcept;
  // kNavSatFix: the transform, its heading source and its counters.
  void set_navsat_heading(const Eigen::Quaterniond& base_orientation) noexcept { navsat_.set_heading(base_orientation); }
  const NavsatTransform& navsat() const noexcept { return navsat_; }
  void set_yaw_gate(double sigma) noexcept { yaw_gate_sigma_ = sigma; }

 private:
  // world_T_base pose with its covariance in the world frame.
  struct WorldPose {
    geometry::RigidTransform t;
    Matrix6 covariance;
  };
  // One file per measurement model: pose_model.cpp, twist_model.cpp, imu_model.cpp.
  SampleRejection convert_pose(const SensorSample& s, const FusionFrames& f, MeasurementBatch* out) noexcept;
  SampleRejection convert_twist(const SensorSample& s, int twist_frame, const StateVector& state,
                                const FusionFrames& f, MeasurementBatch* out) noexcept;
  SampleRejection convert_imu(const SensorSample& s, const StateVector& state, const FusionFrames& f,
                              MeasurementBatch* out) noexcept;
  SampleRejection convert_navsat(const SensorSample& s, const StateVector& state, MeasurementBatch* out) noexcept;
  // Relative/differential handling shared by pose sources and IMU orientation.
  void pose_part(TimeNs stamp, const WorldPose& pose, UpdateMask mask, MeasurementBatch* out) noexcept;
  Measurement blank(TimeNs stamp, MeasurementPart part) const noexcept;
  void add(MeasurementBatch* out, const Measurement& m) const noexcept;

  std::uint8_t index_ = 0;
  SensorParams sensor_;
  bool two_d_ = false;
  double gravity_ = 9.80665;
  double yaw_gate_sigma_ = std::numeric_limits<double>::infinity();

  bool has_reference_ = false;       // relative: the first pose
  geometry::RigidTransform reference_;
  bool has_previous_ = false;        // differential: the previous pose
  WorldPose previous_;
  TimeNs previous_stamp_ = 0;

  NavsatTransform navsat_;  // kNavSatFix only

};

// Covariance of a 6-vector (two 3-vectors) under the rotation r applied to both halves.
Matrix6 rotate_covariance6(const Matrix6& c, const Eigen::Matrix3d& r) noexcept;

}  // namespace rtfuse::est
