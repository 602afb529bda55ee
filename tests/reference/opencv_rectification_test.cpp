// drivers/camera's rectification against OpenCV 4 (the reference every
// stereo pipeline is checked against): R1, R2, P1, P2, Q from
// cv::stereoRectify (CALIB_ZERO_DISPARITY, alpha 0), every pixel's source
// position of both eyes from cv::initUndistortRectifyMap (CV_32FC1), and the
// fixed-point rectifier's output against cv::remap. The largest differences
// are printed so a drift shows before it fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "drivers/camera/stereo_rectification.hpp"
#include "drivers/camera/stereo_rectifier.hpp"
#include "unit/drivers/zed_test_calibrations.hpp"

namespace {

using rtfuse::drivers::CameraIntrinsics;
using rtfuse::drivers::RawPositionMap;
using rtfuse::drivers::StereoCalibration;
using rtfuse::drivers::StereoRectification;
using rtfuse::drivers::StereoRectifier;

constexpr double kMaxPixelDifference = 0.05;

struct OpenCvRectification {
  cv::Mat k[2], d[2];
  cv::Mat r1, r2, p1, p2, q;
};

cv::Mat camera_matrix(const CameraIntrinsics& c) {
  return (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
}

cv::Mat distortion(const CameraIntrinsics& c) { return (cv::Mat_<double>(1, 5) << c.k1, c.k2, c.p1, c.p2, c.k3); }

OpenCvRectification opencv_rectify(const StereoCalibration& c) {
  OpenCvRectification o;
  o.k[0] = camera_matrix(c.left);
  o.k[1] = camera_matrix(c.right);
  o.d[0] = distortion(c.left);
  o.d[1] = distortion(c.right);
  cv::Mat rvec = (cv::Mat_<double>(3, 1) << c.rotation.x(), c.rotation.y(), c.rotation.z());
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  cv::Mat t = (cv::Mat_<double>(3, 1) << c.translation.x(), c.translation.y(), c.translation.z());
  const cv::Size size(c.width, c.height);
  cv::stereoRectify(o.k[0], o.d[0], o.k[1], o.d[1], size, r, t, o.r1, o.r2, o.p1, o.p2, o.q, cv::CALIB_ZERO_DISPARITY,
                    0.0, size);
  return o;
}

template <typename M>
double max_difference(const cv::Mat& cv_m, const M& ours) {
  double worst = 0.0;
  for (int i = 0; i < ours.rows(); ++i) {
    for (int j = 0; j < ours.cols(); ++j) worst = std::max(worst, std::fabs(cv_m.at<double>(i, j) - ours(i, j)));
  }
  return worst;
}

// A textured grey image (smooth gradients and fine detail) in one eye.
cv::Mat test_pattern(int width, int height, int seed) {
  cv::Mat img(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double v = 128 + 60 * std::sin(0.07 * x + seed) * std::cos(0.05 * y) + 40 * std::sin(0.011 * (x + 2 * y));
      img.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
    }
  }
  return img;
}

void compare_with_opencv(const char* label, const StereoCalibration& c) {
  StereoRectification ours;
  std::string error;
  ASSERT_TRUE(compute_stereo_rectification(c, &ours, &error)) << error;
  const OpenCvRectification ref = opencv_rectify(c);

  const double d_r1 = max_difference(ref.r1, ours.left.rotation);
  const double d_r2 = max_difference(ref.r2, ours.right.rotation);
  const double d_p1 = max_difference(ref.p1, ours.left.projection);
  const double d_p2 = max_difference(ref.p2, ours.right.projection);
  const double d_q = max_difference(ref.q, ours.q);
  std::printf("[%s] max |ours - OpenCV|: R1 %.3g  R2 %.3g  P1 %.3g px  P2 %.3g px  Q %.3g\n", label, d_r1, d_r2, d_p1,
              d_p2, d_q);
  EXPECT_LE(d_r1, 1e-9);
  EXPECT_LE(d_r2, 1e-9);
  EXPECT_LE(d_p1, 1e-3);
  EXPECT_LE(d_p2, 1e-3);
  EXPECT_LE(d_q, 1e-3);

  // Every pixel's source position, both eyes.
  const cv::Size size(c.width, c.height);
  StereoRectifier rectifier(c, ours);
  const rtfuse::drivers::RectifiedEye* eyes[2] = {&ours.left, &ours.right};
  const CameraIntrinsics* raws[2] = {&c.left, &c.right};
  double worst_map = 0.0;
  double worst_table = 0.0;
  int inside = 0;
  cv::Mat maps[2][2];
  for (int eye = 0; eye < 2; ++eye) {
    cv::Mat& mx = maps[eye][0];
    cv::Mat& my = maps[eye][1];
    cv::initUndistortRectifyMap(ref.k[eye], ref.d[eye], eye == 0 ? ref.r1 : ref.r2, eye == 0 ? ref.p1 : ref.p2, size,
                                CV_32FC1, mx, my);
    const RawPositionMap map(*raws[eye], *eyes[eye]);
    for (int v = 0; v < c.height; ++v) {
      for (int u = 0; u < c.width; ++u) {
        double x = 0, y = 0;
        ASSERT_TRUE(map.at(u, v, &x, &y));
        const double cx = mx.at<float>(v, u);
        const double cy = my.at<float>(v, u);
        worst_map = std::max({worst_map, std::fabs(x - cx), std::fabs(y - cy)});
        // The rectifier's fixed-point table: the same position to 1/128 px.
        const StereoRectifier::Sample s = rectifier.sample(eye, u, v);
        if (s.inside) {
          ++inside;
          const double tx = s.x + s.wx / 64.0;
          const double ty = s.y + s.wy / 64.0;
          worst_table = std::max({worst_table, std::fabs(tx - cx), std::fabs(ty - cy)});
        }
      }
    }
  }
  const int total = 2 * c.width * c.height;
  std::printf("[%s] max |source position - initUndistortRectifyMap| over %d px: %.3g px (fixed-point table %.3g px, "
              "%d px inside)\n",
              label, total, worst_map, worst_table, inside);
  EXPECT_LE(worst_map, kMaxPixelDifference);
  EXPECT_LE(worst_table, kMaxPixelDifference);

  // The rectifier's output against cv::remap (bilinear, constant 0 border)
  // on a textured side-by-side frame.
  const cv::Mat raw[2] = {test_pattern(c.width, c.height, 1), test_pattern(c.width, c.height, 4)};
  const int bpl = c.width * 4;
  std::vector<std::uint8_t> yuyv(static_cast<std::size_t>(bpl) * static_cast<std::size_t>(c.height));
  for (int y = 0; y < c.height; ++y) {
    for (int x = 0; x < 2 * c.width; ++x) {
      const std::size_t o = static_cast<std::size_t>(y) * static_cast<std::size_t>(bpl) + static_cast<std::size_t>(x) * 2;
      yuyv[o] = raw[x / c.width].at<std::uint8_t>(y, x % c.width);
      yuyv[o + 1] = static_cast<std::uint8_t>(x & 1 ? 0x6B : 0x94);  // chroma must not leak into luma
    }
  }
  std::vector<std::uint8_t> out[2];
  for (auto& o : out) o.assign(static_cast<std::size_t>(c.width) * static_cast<std::size_t>(c.height), 0);
  ASSERT_TRUE(rectifier.rectify({yuyv.data(), yuyv.size(), 2 * c.width, c.height, bpl}, {out[0].data(), c.width},
                                {out[1].data(), c.width}));
  int worst_grey = 0;
  for (int eye = 0; eye < 2; ++eye) {
    cv::Mat expected;
    cv::remap(raw[eye], expected, maps[eye][0], maps[eye][1], cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    for (int v = 0; v < c.height; ++v) {
      for (int u = 0; u < c.width; ++u) {
        const float x = maps[eye][0].at<float>(v, u);
        const float y = maps[eye][1].at<float>(v, u);
        // Where OpenCV blends the border, ours is 0 by definition.
        if (!(x >= 1 && y >= 1 && x <= c.width - 2 && y <= c.height - 2)) continue;
        const int ours_v = out[eye][static_cast<std::size_t>(v) * static_cast<std::size_t>(c.width) + static_cast<std::size_t>(u)];
        worst_grey = std::max(worst_grey, std::abs(ours_v - expected.at<std::uint8_t>(v, u)));
      }
    }
  }
  std::printf("[%s] max |rectifier - cv::remap| inside the image: %d grey levels\n", label, worst_grey);
  // cv::remap quantises positions to 1/32 px, ours to 1/64: on this pattern's
  // steepest slope (~10 levels/px) that is at most a level or two.
  EXPECT_LE(worst_grey, 2);
}

TEST(OpenCvReference, ZedLikeVga) { compare_with_opencv("VGA", rtfuse::test::zed_like_vga()); }

TEST(OpenCvReference, ZedLikeHd) { compare_with_opencv("HD", rtfuse::test::zed_like_hd()); }

TEST(OpenCvReference, LargerRotation) { compare_with_opencv("rotated VGA", rtfuse::test::rotated_vga()); }

}  // namespace
