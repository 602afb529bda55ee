// The stereo camera's per-frame cost (docs/performance.md): rectifying one
// side-by-side YUYV frame into two grey eyes with drivers/camera's
// StereoRectifier, from ZED-like factory calibrations.
//
//   BM_RectifyVgaPair     672 x 376 per eye (1344 x 376 YUYV frame)
//   BM_RectifyHd720Pair   1280 x 720 per eye (2560 x 720 YUYV frame)
//   BM_PairDigestVga      the driver's digest of one rectified VGA pair
//                         (chain_pair_digest: XXH64 over both eyes' rows)
//
// Targets on the reference x86-64 (-O2, no -march=native): <= 1.0 ms and
// <= 3 ms median. Every iteration must allocate nothing (allocs_per_iter = 0;
// the counting operator new is rtfuse_bench.cpp's).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/frame_pool.hpp"
#include "drivers/camera/stereo_camera.hpp"
#include "drivers/camera/stereo_rectification.hpp"
#include "drivers/camera/stereo_rectifier.hpp"
#include "support/alloc_counter.hpp"
#include "unit/drivers/zed_test_calibrations.hpp"

namespace {

using rtfuse::drivers::StereoCalibration;
using rtfuse::drivers::StereoRectification;
using rtfuse::drivers::StereoRectifier;
using rtfuse::test::AllocScope;

// A camera-like frame: smooth shading, edges and sensor noise in luma,
// slowly varying chroma, both eyes slightly different.
std::vector<std::uint8_t> realistic_yuyv(int frame_width, int height, int bytes_per_line) {
  std::vector<std::uint8_t> frame(static_cast<std::size_t>(bytes_per_line) * static_cast<std::size_t>(height));
  std::uint32_t noise = 12345u;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < frame_width; ++x) {
      noise = noise * 1664525u + 1013904223u;
      const int shade = 40 + (x % (frame_width / 2)) * 150 / (frame_width / 2) + y * 40 / height;
      const int edge = ((x / 37 + y / 23) % 2) * 30;
      const int value = shade + edge + static_cast<int>(noise >> 29) - 4;
      const std::size_t o = static_cast<std::size_t>(y) * static_cast<std::size_t>(bytes_per_line) +
                            static_cast<std::size_t>(x) * 2;
      frame[o] = static_cast<std::uint8_t>(value < 0 ? 0 : value > 255 ? 255 : value);
      frame[o + 1] = static_cast<std::uint8_t>(128 + ((x / 2 + y) % 16) - 8);
    }
  }
  return frame;
}

void rectify_pair(benchmark::State& state, const StereoCalibration& calibration) {
  StereoRectification rectification;
  std::string error;
  if (!compute_stereo_rectification(calibration, &rectification, &error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  const StereoRectifier rectifier(calibration, rectification);
  const int w = calibration.width;
  const int h = calibration.height;
  const int bpl = 4 * w;
  const std::vector<std::uint8_t> frame = realistic_yuyv(2 * w, h, bpl);
  std::vector<std::uint8_t> left(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  std::vector<std::uint8_t> right(left.size());
  bool ok = true;
  std::size_t allocations = 0;
  {
    AllocScope allocs;
    for (auto _ : state) {
      ok = rectifier.rectify({frame.data(), frame.size(), 2 * w, h, bpl}, {left.data(), w}, {right.data(), w}) && ok;
      benchmark::DoNotOptimize(left.data());
      benchmark::DoNotOptimize(right.data());
      benchmark::ClobberMemory();
    }
    allocations = allocs.count();
  }
  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocations), benchmark::Counter::kAvgIterations);
  state.counters["pixels"] = static_cast<double>(2 * w * h);
  if (!ok) state.SkipWithError("rectify() refused the frame");
}

void BM_RectifyVgaPair(benchmark::State& state) { rectify_pair(state, rtfuse::test::zed_like_vga()); }
BENCHMARK(BM_RectifyVgaPair)->Unit(benchmark::kMicrosecond);

void BM_RectifyHd720Pair(benchmark::State& state) { rectify_pair(state, rtfuse::test::zed_like_hd()); }
BENCHMARK(BM_RectifyHd720Pair)->Unit(benchmark::kMicrosecond);

// What the camera thread adds per published pair: both eyes of a VGA pair
// in a frame pool slot (rows padded to the pool's stride), digested and
// chained as StereoCamera does after rectifying.
void BM_PairDigestVga(benchmark::State& state) {
  constexpr int kW = 672;
  constexpr int kH = 376;
  rtfuse::FramePool pool(2, kW, kH);
  rtfuse::FramePool::WriteSlot slot = pool.acquire();
  if (!slot.valid()) {
    state.SkipWithError("no pool slot");
    return;
  }
  std::uint32_t noise = 12345u;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      noise = noise * 1664525u + 1013904223u;
      slot.left[y * slot.stride + x] = static_cast<std::uint8_t>(noise >> 24);
      slot.right[y * slot.stride + x] = static_cast<std::uint8_t>(noise >> 16);
    }
  }
  std::uint64_t digest = 0;
  std::size_t allocations = 0;
  {
    AllocScope allocs;
    for (auto _ : state) {
      digest = rtfuse::drivers::chain_pair_digest(digest, slot.left, slot.right, slot.width, slot.height,
                                                  slot.stride);
      benchmark::DoNotOptimize(digest);
    }
    allocations = allocs.count();
  }
  pool.abandon(slot);
  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocations), benchmark::Counter::kAvgIterations);
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * 2 * kW * kH);
}
BENCHMARK(BM_PairDigestVga)->Unit(benchmark::kMicrosecond);

}  // namespace
