// The dense stereo matcher (vision/semi_global_matcher.hpp) on pairs the
// simulator renders, against the renderer's own geometry: for an ideal
// pinhole pair (no distortion, parallel eyes, so the raw frame is already
// rectified) each pixel's true disparity is f B / Z, Z the depth of the
// nearest world surface its ray meets (ray-cast here from the camera
// world's rectangles, as the renderer picks them: the nearest surface
// that faces the eye). At least 95 % of the pixels with an estimate must be
// within 1 px of it (issue 27).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

#include "sim/camera_world.hpp"
#include "sim/stereo_renderer.hpp"
#include "support/pinhole_stereo.hpp"
#include "support/world_depth.hpp"
#include "vision/semi_global_matcher.hpp"

namespace rtfuse::sim {
namespace stereo_disparity_truth_test {

constexpr int kW = 672;
constexpr int kH = 376;
constexpr double kF = 350.0;
constexpr double kCx = 336.0;
constexpr double kCy = 188.0;
constexpr double kBaseline = 0.12;
constexpr double kPi = 3.14159265358979323846;

drivers::StereoCalibration pinhole_pair() { return test::pinhole_stereo_pair(kW, kH, kF, kCx, kCy, kBaseline); }

// The left eye's optical frame at (x, y, z), looking horizontally along yaw
// and pitched down by `down` radians.
geometry::RigidTransform camera_at(double x, double y, double z, double yaw, double down) {
  Eigen::Matrix3d base_r_optical;  // optical z forward = base x, x right = -base y, y down = -base z
  base_r_optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                            Eigen::AngleAxisd(down, Eigen::Vector3d::UnitY()).toRotationMatrix() * base_r_optical;
  geometry::RigidTransform t;
  t.rotation = Eigen::Quaterniond(r);
  t.translation = Eigen::Vector3d(x, y, z);
  return t;
}

// The true disparity at pixel (u, v) of the left eye (0: the ray meets nothing).
double true_disparity(const CameraWorld& world, const geometry::RigidTransform& world_T_left, double u, double v) {
  const double z = test::true_depth(world, world_T_left, kF, kCx, kCy, u, v);
  return std::isfinite(z) ? kF * kBaseline / z : 0.0;
}

struct Score {
  int estimated = 0, within = 0;
  double share() const { return estimated > 0 ? static_cast<double>(within) / estimated : 0.0; }
};

Score score_view(const CameraWorld& world, const geometry::RigidTransform& pose, int downscale, double tolerance_px) {
  StereoRendererOptions options;  // the default exposure noise
  StereoRenderer renderer(pinhole_pair(), world, options);
  EXPECT_TRUE(renderer.valid());
  const int bpl = renderer.min_bytes_per_line();
  std::vector<std::uint8_t> frame(static_cast<std::size_t>(bpl) * kH);
  EXPECT_TRUE(renderer.render(pose, 0, 0, frame.data(), bpl));
  // Luma of each eye out of the side-by-side YUYV frame.
  vision::Plane<std::uint8_t> left(kW, kH), right(kW, kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      left.row(y)[x] = frame[static_cast<std::size_t>(y) * bpl + 2 * static_cast<std::size_t>(x)];
      right.row(y)[x] = frame[static_cast<std::size_t>(y) * bpl + 2 * static_cast<std::size_t>(kW + x)];
    }
  }
  vision::DisparityParams params;
  params.disparities = 64;
  params.downscale = downscale;
  vision::SemiGlobalMatcher matcher(kW, kH, params);
  EXPECT_TRUE(matcher.valid()) << matcher.error();
  vision::Plane<std::uint16_t> out(matcher.output_width(kW), matcher.output_height(kH));
  EXPECT_EQ(matcher.compute(vision::view_of(left), vision::view_of(right), vision::view_of(out)),
            vision::DisparityStatus::kOk);
  Score s;
  for (int y = 0; y < out.height(); ++y) {
    for (int x = 0; x < out.width(); ++x) {
      const std::uint16_t d = out.at(x, y);
      if (d == vision::kInvalidDisparity) continue;
      // A matched pixel stands for the input pixels it averaged.
      const double centre = (downscale - 1) / 2.0;
      const double truth = true_disparity(world, pose, downscale * x + centre, downscale * y + centre);
      ++s.estimated;
      s.within += std::fabs(d / static_cast<double>(vision::kDisparityScale) - truth) <= tolerance_px ? 1 : 0;
    }
  }
  return s;
}

class RenderedPairs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { world_ = new CameraWorld(); }
  static void TearDownTestSuite() {
    delete world_;
    world_ = nullptr;
  }
  static CameraWorld* world_;
};
CameraWorld* RenderedPairs::world_ = nullptr;

TEST_F(RenderedPairs, FullResolutionWithinOnePixel) {
  const CameraWorld& w = *world_;
  // Boxes and the textured wall ahead over the floor; a corner of the walls.
  const geometry::RigidTransform poses[] = {
      camera_at(w.config().max_x - 1.0, 4.0, 0.6, 0.0, 0.1),
      camera_at(w.config().max_x - 2.0, w.config().max_y - 2.0, 0.8, kPi / 4, 0.15),
  };
  for (const auto& pose : poses) {
    const Score s = score_view(w, pose, 1, 1.0);
    std::printf("full resolution: %d estimated (%.1f %% of the image), %.2f %% within 1 px of the truth\n",
                s.estimated, 100.0 * s.estimated / (kW * kH), 100.0 * s.share());
    EXPECT_GE(s.share(), 0.95);
    EXPECT_GE(s.estimated, kW * kH / 2);  // it does estimate most of the image
  }
}

TEST_F(RenderedPairs, HalfResolutionWithinOneMatchedPixel) {
  const CameraWorld& w = *world_;
  const Score s = score_view(w, camera_at(w.config().min_x + 1.0, 3.0, 0.6, kPi, 0.1), 2, 2.0);
  std::printf("half resolution: %d estimated, %.2f %% within 1 matched px (2 input px) of the truth\n", s.estimated,
              100.0 * s.share());
  EXPECT_GE(s.share(), 0.95);
  EXPECT_GE(s.estimated, kW * kH / 8);
}

}  // namespace stereo_disparity_truth_test
}  // namespace rtfuse::sim
