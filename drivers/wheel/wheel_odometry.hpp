#pragma once
// Body twist of a differential or skid-steer base from two consecutive
// encoder sample sets, with its covariance, and a dead-reckoned "raw wheel
// odometry" pose. Pure arithmetic: no allocation after create().
//
// Each side's travel is the mean over its wheels that are valid in both sets
// and in the same unwrap segment. Covariance (per side, then propagated):
//   var_side = (slip_fraction * v_side)^2 + q^2 / n_side,
//   q = one count per sample period in m/s (quantisation), n_side wheels used;
//   vx = (v_l + v_r)/2, vyaw = (v_r - v_l)/B, B = track (* skid factor);
//   var_vx   = (var_l + var_r)/4 + vx_floor^2
//   var_vyaw = (var_l + var_r)/B^2 + vyaw_floor^2 [+ skid_k * |v_r - v_l|]
//   cov      = (var_r - var_l)/(2B)
#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "core/time.hpp"
#include "drivers/canopen/encoder_reading.hpp"
#include "drivers/wheel/planar_pose.hpp"
#include "drivers/wheel/wheel_odometry_config.hpp"

namespace rtfuse::drivers {

struct WheelTwist {
  TimeNs stamp = 0;  // sample time of the newer set (its SYNC)
  TimeNs dt_ns = 0;  // time between the two sets
  double vx = 0.0;   // m/s, base_link forward
  double vyaw = 0.0; // rad/s, counter-clockwise seen from above
  double var_vx = 0.0;
  double var_vyaw = 0.0;
  double cov_vx_vyaw = 0.0;
  double v_left = 0.0;   // m/s of each side, for diagnostics
  double v_right = 0.0;
  int wheels_used = 0;
};

struct WheelOdometryStats {
  std::int64_t updates = 0;
  std::int64_t outputs = 0;
  std::int64_t no_side = 0;    // a side without a wheel valid in both sets
  std::int64_t reseeds = 0;    // first set, or the previous one too old (> max_gap_ns)
  std::int64_t stale = 0;      // a set not newer than the previous one
  std::int64_t bad_input = 0;  // null/short reading array, or a non-finite result
};

class WheelOdometry {
 public:
  // nullptr with *error set when the config is invalid (see validate_config).
  static std::unique_ptr<WheelOdometry> create(const WheelOdometryConfig& config, std::string* error);

  // readings[i] is encoder i (CanopenEncoders node order), n of them. True
  // with *out filled when the two last sets gave a twist.
  bool update(const EncoderReading* readings, int n, WheelTwist* out) noexcept;

  const PlanarPose& pose() const noexcept { return pose_; }
  TimeNs pose_stamp() const noexcept { return pose_stamp_; }
  void reset_pose(const PlanarPose& pose) noexcept { pose_ = pose; }

  double meters_per_count() const noexcept { return meters_per_count_; }
  double effective_track_m() const noexcept { return track_; }
  const WheelOdometryStats& stats() const noexcept { return stats_; }
  const WheelOdometryConfig& config() const noexcept { return config_; }

 private:
  explicit WheelOdometry(const WheelOdometryConfig& config);

  struct WheelMemory {
    bool valid = false;
    std::int64_t counts = 0;
    std::uint32_t segment = 0;
  };

  WheelOdometryConfig config_;
  double meters_per_count_ = 0.0;
  double track_ = 0.0;
  std::array<WheelMemory, kMaxWheels> prev_{};
  bool has_prev_ = false;
  TimeNs prev_stamp_ = 0;
  PlanarPose pose_;
  TimeNs pose_stamp_ = 0;
  WheelOdometryStats stats_;
};

}  // namespace rtfuse::drivers
