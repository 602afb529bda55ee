#pragma once
// Global filter parameters, robot_localization names in comments.
#include <limits>

#include "estimation/navsat_params.hpp"
#include "estimation/sensor_sample.hpp"

#include "estimation/state.hpp"

namespace rtfuse::est {

struct FilterParams {
  bool two_d_mode = false;                    // two_d_mode
  double sensor_timeout_s = 0.1;              // sensor_timeout
  StateMatrix process_noise = StateMatrix::Zero();       // process_noise_covariance
  StateMatrix initial_covariance = StateMatrix::Zero();  // initial_estimate_covariance
  bool dynamic_process_noise = false;         // dynamic_process_noise_covariance
  bool has_initial_state = false;             // initial_state given
  StateVector initial_state = StateVector::Zero();
  // Variances above this are capped (row and column scaled, which keeps P
  // positive semi-definite) so a sensor that stops does not let P explode.
  double max_variance = 1e6;
  bool smooth_lagged_data = false;            // smooth_lagged_data
  double history_length_s = 0.0;              // history_length
  // Most measurements kept for lagged-data smoothing; bounds the re-filtering
  // work of one late measurement (allocated once, at configuration).
  int history_capacity = 256;
  double gravity = 9.80665;                   // gravitational_acceleration
  // When two or more sensors fuse absolute yaw, a yaw innovation beyond this
  // many standard deviations is dropped from that update and counted as a
  // yaw conflict (the rest of the measurement is still fused).
  double yaw_conflict_gate_sigma = 5.0;
};

struct SensorParams {
  SensorKind kind = SensorKind::kOdometry;
  UpdateMask update_mask = 0;                 // <sensor>_config
  bool differential = false;                  // <sensor>_differential
  bool relative = false;                      // <sensor>_relative
  double pose_rejection_threshold = std::numeric_limits<double>::infinity();
  double twist_rejection_threshold = std::numeric_limits<double>::infinity();
  double linear_acceleration_rejection_threshold = std::numeric_limits<double>::infinity();
  bool remove_gravitational_acceleration = false;
  int queue_size = 10;                        // <sensor>_queue_size
  NavsatParams navsat;                        // kNavSatFix: navsat_transform_node's
};

}  // namespace rtfuse::est
