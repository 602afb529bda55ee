// The visual odometry's time per pair at the ZED's sizes (issue 10), for
// docs/performance.md: pairs the simulator renders along a drive (1 m/s,
// turning at 0.3 rad/s, 30 fps) through a ZED-like factory calibration,
// rectified by the camera driver's rectifier, then timed through
// StereoOdometry::process in order with [vo]'s default parameters.
//
//   BM_StereoOdometryZed/672    VGA, 672 x 376 per eye
//   BM_StereoOdometryZed/1280   HD720, 1280 x 720 per eye
//
// Counters: bench/vo_pairs_run.hpp's (p50_ms and p99_ms: the time a pair
// holds the camera thread). The rendering and rectification are set-up,
// not timed.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>
#include <vector>

#include "bench/vo_pairs_run.hpp"
#include "drivers/camera/stereo_rectification.hpp"
#include "drivers/camera/stereo_rectifier.hpp"
#include "runtime/devices/visual_odometry/visual_odometry.hpp"
#include "sim/camera_world.hpp"
#include "sim/stereo_renderer.hpp"
#include "unit/drivers/zed_test_calibrations.hpp"

namespace {

constexpr int kPairs = 60;

struct RenderedPairs {
  int width = 0, height = 0;
  rtfuse::drivers::StereoRectification rectification;
  std::vector<std::vector<std::uint8_t>> left, right;
};

bool render_pairs(const rtfuse::drivers::StereoCalibration& cal, RenderedPairs* out, std::string* error) {
  if (!rtfuse::drivers::compute_stereo_rectification(cal, &out->rectification, error)) return false;
  const rtfuse::drivers::StereoRectifier rectifier(cal, out->rectification);
  rtfuse::sim::CameraWorld world;
  rtfuse::sim::StereoRenderer renderer(cal, world);
  const int w = cal.width, h = cal.height, bpl = 4 * w;
  out->width = w;
  out->height = h;
  std::vector<std::uint8_t> frame(static_cast<std::size_t>(bpl) * static_cast<std::size_t>(h));
  // The optical frame of a camera 0.3 m up looking along the robot's x.
  Eigen::Matrix3d base_R_optical;
  base_R_optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  double x = 0.0, y = 0.0, yaw = 0.0;
  for (int k = 0; k < kPairs; ++k) {
    rtfuse::geometry::RigidTransform world_T_left;
    world_T_left.translation = Eigen::Vector3d(x, y, 0.3);
    world_T_left.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * base_R_optical);
    if (!renderer.render(world_T_left, 0, static_cast<std::uint32_t>(k), frame.data(), bpl)) {
      *error = "the renderer refused the calibration";
      return false;
    }
    out->left.emplace_back(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
    out->right.emplace_back(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
    if (!rectifier.rectify({frame.data(), frame.size(), 2 * w, h, bpl}, {out->left.back().data(), w},
                           {out->right.back().data(), w})) {
      *error = "the rectifier refused the frame";
      return false;
    }
    const double dt = 1.0 / 30.0;
    x += std::cos(yaw) * 1.0 * dt;
    y += std::sin(yaw) * 1.0 * dt;
    yaw += 0.3 * dt;
  }
  return true;
}

void BM_StereoOdometryZed(benchmark::State& state) {
  const bool vga = state.range(0) == 672;
  const rtfuse::drivers::StereoCalibration cal = vga ? rtfuse::test::zed_like_vga() : rtfuse::test::zed_like_hd();
  RenderedPairs pairs;
  std::string error;
  if (!render_pairs(cal, &pairs, &error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  const rtfuse::drivers::StereoRectification& r = pairs.rectification;
  const rtfuse::vision::StereoCameraModel model{r.fx, r.cx, r.cy, r.baseline_m};
  rtfuse::vision::StereoOdometry vo(pairs.width, pairs.height, model,
                                    rtfuse::stereo_odometry_params(rtfuse::VoSection{}));
  std::vector<rtfuse::vision::GreyView> lv, rv;
  for (std::size_t k = 0; k < pairs.left.size(); ++k) {
    lv.push_back({pairs.left[k].data(), pairs.width, pairs.height, pairs.width});
    rv.push_back({pairs.right[k].data(), pairs.width, pairs.height, pairs.width});
  }
  rtfuse::bench::run_vo_pairs(state, vo, lv, rv);
}
BENCHMARK(BM_StereoOdometryZed)->Arg(672)->Arg(1280)->Unit(benchmark::kMillisecond);

}  // namespace
