#pragma once
// [vo]: stereo visual odometry on the camera's pairs (vision/stereo_odometry),
// feeding the [[sensor]] with source = "stereo_vo" a twist of camera.frame.
// Schema: docs/configuration.md.
namespace rtfuse {

struct VoSection {
  bool enabled = false;
  bool half_resolution = true;     // detect and match at half size (VGA and up)
  int ransac_iterations = 200;
  double inlier_threshold_px = 2.0;
  int min_inliers = 20;            // fewer: no measurement (a plain wall, a covered lens)
  int bucket_size_px = 50;         // matches spread over buckets of this size
  int bucket_max = 2;              // kept per bucket
  // A longer interval between two processed pairs (frames lost, the camera
  // unplugged) starts the odometry again instead of bridging it.
  double max_interval_s = 0.25;
  // Faster than this is a wrong solution, not a robot: rejected and counted.
  double max_speed_mps = 10.0;
  double max_turn_rate_rad_s = 6.0;
  // The egomotion's covariance (s^2 (J^T J)^-1) counts every inlier as an
  // independent measurement, which neighbouring features are not: on the
  // simulated robot at VGA the twists scatter about 4x its sigma while the
  // robot moves. It is multiplied by this, and the sigmas below are added
  // in quadrature.
  double covariance_scale = 16.0;
  double min_linear_sigma_mps = 0.005;
  double min_angular_sigma_rad_s = 0.002;
};

}  // namespace rtfuse
