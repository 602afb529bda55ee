// Back-projection of a disparity image into map points.
#include "mapping/disparity_points.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace disparity_points_test {

using namespace rtfuse::mapping;
using rtfuse::vision::DisparityImage;
using rtfuse::vision::kDisparityScale;
using rtfuse::vision::kInvalidDisparity;
using rtfuse::vision::StereoCameraModel;

const StereoCameraModel kCamera{100.0, 2.0, 1.5, 0.1};  // f, cu, cv, baseline

TEST(DisparityPoints, BackProjectsThroughTheRectifiedCamera) {
  std::vector<std::uint16_t> d(4 * 3, 8 * kDisparityScale);  // 8 px everywhere: Z = 100 * 0.1 / 8
  d[0] = kInvalidDisparity;
  d[1] = 0;
  const DisparityImage image{d.data(), 4, 3, 4};
  std::vector<MapPoint> out(12);
  const DisparityPointCounts c =
      disparity_points(image, 1, kCamera, rtfuse::geometry::RigidTransform::identity(), out.data(), out.size());
  EXPECT_EQ(c.points, 10u);
  EXPECT_EQ(c.invalid, 1u);
  EXPECT_EQ(c.at_infinity, 1u);
  // Pixels (0, 0) and (1, 0) were skipped: the first point is pixel (2, 0).
  EXPECT_FLOAT_EQ(out[0].z, 1.25f);
  EXPECT_FLOAT_EQ(out[0].x, 0.0f);
  EXPECT_FLOAT_EQ(out[0].y, -1.5f / 100.0f * 1.25f);
  EXPECT_FLOAT_EQ(out[1].x, 1.0f / 100.0f * 1.25f);  // pixel (3, 0)
}

TEST(DisparityPoints, AHalvedImageStandsForBlocksOfTheInput) {
  std::vector<std::uint16_t> d(2 * 2, 4 * kDisparityScale + kDisparityScale / 2);  // 4.5 input pixels
  const DisparityImage image{d.data(), 2, 2, 2};
  std::vector<MapPoint> out(4);
  disparity_points(image, 2, kCamera, rtfuse::geometry::RigidTransform::identity(), out.data(), out.size());
  const double z = 100.0 * 0.1 / 4.5;
  EXPECT_FLOAT_EQ(out[3].z, static_cast<float>(z));
  EXPECT_FLOAT_EQ(out[3].x, static_cast<float>((2.5 - 2.0) / 100.0 * z));  // pixel (1, 1): input centre 2.5
  EXPECT_FLOAT_EQ(out[3].y, static_cast<float>((2.5 - 1.5) / 100.0 * z));
}

TEST(DisparityPoints, TheMountCarriesThePointsIntoTheMap) {
  // An optical frame looking along the map's +x, 1 m up: optical z -> map
  // x, optical x -> map -y, optical y -> map -z.
  rtfuse::geometry::RigidTransform mount;
  Eigen::Matrix3d r;
  r << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  mount.rotation = Eigen::Quaterniond(r);
  mount.translation = Eigen::Vector3d(0.0, 0.0, 1.0);
  std::vector<std::uint16_t> d(1, 10 * kDisparityScale);
  const DisparityImage image{d.data(), 1, 1, 1};
  MapPoint p;
  const StereoCameraModel centred{100.0, 0.0, 0.0, 0.1};
  disparity_points(image, 1, centred, mount, &p, 1);
  EXPECT_NEAR(p.x, 1.0f, 1e-6f);
  EXPECT_NEAR(p.y, 0.0f, 1e-6f);
  EXPECT_NEAR(p.z, 1.0f, 1e-6f);
}

TEST(DisparityPoints, BadCamerasAndFullOutputsAreCounted) {
  std::vector<std::uint16_t> d(6, 16);
  const DisparityImage image{d.data(), 3, 2, 3};
  MapPoint out[4];
  const StereoCameraModel no_baseline{100.0, 1.0, 1.0, 0.0};
  const DisparityPointCounts bad =
      disparity_points(image, 1, no_baseline, rtfuse::geometry::RigidTransform::identity(), out, 4);
  EXPECT_EQ(bad.points, 0u);
  EXPECT_EQ(bad.invalid, 6u);
  const DisparityPointCounts full =
      disparity_points(image, 1, kCamera, rtfuse::geometry::RigidTransform::identity(), out, 4);
  EXPECT_EQ(full.points, 4u);
  EXPECT_EQ(full.truncated, 2u);
}

}  // namespace disparity_points_test
