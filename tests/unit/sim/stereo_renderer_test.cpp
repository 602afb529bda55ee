// The simulated stereo camera: a deterministic world seen through a
// calibrated, distorted pair. The geometry must be right to the pixel (the
// rectification and visual odometry downstream are tested against it), the
// texture must be there where features are wanted and absent on the plain
// wall, and a frame must cost no allocation.
#include "sim/stereo_renderer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "sim/camera_rays.hpp"
#include "sim/camera_world.hpp"
#include "sim/mip_texture.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::sim {
namespace stereo_renderer_test {

constexpr int kW = 672;
constexpr int kH = 376;
constexpr double kF = 350.0;
constexpr double kBaseline = 0.12;
constexpr double kPi = 3.14159265358979323846;

// A ZED-like VGA pair: barrel distortion of a wide lens, a slightly rotated
// right eye.
drivers::StereoCalibration zed_like() {
  drivers::StereoCalibration c;
  c.width = kW;
  c.height = kH;
  c.left = {kF, kF, 336.0, 188.0, -0.17, 0.025, 0.0002, -0.0001, 0.0};
  c.right = {351.0, 350.5, 334.0, 189.0, -0.168, 0.024, -0.0001, 0.0002, 0.0};
  c.rotation = Eigen::Vector3d(0.002, -0.003, 0.001);
  c.translation = Eigen::Vector3d(-kBaseline, 0.0, 0.0);
  return c;
}

// An ideal pair: no distortion, parallel eyes, so disparity = f B / Z.
drivers::StereoCalibration pinhole_pair() {
  drivers::StereoCalibration c;
  c.width = kW;
  c.height = kH;
  c.left = {kF, kF, 336.0, 188.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  c.right = c.left;
  c.translation = Eigen::Vector3d(-kBaseline, 0.0, 0.0);
  return c;
}

StereoRendererOptions quiet() {
  StereoRendererOptions o;
  o.noise_sigma_grey = 0.0;
  return o;
}

// The left eye's optical frame at (x, y, z) in the world, looking
// horizontally along heading yaw (0: +x), then pitched up by `pitch` and
// rolled by `roll` about its own axis of view.
geometry::RigidTransform camera_at(double x, double y, double z, double yaw, double pitch = 0.0, double roll = 0.0) {
  Eigen::Matrix3d base_r_optical;  // optical z forward = base x, optical x right = -base y, y down = -base z
  base_r_optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                            Eigen::AngleAxisd(-pitch, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()).toRotationMatrix() * base_r_optical;
  geometry::RigidTransform t;
  t.rotation = Eigen::Quaterniond(r);
  t.translation = Eigen::Vector3d(x, y, z);
  return t;
}

// One eye's luma out of a side-by-side YUYV frame.
struct Luma {
  int width = 0, height = 0;
  std::vector<int> v;
  int at(int x, int y) const { return v[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)]; }
};

Luma eye_luma(const std::vector<std::uint8_t>& frame, int bytes_per_line, int eye) {
  Luma l;
  l.width = kW;
  l.height = kH;
  l.v.resize(static_cast<std::size_t>(kW) * kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      l.v[static_cast<std::size_t>(y) * kW + static_cast<std::size_t>(x)] =
          frame[static_cast<std::size_t>(y) * static_cast<std::size_t>(bytes_per_line) + 2 * static_cast<std::size_t>(eye * kW + x)];
    }
  }
  return l;
}

class Rendered {
 public:
  Rendered(const drivers::StereoCalibration& cal, const CameraWorld& world, StereoRendererOptions o = quiet())
      : renderer(cal, world, o), bpl(renderer.min_bytes_per_line() + 64), frame(static_cast<std::size_t>(bpl) * kH, 0) {}
  void render(const geometry::RigidTransform& pose, std::uint32_t seq = 0) {
    ASSERT_TRUE(renderer.render(pose, 1000, seq, frame.data(), bpl, &info));
  }
  Luma eye(int e) const { return eye_luma(frame, bpl, e); }

  StereoRenderer renderer;
  int bpl;
  std::vector<std::uint8_t> frame;
  RenderedFrame info;
};

// Sum of absolute differences of a square patch of a centred at (ax, ay)
// and of b centred at (bx, by).
double sad(const Luma& a, int ax, int ay, const Luma& b, int bx, int by, int half) {
  double s = 0.0;
  for (int dy = -half; dy <= half; ++dy) {
    for (int dx = -half; dx <= half; ++dx) s += std::abs(a.at(ax + dx, ay + dy) - b.at(bx + dx, by + dy));
  }
  return s;
}

// Where the patch of a at (x, y) lies in b along the same row: the shift
// (b's x minus a's x) in [lo, hi], refined to a fraction of a pixel by a
// parabola through the best SAD and its neighbours.
double match_along_row(const Luma& a, const Luma& b, int x, int y, int lo, int hi, int half = 10) {
  int best = lo;
  double best_sad = 1e300;
  std::vector<double> costs;
  for (int d = lo; d <= hi; ++d) {
    const double c = sad(a, x, y, b, x + d, y, half);
    costs.push_back(c);
    if (c < best_sad) {
      best_sad = c;
      best = d;
    }
  }
  if (best == lo || best == hi) return best;
  const double cm = costs[static_cast<std::size_t>(best - lo - 1)];
  const double c0 = costs[static_cast<std::size_t>(best - lo)];
  const double cp = costs[static_cast<std::size_t>(best - lo + 1)];
  const double denom = cm - 2.0 * c0 + cp;
  return best + (denom > 0.0 ? 0.5 * (cm - cp) / denom : 0.0);
}

double mean_abs_gradient(const Luma& l, int x0, int y0, int x1, int y1) {
  double s = 0.0;
  int n = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      s += std::abs(l.at(x + 1, y) - l.at(x, y)) + std::abs(l.at(x, y + 1) - l.at(x, y));
      ++n;
    }
  }
  return s / n;
}

double stddev(const Luma& l, int x0, int y0, int x1, int y1) {
  double s = 0.0;
  double s2 = 0.0;
  int n = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      s += l.at(x, y);
      s2 += static_cast<double>(l.at(x, y)) * l.at(x, y);
      ++n;
    }
  }
  const double m = s / n;
  return std::sqrt(std::max(0.0, s2 / n - m * m));
}

CameraWorldConfig no_boxes() {
  CameraWorldConfig c;
  c.box_count = 0;
  return c;
}

TEST(StereoRenderer, LensInversionConvergesEverywhere) {
  const drivers::StereoCalibration cal = zed_like();
  const CameraWorld world(no_boxes());
  const StereoRenderer r(cal, world);
  ASSERT_TRUE(r.valid()) << r.error();
  for (int e = 0; e < 2; ++e) {
    EXPECT_TRUE(r.rays(e).converged());
    EXPECT_LT(r.rays(e).max_residual_px(), 1e-6);
  }
  // The rays round-trip through the forward model to the pixel they came from.
  const drivers::CameraIntrinsics& k = cal.left;
  for (const auto& px : {std::pair<double, double>{0.0, 0.0}, {671.0, 375.0}, {336.0, 188.0}, {10.0, 300.0}}) {
    const Undistorted u = undistort_normalized(k, (px.first - k.cx) / k.fx, (px.second - k.cy) / k.fy);
    ASSERT_TRUE(u.converged);
    double pu = 0.0;
    double pv = 0.0;
    ASSERT_TRUE(project_to_pixel(k, Eigen::Vector3d(2.0 * u.x, 2.0 * u.y, 2.0), &pu, &pv));
    EXPECT_NEAR(pu, px.first, 1e-6);
    EXPECT_NEAR(pv, px.second, 1e-6);
  }
}

TEST(StereoRenderer, RejectsALensThatFoldsOver) {
  drivers::StereoCalibration cal = zed_like();
  cal.left.k1 = -1.5;  // r_d = r (1 - 1.5 r^2) turns back at r = 0.47: the image corners have no ray
  const CameraWorld world(no_boxes());
  StereoRenderer r(cal, world);
  EXPECT_FALSE(r.valid());
  std::vector<std::uint8_t> frame(static_cast<std::size_t>(4 * kW) * kH);
  EXPECT_FALSE(r.render(camera_at(0, 0, 0.4, 0), 0, 0, frame.data(), 4 * kW));
}

TEST(StereoRenderer, SameInputsSameBytes) {
  const CameraWorld world_a;
  const CameraWorld world_b;  // built again from the same config: the same world
  Rendered a(zed_like(), world_a, StereoRendererOptions{});
  Rendered b(zed_like(), world_b, StereoRendererOptions{});
  const geometry::RigidTransform pose = camera_at(3.0, 1.0, 0.4, 0.3);
  a.render(pose, 7);
  b.render(pose, 7);
  EXPECT_EQ(a.frame, b.frame);
  a.render(pose, 7);
  EXPECT_EQ(a.frame, b.frame);

  // The noise is per frame: another sequence number changes pixels, by a
  // few grey levels.
  b.render(pose, 8);
  int changed = 0;
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < a.frame.size(); i += 2) {
    const int d = static_cast<int>(a.frame[i]) - static_cast<int>(b.frame[i]);
    changed += d != 0;
    sum_sq += static_cast<double>(d) * d;
  }
  const double pixels = 2.0 * kW * kH;
  EXPECT_GT(changed, pixels / 2);
  const double sigma_diff = std::sqrt(sum_sq / pixels);  // sqrt(2) * sigma, plus rounding
  EXPECT_GT(sigma_diff, 2.0);
  EXPECT_LT(sigma_diff, 4.0);

  // Chroma is neutral everywhere.
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < 2 * kW; ++x) ASSERT_EQ(a.frame[static_cast<std::size_t>(y * a.bpl + 2 * x + 1)], 128);
  }

  // Another seed is another world.
  CameraWorldConfig other;
  other.seed = 2;
  const CameraWorld world_c(other);
  Rendered c(zed_like(), world_c, StereoRendererOptions{});
  c.render(pose, 7);
  EXPECT_NE(a.frame, c.frame);
}

// Facing a textured wall square on at Z, the ideal pair sees it shifted by
// the disparity f B / Z.
TEST(StereoRenderer, DisparityOfAWallIsFocalTimesBaselineOverDepth) {
  const CameraWorld world(no_boxes());
  Rendered r(pinhole_pair(), world);
  constexpr double kZ = 3.0;
  r.render(camera_at(world.wall_max_x() - kZ, 5.0, 1.2, 0.0));
  const Luma left = r.eye(0);
  const Luma right = r.eye(1);
  for (const auto& p : {std::pair<int, int>{336, 188}, {150, 100}, {520, 260}, {250, 300}}) {
    const double shift = match_along_row(left, right, p.first, p.second, -40, 0);
    EXPECT_NEAR(-shift, kF * kBaseline / kZ, 0.25) << "at " << p.first << "," << p.second;
  }
}

// The wall's top edge against the sky is where the distorted projection of
// its 3-D points says, in both eyes: the renderer's lens is the calibration's.
TEST(StereoRenderer, WallTopEdgeLiesWhereTheDistortedProjectionPutsIt) {
  const CameraWorld world(no_boxes());
  const drivers::StereoCalibration cal = zed_like();
  Rendered r(cal, world);
  const geometry::RigidTransform world_T_left = camera_at(world.wall_max_x() - 5.0, 6.0, 1.0, 0.0);
  r.render(world_T_left);
  const geometry::RigidTransform left_T_world = world_T_left.inverse();
  const geometry::RigidTransform right_T_world = r.renderer.left_T_right().inverse() * left_T_world;
  double max_distortion_px = 0.0;
  for (int e = 0; e < 2; ++e) {
    const Luma l = r.eye(e);
    const drivers::CameraIntrinsics& k = e == 0 ? cal.left : cal.right;
    const geometry::RigidTransform& eye_T_world = e == 0 ? left_T_world : right_T_world;
    int checked = 0;
    for (double y = 6.0 - 6.0; y <= 6.0 + 6.0; y += 0.5) {
      const Eigen::Vector3d p = eye_T_world * Eigen::Vector3d(world.wall_max_x(), y, world.config().wall_height_m);
      double u = 0.0;
      double v = 0.0;
      ASSERT_TRUE(project_to_pixel(k, p, &u, &v));
      const int col = static_cast<int>(std::lround(u));
      if (col < 2 || col > kW - 3 || v < 2 || v > kH - 3) continue;
      // Sky (bright, smooth) above, the wall (at most 239 x its shade) below:
      // the first row from the top that is no longer sky.
      int edge = -1;
      for (int row = 0; row < kH; ++row) {
        if (l.at(col, row) < 190) {
          edge = row;
          break;
        }
      }
      // Pixel centres are integer rows: the first one below the edge at v.
      EXPECT_NEAR(edge, std::ceil(v), 1.0) << "eye " << e << " column " << col << " v " << v;
      ++checked;
      // How far the lens moved the edge: what this test would miss without distortion.
      const double v_pinhole = k.fy * p.y() / p.z() + k.cy;
      max_distortion_px = std::max(max_distortion_px, std::abs(v - v_pinhole));
    }
    EXPECT_GE(checked, 15);
  }
  EXPECT_GT(max_distortion_px, 5.0);
}

TEST(StereoRenderer, PlainWallIsPlainAndTexturedSurfacesAreTextured) {
  const CameraWorld world(no_boxes());
  Rendered r(zed_like(), world, StereoRendererOptions{});  // with exposure noise
  // Square on to the plain wall (min_y by default) from 3 m, at 1.2 m: the
  // wall fills the upper middle of the image.
  r.render(camera_at(5.0, world.wall_min_y() + 3.0, 1.2, -kPi / 2));
  const Luma plain = r.eye(0);
  EXPECT_LT(stddev(plain, 236, 60, 436, 180), 3.0);  // the exposure noise (sigma 2) and nothing else
  // The floor below it is textured.
  EXPECT_GT(mean_abs_gradient(plain, 100, 345, 572, 370), 6.0);

  // A textured wall, the same way.
  r.render(camera_at(world.wall_max_x() - 3.0, 5.0, 1.2, 0.0));
  const Luma textured = r.eye(0);
  EXPECT_GT(stddev(textured, 236, 60, 436, 180), 25.0);
  EXPECT_GT(mean_abs_gradient(textured, 236, 60, 436, 180), 6.0);

  // And so is every face of a box (the default world has them).
  const CameraWorld boxed;
  ASSERT_GT(boxed.box_count(), 0);
  for (int i = 0; i < boxed.surface_count(); ++i) {
    const WorldSurface& s = boxed.surface(i);
    if (s.kind == SurfaceKind::kPlainWall) {
      EXPECT_EQ(s.texture, -1);
      continue;
    }
    ASSERT_GE(s.texture, 0);
    const MipTexture& t = boxed.texture(s.texture);
    EXPECT_NEAR(t.width() * s.texel_m, s.size_u, s.texel_m);
    double g = 0.0;
    for (int y = 0; y + 1 < t.height(); ++y) {
      for (int x = 0; x + 1 < t.width(); ++x) g += std::abs(t.texel(0, x + 1, y) - t.texel(0, x, y));
    }
    EXPECT_GT(g / ((t.width() - 1) * (t.height() - 1)), 8.0) << "surface " << i;
  }
}

// Moving the camera moves the image as the geometry says: sideways by
// 0.2 m in front of a wall at 3 m shifts it by f * 0.2 / 3 pixels; turning
// by 3 degrees moves the centre by f tan(3 degrees).
TEST(StereoRenderer, ImageMovesConsistentlyWithTheCamera) {
  const CameraWorld world(no_boxes());
  Rendered r(pinhole_pair(), world);
  const double x = world.wall_max_x() - 3.0;
  r.render(camera_at(x, 5.0, 1.2, 0.0));
  const Luma before = r.eye(0);
  r.render(camera_at(x, 5.0 - 0.2, 1.2, 0.0));  // 0.2 m to the camera's right
  const Luma moved = r.eye(0);
  for (const auto& p : {std::pair<int, int>{336, 188}, {200, 120}, {480, 250}}) {
    EXPECT_NEAR(match_along_row(before, moved, p.first, p.second, -40, 0), -kF * 0.2 / 3.0, 0.3);
  }
  const double turn = 3.0 * kPi / 180.0;
  r.render(camera_at(x, 5.0, 1.2, turn));  // to the left: the scene moves right
  const Luma turned = r.eye(0);
  EXPECT_NEAR(match_along_row(before, turned, 336, 188, 0, 40), kF * std::tan(turn), 0.3);
}

// Above the horizon the sky, below it the world, whatever the camera's roll
// and pitch. From 5 m up the walls are below the horizon too.
TEST(StereoRenderer, SkyAboveTheHorizonGroundBelow) {
  const CameraWorld world;
  Rendered r(zed_like(), world);
  const geometry::RigidTransform pose = camera_at(6.0, 6.0, 5.0, 0.7, 0.08, 0.15);
  r.render(pose);
  const Eigen::Vector3d up = pose.rotation.conjugate() * Eigen::Vector3d::UnitZ();
  const Luma l = r.eye(0);
  const drivers::CameraIntrinsics& k = r.renderer.calibration().left;
  int sky = 0;
  int ground = 0;
  int ground_like_sky = 0;
  for (int y = 0; y < kH; y += 3) {
    for (int x = 0; x < kW; x += 3) {
      const Undistorted d = undistort_normalized(k, (x - k.cx) / k.fx, (y - k.cy) / k.fy);
      const Eigen::Vector3d ray = Eigen::Vector3d(d.x, d.y, 1.0).normalized();
      const double elevation = std::asin(ray.dot(up));
      const float sky_luma = CameraWorld::sky_luma(static_cast<float>(ray.dot(up)));
      if (elevation > 0.01) {
        ASSERT_NEAR(l.at(x, y), sky_luma, 1.0) << x << "," << y;
        ++sky;
      } else if (elevation < -0.01) {
        ground_like_sky += std::abs(l.at(x, y) - sky_luma) <= 1.0f;
        ++ground;
      }
    }
  }
  EXPECT_GT(sky, 2000);
  EXPECT_GT(ground, 2000);
  // Below the horizon: floor, walls, and the floor's grey beyond them, which
  // may match the sky at a pixel by chance but not over a region.
  EXPECT_LT(ground_like_sky, ground / 20);
  EXPECT_GT(r.info.sky_pixels, 2 * sky);  // both eyes, every pixel
}

TEST(StereoRenderer, RendersWithoutAllocating) {
  const CameraWorld world;
  Rendered r(zed_like(), world, StereoRendererOptions{});
  r.render(camera_at(1.0, 0.0, 0.4, 0.0));  // warm
  std::size_t allocations = 0;
  {
    test::AllocScope scope;
    for (std::uint32_t i = 0; i < 5; ++i) {
      r.renderer.render(camera_at(1.0 + 0.1 * i, 0.05 * i, 0.4, 0.1 * i), 1000 + i, i, r.frame.data(), r.bpl);
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
}

TEST(StereoRenderer, RefusesAShortLine) {
  const CameraWorld world(no_boxes());
  StereoRenderer r(pinhole_pair(), world);
  std::vector<std::uint8_t> frame(static_cast<std::size_t>(4 * kW) * kH, 7);
  EXPECT_FALSE(r.render(camera_at(0, 0, 0.4, 0), 0, 0, frame.data(), 4 * kW - 2));
  EXPECT_FALSE(r.render(camera_at(0, 0, 0.4, 0), 0, 0, nullptr, 4 * kW));
  EXPECT_EQ(frame[0], 7);
}

// Far away, one pixel covers many texels: the prefiltered levels hold the
// local mean, so a fine pattern fades to grey instead of aliasing.
TEST(MipTexture, CoarserLevelsHoldTheMean) {
  std::vector<std::uint8_t> checker(64 * 64);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) checker[static_cast<std::size_t>(y * 64 + x)] = ((x + y) & 1) ? 200 : 40;
  }
  const MipTexture t(64, 64, checker);
  EXPECT_EQ(t.levels(), 7);
  EXPECT_EQ(t.width(6), 1);
  EXPECT_EQ(t.texel(1, 3, 5), 120);
  EXPECT_NEAR(t.sample_lod(17.3f, 40.8f, 2.5f), 120.0f, 0.5f);
  EXPECT_NEAR(t.sample(0, 10.5f, 10.5f), 40.0f, 1e-4f);  // a texel centre
  EXPECT_NEAR(t.sample(0, 11.0f, 10.5f), 120.0f, 1e-4f);  // between two texels
}

}  // namespace stereo_renderer_test
}  // namespace rtfuse::sim
