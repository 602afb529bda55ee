#pragma once
// A measurement expressed in state space, ready for the EKF: robot_localization's
// Measurement after its ROS-side preprocessing (frames, differential, relative).
#include <cstdint>
#include <limits>

#include "core/time.hpp"
#include "estimation/state.hpp"

namespace rtfuse::est {

// Which rejection threshold and diagnostics bucket a measurement belongs to.
enum class MeasurementPart : std::uint8_t { kPose, kTwist, kAcceleration };

struct Measurement {
  TimeNs stamp = 0;
  std::uint8_t sensor = 0;
  MeasurementPart part = MeasurementPart::kPose;
  UpdateMask mask = 0;
  StateVector z = StateVector::Zero();
  StateMatrix covariance = StateMatrix::Zero();  // only the masked block is read
  double mahalanobis_threshold = std::numeric_limits<double>::infinity();
  // Finite only when several sensors fuse absolute yaw (see FilterParams).
  double yaw_gate_sigma = std::numeric_limits<double>::infinity();
};

}  // namespace rtfuse::est
