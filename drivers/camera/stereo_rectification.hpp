#pragma once
// Stereo rectification of a calibrated pair, computed once at start-up: what
// OpenCV's cv::stereoRectify gives with CALIB_ZERO_DISPARITY, alpha = 0 and
// the output the size of the input, and the per-pixel source positions that
// cv::initUndistortRectifyMap gives for it. tests/reference/ checks both
// against OpenCV itself; OpenCV is never linked into the runtime.
//
// After rectification both eyes are the same undistorted pinhole (fx = fy,
// same cx, cy), rotated so that epipolar lines are image rows: a point at
// depth Z seen at column u_left appears in the right image on the same row at
// u_right = u_left - fx * baseline / Z. alpha = 0 zooms in until every
// rectified pixel of both eyes has a source inside its raw image (for
// moderate distortion; the test checks it on ZED-like calibrations).
#include <string>

#include <Eigen/Core>

#include "drivers/camera/stereo_calibration.hpp"

namespace rtfuse::drivers {

struct RectifiedEye {
  // R1 / R2: rotates a point from the raw camera's frame into the rectified
  // camera's frame (both rectified frames are parallel).
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  // P1 / P2: projects a point in the LEFT rectified frame to this eye's
  // rectified pixels. P2(0, 3) = -fx * baseline for a right eye at +x.
  Eigen::Matrix<double, 3, 4> projection = Eigen::Matrix<double, 3, 4>::Zero();
};

struct StereoRectification {
  int width = 0;   // one eye, pixels (rectified size = raw size)
  int height = 0;
  RectifiedEye left, right;
  // Q: [u v disparity 1] -> homogeneous [X Y Z W] in the left rectified frame
  // (disparity = u_left - u_right), as cv::reprojectImageTo3D takes it.
  Eigen::Matrix4d q = Eigen::Matrix4d::Zero();
  // The rectified pinhole both eyes share (no distortion), pixels.
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  // Distance between the rectified optical centres along the rectified x
  // axis, metres, > 0 (the right eye sits at +baseline_m in the left frame).
  double baseline_m = 0.0;
};

// Fails (and says why in *error) for a calibration that is not a
// side-by-side pair: non-positive sizes or focal lengths, non-finite
// values, a translation that is zero or more vertical than horizontal, a
// relative rotation over 0.5 rad, or distortion so strong that no alpha = 0
// view exists.
bool compute_stereo_rectification(const StereoCalibration& calibration, StereoRectification* rectification,
                                  std::string* error);

// The raw (distorted) image position a rectified pixel samples: for every
// rectified pixel, what cv::initUndistortRectifyMap stores in its maps.
class RawPositionMap {
 public:
  RawPositionMap(const CameraIntrinsics& raw, const RectifiedEye& eye);
  // Source position (x, y) in raw pixels of rectified pixel (u, v). False
  // when the ray points behind the raw camera (no source at all); a position
  // outside the raw image is returned as it is (the caller checks bounds).
  bool at(double u, double v, double* x, double* y) const noexcept;

 private:
  CameraIntrinsics raw_;
  Eigen::Matrix3d inverse_;  // (P[:, 0:3] * R)^-1: rectified pixel -> raw camera ray
};

// Rotation matrix of a rotation vector (axis * angle, radians), as
// cv::Rodrigues. Uses only sqrt, sin and cos (same bits on x86-64 and aarch64).
Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& rotation_vector) noexcept;

}  // namespace rtfuse::drivers
