#pragma once
// The camera's motion between two rectified stereo pairs from matched
// features (VISO2-S, Kitt et al. 2010; Geiger et al. 2011): each match is
// triangulated from the previous pair and reprojected into both current
// images through a motion p_cur = R p_prev + t, R = Rx(rx) Ry(ry) Rz(rz).
// RANSAC on minimal sets of three matches (a deterministic PCG32 seeded per
// call, so the same matches give the same motion everywhere), each fitted by
// Gauss-Newton on the reprojection error; then Gauss-Newton on the inliers
// of the best set, the inliers taken again with the refined motion, and a
// last refinement. The motion's covariance is s^2 (J^T J)^-1 of the final
// normal equations, s^2 the residual variance.
//
// Fixed-size math (Eigen 6x6) and arrays sized at construction: no
// allocation per call.
#include <cstdint>
#include <memory>

#include <Eigen/Core>

namespace rtfuse::vision {

// A rectified stereo camera: pixels and metres.
struct StereoCameraModel {
  double f = 0.0;   // focal length, both eyes, pixels
  double cu = 0.0;  // principal point, pixels
  double cv = 0.0;
  double baseline = 0.0;  // metres, right eye at +baseline along x
};

// One feature in the four images, full-resolution pixels.
struct StereoObservation {
  double u_lp = 0.0, v_lp = 0.0, u_rp = 0.0;  // previous pair (the right row is the left one)
  double u_lc = 0.0, v_lc = 0.0, u_rc = 0.0, v_rc = 0.0;  // current pair
};

struct EgomotionParams {
  int ransac_iterations = 200;  // at most
  // Adaptive stop: enough samples for this confidence that one was all
  // inliers, given the best set so far (0: always ransac_iterations), but
  // never fewer than ransac_min_iterations.
  double ransac_confidence = 0.9999;
  int ransac_min_iterations = 30;
  double inlier_threshold_px = 2.0;  // on the root of the summed squares of the four residuals
  int min_inliers = 6;
  bool reweighting = true;  // trust points near the image's vertical centre line more (VISO2)
  int max_gauss_newton_steps = 20;
};

struct Egomotion {
  bool ok = false;
  // rx, ry, rz (rad), tx, ty, tz (m): previous camera -> current camera.
  Eigen::Matrix<double, 6, 1> params = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  int matches = 0;
  int inliers = 0;
  double residual_rms_px = 0.0;  // over the inliers' four residuals
  int iterations = 0;            // RANSAC samples drawn (the adaptive stop)
};

// The 4x4 transform of params: x_cur = T x_prev.
Eigen::Matrix4d egomotion_transform(const Eigen::Matrix<double, 6, 1>& params) noexcept;

class StereoEgomotion {
 public:
  explicit StereoEgomotion(int max_matches);

  // seed: with the frame's number, so one frame's result does not depend on
  // the frames before it.
  Egomotion estimate(const StereoCameraModel& camera, const StereoObservation* obs, int n,
                     const EgomotionParams& params, std::uint64_t seed) noexcept;
  // After estimate: whether match i was an inlier of the result.
  bool inlier(int i) const noexcept { return inlier_[i] != 0; }

 private:
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  bool gauss_newton(const StereoCameraModel& cam, const StereoObservation* obs, const int* idx, int n, Vec6* theta,
                    int max_steps, double eps, bool weighted, Eigen::Matrix<double, 6, 6>* normal,
                    double* weighted_sq) noexcept;
  int count_inliers(const StereoCameraModel& cam, const StereoObservation* obs, int n, const Vec6& theta,
                    double threshold_sq, std::uint8_t* flags, int* list) noexcept;

  int capacity_;
  std::unique_ptr<Eigen::Vector3d[]> points_;  // triangulated from the previous pair
  std::unique_ptr<int[]> candidates_;           // matches with a valid triangulation
  std::unique_ptr<int[]> current_, best_;       // inlier lists
  std::unique_ptr<std::uint8_t[]> flags_, inlier_;
};

}  // namespace rtfuse::vision
