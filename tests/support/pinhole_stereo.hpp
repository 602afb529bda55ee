#pragma once
// An ideal rectified stereo pair for the simulator's renderer (no
// distortion, parallel eyes, right eye at +baseline along x), so a rendered
// frame is already rectified and its true disparity is f B / Z.
#include <Eigen/Core>

#include "drivers/camera/stereo_calibration.hpp"

namespace rtfuse::test {

inline drivers::StereoCalibration pinhole_stereo_pair(int width, int height, double f, double cx, double cy,
                                                      double baseline) {
  drivers::StereoCalibration c;
  c.width = width;
  c.height = height;
  c.left = {f, f, cx, cy, 0.0, 0.0, 0.0, 0.0, 0.0};
  c.right = c.left;
  c.translation = Eigen::Vector3d(-baseline, 0.0, 0.0);
  return c;
}

}  // namespace rtfuse::test
