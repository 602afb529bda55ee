// Stereo rectification properties on ZED-like calibrations: a 3-D point seen
// through both distorted raw cameras lands on the same rectified row in
// both eyes with disparity fx * B / Z, the remap takes each rectified pixel
// back to where the raw camera saw it, Q inverts the projection, and
// calibrations that are not side-by-side pairs are refused with a reason.
// (Agreement with OpenCV itself: tests/reference.)
#include "drivers/camera/stereo_rectification.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "support/alloc_counter.hpp"
#include "unit/drivers/zed_test_calibrations.hpp"

namespace stereo_rectification_test {

using rtfuse::drivers::CameraIntrinsics;
using rtfuse::drivers::RawPositionMap;
using rtfuse::drivers::StereoCalibration;
using rtfuse::drivers::StereoRectification;

// The plumb-bob projection, written independently of the code under test.
Eigen::Vector2d project_distorted(const CameraIntrinsics& k, const Eigen::Vector3d& p) {
  const double x = p.x() / p.z();
  const double y = p.y() / p.z();
  const double r2 = x * x + y * y;
  const double radial = 1 + k.k1 * r2 + k.k2 * r2 * r2 + k.k3 * r2 * r2 * r2;
  const double xd = x * radial + 2 * k.p1 * x * y + k.p2 * (r2 + 2 * x * x);
  const double yd = y * radial + k.p1 * (r2 + 2 * y * y) + 2 * k.p2 * x * y;
  return {k.fx * xd + k.cx, k.fy * yd + k.cy};
}

StereoRectification rectify(const StereoCalibration& c) {
  StereoRectification r;
  std::string error;
  EXPECT_TRUE(compute_stereo_rectification(c, &r, &error)) << error;
  return r;
}

void expect_point_geometry(const StereoCalibration& c) {
  const StereoRectification r = rectify(c);
  const Eigen::Matrix3d rot = rtfuse::drivers::rotation_from_vector(c.rotation);
  const RawPositionMap left_map(c.left, r.left);
  const RawPositionMap right_map(c.right, r.right);
  int checked = 0;
  for (double z : {0.6, 1.5, 4.0, 12.0}) {
    for (double fx : {-0.35, 0.0, 0.3}) {
      for (double fy : {-0.25, 0.05, 0.2}) {
        const Eigen::Vector3d x_left(fx * z, fy * z, z);  // left raw camera frame
        const Eigen::Vector3d x_right = rot * x_left + c.translation;
        // Where the rectified eyes see the point.
        const Eigen::Vector3d in_rect = r.left.rotation * x_left;
        const Eigen::Vector3d ul = r.left.projection * in_rect.homogeneous();
        const Eigen::Vector3d ur = r.right.projection * in_rect.homogeneous();
        const double u_l = ul.x() / ul.z(), v_l = ul.y() / ul.z();
        const double u_r = ur.x() / ur.z(), v_r = ur.y() / ur.z();
        EXPECT_NEAR(v_l, v_r, 1e-9) << "same row in both eyes";
        EXPECT_NEAR(u_l - u_r, r.fx * r.baseline_m / in_rect.z(), 1e-9) << "disparity = f B / Z";
        // The remap sends those rectified pixels to where each distorted raw
        // camera saw the point.
        double x = 0, y = 0;
        ASSERT_TRUE(left_map.at(u_l, v_l, &x, &y));
        const Eigen::Vector2d raw_l = project_distorted(c.left, x_left);
        EXPECT_NEAR(x, raw_l.x(), 1e-6);
        EXPECT_NEAR(y, raw_l.y(), 1e-6);
        ASSERT_TRUE(right_map.at(u_r, v_r, &x, &y));
        const Eigen::Vector2d raw_r = project_distorted(c.right, x_right);
        EXPECT_NEAR(x, raw_r.x(), 1e-6);
        EXPECT_NEAR(y, raw_r.y(), 1e-6);
        // Q takes (u, v, disparity) back to the point in the rectified frame.
        const Eigen::Vector4d h = r.q * Eigen::Vector4d(u_l, v_l, u_l - u_r, 1.0);
        EXPECT_NEAR((h.head<3>() / h.w() - in_rect).norm(), 0.0, 1e-9 * z);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 36);
}

TEST(StereoRectification, PointLandsOnSameRowWithDisparityFbOverZ) {
  expect_point_geometry(rtfuse::test::zed_like_hd());
  expect_point_geometry(rtfuse::test::zed_like_vga());
  expect_point_geometry(rtfuse::test::rotated_vga());
}

TEST(StereoRectification, SharedPinholeAndBaseline) {
  const StereoCalibration c = rtfuse::test::zed_like_hd();
  const StereoRectification r = rectify(c);
  EXPECT_EQ(r.width, 1280);
  EXPECT_EQ(r.height, 720);
  EXPECT_EQ(r.fx, r.fy);
  EXPECT_EQ(r.left.projection(0, 0), r.fx);
  EXPECT_EQ(r.right.projection(1, 1), r.fx);
  EXPECT_EQ(r.left.projection(0, 2), r.right.projection(0, 2));  // CALIB_ZERO_DISPARITY
  EXPECT_EQ(r.left.projection(1, 2), r.right.projection(1, 2));
  EXPECT_EQ(r.cx, r.left.projection(0, 2));
  EXPECT_NEAR(r.baseline_m, c.translation.norm(), 1e-12);
  EXPECT_NEAR(r.right.projection(0, 3), -r.fx * r.baseline_m, 1e-9);
  EXPECT_EQ(r.left.projection.col(3), Eigen::Vector3d::Zero());
  // alpha = 0 scales the mean raw fy just enough to fill the view; with the
  // ZED's barrel distortion (undistorting pushes the border outwards) and
  // its small rotations that is within a few percent.
  EXPECT_NE(r.fx, (c.left.fy + c.right.fy) / 2);
  EXPECT_NEAR(r.fx, (c.left.fy + c.right.fy) / 2, 0.03 * c.left.fy);
  for (const Eigen::Matrix3d& m : {r.left.rotation, r.right.rotation}) {
    EXPECT_NEAR((m * m.transpose() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
    EXPECT_NEAR(m.determinant(), 1.0, 1e-12);
  }
}

TEST(StereoRectification, AlphaZeroKeepsEveryPixelInsideForZedCalibrations) {
  for (const StereoCalibration& c : {rtfuse::test::zed_like_vga(), rtfuse::test::zed_like_hd()}) {
    const StereoRectification r = rectify(c);
    for (int eye = 0; eye < 2; ++eye) {
      const RawPositionMap map(eye == 0 ? c.left : c.right, eye == 0 ? r.left : r.right);
      for (int v = 0; v < c.height; v += 3) {
        for (int u = 0; u < c.width; u += 3) {
          double x = 0, y = 0;
          ASSERT_TRUE(map.at(u, v, &x, &y));
          ASSERT_TRUE(x > -0.5 && y > -0.5 && x < c.width - 0.5 && y < c.height - 0.5)
              << "eye " << eye << " (" << u << ", " << v << ") -> (" << x << ", " << y << ")";
        }
      }
    }
  }
}

TEST(StereoRectification, AlignedUndistortedPairIsLeftAsItIs) {
  StereoCalibration c;
  c.width = 640;
  c.height = 480;
  c.left = {500, 500, 320, 240, 0, 0, 0, 0, 0};
  c.right = c.left;
  c.translation = Eigen::Vector3d(-0.1, 0, 0);
  const StereoRectification r = rectify(c);
  EXPECT_NEAR((r.left.rotation - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-15);
  EXPECT_NEAR((r.right.rotation - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-15);
  EXPECT_NEAR(r.fx, 500.0, 1e-3);
  EXPECT_NEAR(r.cx, 320.0, 1e-3);
  EXPECT_NEAR(r.cy, 240.0, 1e-3);
  EXPECT_NEAR(r.baseline_m, 0.1, 1e-15);
  const RawPositionMap map(c.left, r.left);
  double x = 0, y = 0;
  ASSERT_TRUE(map.at(100, 400, &x, &y));
  EXPECT_NEAR(x, 100, 1e-3);
  EXPECT_NEAR(y, 400, 1e-3);
}

TEST(StereoRectification, RotationVectorMatchesAngleAxis) {
  const Eigen::Vector3d r(0.03, -0.2, 0.11);
  const Eigen::Matrix3d expected = Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix();
  EXPECT_NEAR((rtfuse::drivers::rotation_from_vector(r) - expected).norm(), 0.0, 1e-15);
  EXPECT_EQ(rtfuse::drivers::rotation_from_vector(Eigen::Vector3d::Zero()), Eigen::Matrix3d::Identity());
}

TEST(StereoRectification, RefusesWhatIsNotASideBySidePair) {
  const StereoCalibration good = rtfuse::test::zed_like_vga();
  StereoRectification r;
  std::string error;
  StereoCalibration c = good;
  c.translation = Eigen::Vector3d(0.01, -0.12, 0);
  EXPECT_FALSE(compute_stereo_rectification(c, &r, &error));
  EXPECT_NE(error.find("is not mostly along x: only side-by-side (horizontal) pairs"), std::string::npos) << error;
  c.translation = Eigen::Vector3d::Zero();
  EXPECT_FALSE(compute_stereo_rectification(c, &r, &error));
  EXPECT_NE(error.find("not mostly along x"), std::string::npos) << error;
  c = good;
  c.rotation = Eigen::Vector3d(0, 0.7, 0);
  EXPECT_FALSE(compute_stereo_rectification(c, &r, &error));
  EXPECT_NE(error.find("rotated 0.700 rad from each other"), std::string::npos) << error;
  c = good;
  c.right.fy = 0;
  EXPECT_FALSE(compute_stereo_rectification(c, &r, &error));
  EXPECT_NE(error.find("must be > 0"), std::string::npos) << error;
  c = good;
  c.left.k2 = std::nan("");
  EXPECT_FALSE(compute_stereo_rectification(c, &r, &error));
  EXPECT_NE(error.find("non-finite"), std::string::npos) << error;
  c = good;
  c.height = 0;
  EXPECT_FALSE(compute_stereo_rectification(c, &r, &error));
  EXPECT_EQ(error, "stereo rectification: image size 672 x 0: must be positive");
}

TEST(StereoRectification, RawPositionLookupDoesNotAllocate) {
  const StereoCalibration c = rtfuse::test::zed_like_vga();
  const StereoRectification r = rectify(c);
  const RawPositionMap map(c.left, r.left);
  double sum = 0;
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 1000; ++i) {
    double x = 0, y = 0;
    map.at(i % 672, i % 376, &x, &y);
    sum += x + y;
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(sum, 0);
}

}  // namespace stereo_rectification_test
