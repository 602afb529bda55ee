#pragma once
// A stereo pair's calibration in OpenCV's conventions, whatever file it came
// from (a ZED factory file today): the form stereo rectification, the
// simulated camera and the tests' OpenCV reference all take.
//
// Camera frames are optical: x right, y down, z forward, metres.
#include <Eigen/Core>

namespace rtfuse::drivers {

// A pinhole with OpenCV's plumb-bob distortion (k1, k2, p1, p2, k3), pixels.
struct CameraIntrinsics {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;
};

struct StereoCalibration {
  int width = 0;   // one eye's image, pixels
  int height = 0;
  CameraIntrinsics left, right;
  // The right camera's frame from the left's, as cv::stereoRectify takes it:
  // x_right = R * x_left + T. rotation is R as a rotation vector (radians),
  // translation is T in metres (about (-baseline, 0, 0) for a side-by-side pair).
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

}  // namespace rtfuse::drivers
