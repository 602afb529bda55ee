// The simulated stereo camera's cost (src/sim/stereo_renderer.hpp):
//
//   BM_RenderVgaStereoFrame   one side-by-side YUYV frame, 2 x 672 x 376, of
//                             the default camera world, along the demo
//                             drive's ground truth at 30 fps (a ZED-like
//                             distorted pair, 0.35 m up at the front of
//                             base_link, looking ahead)
//
// It must keep up live at 30 fps on one core beside the rest of the
// simulator: the aim is frame_median_ms <= 10 in a release build, and
// allocs_per_iter = 0. Nothing asserts a time; a benchmark that cannot do
// its job says why with SkipWithError.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <ctime>
#include <string>
#include <vector>

#include "sim/camera_world.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/stereo_renderer.hpp"
#include "sim/truth_trajectory.hpp"
#include "support/alloc_counter.hpp"

namespace {

using rtfuse::test::AllocScope;

rtfuse::drivers::StereoCalibration zed_like_vga() {
  rtfuse::drivers::StereoCalibration c;
  c.width = 672;
  c.height = 376;
  c.left = {350.0, 350.0, 336.0, 188.0, -0.17, 0.025, 0.0002, -0.0001, 0.0};
  c.right = {351.0, 350.5, 334.0, 189.0, -0.168, 0.024, -0.0001, 0.0002, 0.0};
  c.rotation = Eigen::Vector3d(0.002, -0.003, 0.001);
  c.translation = Eigen::Vector3d(-0.12, 0.0, 0.0);
  return c;
}

// The left eye's optical frame in the world at the truth's pose: base_link
// (x forward, z up) -> the camera mount (0.2 m ahead, 0.35 m up) -> optical
// axes (z forward, x right, y down).
rtfuse::geometry::RigidTransform left_eye_pose(const rtfuse::sim::TruthState& s) {
  rtfuse::geometry::RigidTransform world_T_base;
  world_T_base.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(s.yaw, Eigen::Vector3d::UnitZ()));
  world_T_base.translation = Eigen::Vector3d(s.x, s.y, 0.0);
  Eigen::Matrix3d base_r_optical;
  base_r_optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  rtfuse::geometry::RigidTransform base_T_optical;
  base_T_optical.rotation = Eigen::Quaterniond(base_r_optical);
  base_T_optical.translation = Eigen::Vector3d(0.2, 0.0, 0.35);
  return world_T_base * base_T_optical;
}

double thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e9 + static_cast<double>(ts.tv_nsec);
}

void BM_RenderVgaStereoFrame(benchmark::State& state) {
  rtfuse::sim::DriveScenario scenario;
  std::string error;
  if (!rtfuse::sim::load_drive_scenario(std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/demo.toml", &scenario,
                                        &error)) {
    state.SkipWithError(("config/scenarios/demo.toml: " + error).c_str());
    return;
  }
  const rtfuse::sim::TruthTrajectory truth(scenario);
  const rtfuse::sim::CameraWorld world;
  rtfuse::sim::StereoRenderer renderer(zed_like_vga(), world);
  if (!renderer.valid()) {
    state.SkipWithError(renderer.error());
    return;
  }
  const int bytes_per_line = renderer.min_bytes_per_line();
  std::vector<std::uint8_t> frame(static_cast<std::size_t>(bytes_per_line) *
                                  static_cast<std::size_t>(renderer.eye_height()));
  constexpr double kFps = 30.0;
  const auto frames_per_drive = static_cast<std::uint32_t>(truth.duration_s() * kFps);
  std::uint32_t sequence = 0;
  auto one_frame = [&]() {
    const double t = static_cast<double>(sequence % std::max<std::uint32_t>(frames_per_drive, 1)) / kFps;
    const rtfuse::TimeNs stamp = static_cast<rtfuse::TimeNs>(sequence) * 33'333'333;
    const bool ok = renderer.render(left_eye_pose(truth.truth_at(t)), stamp, sequence, frame.data(), bytes_per_line);
    ++sequence;
    return ok;
  };
  for (int i = 0; i < 3; ++i) one_frame();  // warm the caches and the page tables

  std::vector<double> wall_ns(static_cast<std::size_t>(state.max_iterations), 0.0);
  std::vector<double> cpu_ns(wall_ns.size(), 0.0);
  std::size_t n = 0;
  std::size_t allocations = 0;
  bool ok = true;
  {
    AllocScope allocs;
    for (auto _ : state) {
      const auto a = std::chrono::steady_clock::now();
      const double c = thread_cpu_ns();
      ok &= one_frame();
      const double cpu = thread_cpu_ns() - c;
      const auto b = std::chrono::steady_clock::now();
      if (n < wall_ns.size()) {
        wall_ns[n] = static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(b - a).count());
        cpu_ns[n] = cpu;
        ++n;
      }
      benchmark::DoNotOptimize(frame.data());
      benchmark::ClobberMemory();
    }
    allocations = allocs.count();
  }
  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocations), benchmark::Counter::kAvgIterations);
  if (n > 0) {
    wall_ns.resize(n);
    cpu_ns.resize(n);
    std::sort(wall_ns.begin(), wall_ns.end());
    std::sort(cpu_ns.begin(), cpu_ns.end());
    const std::size_t p99 = (n * 99 + 99) / 100 - 1;  // nearest rank
    state.counters["frame_median_ms"] = wall_ns[n / 2] * 1e-6;
    state.counters["frame_p99_ms"] = wall_ns[p99] * 1e-6;
    // CPU time of the rendering thread alone: what the frame costs when the
    // machine is shared (wall time also counts the waits for a core).
    state.counters["frame_cpu_median_ms"] = cpu_ns[n / 2] * 1e-6;
    state.counters["core_share_at_30fps"] = cpu_ns[n / 2] * 1e-9 * kFps;
  }
  state.SetItemsProcessed(state.iterations());
  if (!ok) state.SkipWithError("render() refused the frame");
}
BENCHMARK(BM_RenderVgaStereoFrame)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
