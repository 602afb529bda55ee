// The dense stereo matcher's time per pair (issue 27) for docs/performance.md:
//
//   BM_Disparity/W/H/N/S   SemiGlobalMatcher::compute on a W x H pair with N
//                          disparities (input pixels) at downscale S (1 full,
//                          2 half resolution: the live default), 8 paths.
//                          The pair: a smooth random texture over a slanted
//                          plane (disparities N/8 to N/2), rendered here so
//                          the benchmark needs no files.
//   BM_Disparity4Paths/... the same with 4 paths.
//   BM_Disparity4PathsBaseline/... 4 paths on the build's baseline lanes
//                          (SSE2, NEON) where the default would choose AVX2.
//
// The label names the backend the matcher ran on (DisparityBackend).
// Counters: allocs_per_iter (must be 0), valid (share of pixels estimated).
// The side-by-side figures against OpenCV's StereoSGBM on the Middlebury
// pairs come from rtfuse_bench_opencv (tests/bench/opencv/).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <random>
#include <vector>

#include "support/alloc_counter.hpp"
#include "vision/semi_global_matcher.hpp"

namespace {

struct BenchPair {
  rtfuse::vision::Plane<std::uint8_t> left, right;
};

// Grey levels on a 4 px lattice, bilinear between (integer arithmetic),
// seen at disparity d(x) = lo + (hi - lo) x / w in the right eye.
BenchPair slanted_pair(int w, int h, int lo, int hi) {
  constexpr int kCell = 4;
  const int gw = (w + 2 * hi) / kCell + 2, gh = h / kCell + 2;
  std::mt19937 rng(27);
  std::vector<int> grid(static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh));
  for (int& g : grid) g = static_cast<int>(rng() % 256);
  // Texture sampled at u / 16 of a pixel.
  auto tex = [&](int u16, int v) {
    const int gu = u16 / (16 * kCell), fu = u16 % (16 * kCell), gv = v / kCell, fv = v % kCell;
    auto g = [&](int i, int j) { return grid[static_cast<std::size_t>(j) * static_cast<std::size_t>(gw) + static_cast<std::size_t>(i)]; };
    const int top = g(gu, gv) * (16 * kCell - fu) + g(gu + 1, gv) * fu;
    const int bottom = g(gu, gv + 1) * (16 * kCell - fu) + g(gu + 1, gv + 1) * fu;
    return static_cast<std::uint8_t>((top * (kCell - fv) + bottom * fv) / (16 * kCell * kCell));
  };
  BenchPair p{rtfuse::vision::Plane<std::uint8_t>(w, h), rtfuse::vision::Plane<std::uint8_t>(w, h)};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int d16 = 16 * lo + 16 * (hi - lo) * x / w;
      p.left.row(y)[x] = tex(16 * (x + hi), y);
      p.right.row(y)[x] = tex(16 * (x + hi) + d16, y);
    }
  }
  return p;
}

void run_disparity(benchmark::State& state, int paths,
                   rtfuse::vision::DisparityBackend backend = rtfuse::vision::DisparityBackend::kAuto) {
  const int w = static_cast<int>(state.range(0)), h = static_cast<int>(state.range(1));
  rtfuse::vision::DisparityParams params;
  params.disparities = static_cast<int>(state.range(2));
  params.downscale = static_cast<int>(state.range(3));
  params.paths = paths;
  rtfuse::vision::SemiGlobalMatcher matcher(w, h, params, backend);
  if (!matcher.valid()) {
    state.SkipWithError(matcher.error());
    return;
  }
  state.SetLabel(rtfuse::vision::to_string(matcher.backend()));
  const BenchPair pair = slanted_pair(w, h, params.disparities / 8, params.disparities / 2);
  rtfuse::vision::Plane<std::uint16_t> out(matcher.output_width(w), matcher.output_height(h));
  const auto lv = rtfuse::vision::view_of(pair.left), rv = rtfuse::vision::view_of(pair.right);
  const auto ov = rtfuse::vision::view_of(out);
  if (matcher.compute(lv, rv, ov) != rtfuse::vision::DisparityStatus::kOk) {  // warm: page in the workspace
    state.SkipWithError("compute refused the pair");
    return;
  }
  std::size_t allocations = 0;
  {
    rtfuse::test::AllocScope allocs;
    for (auto _ : state) {
      benchmark::DoNotOptimize(matcher.compute(lv, rv, ov));
      benchmark::ClobberMemory();
    }
    allocations = allocs.count();
  }
  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocations), benchmark::Counter::kAvgIterations);
  state.counters["valid"] = static_cast<double>(matcher.valid_pixels()) / (static_cast<double>(out.width()) * out.height());
}

void BM_Disparity(benchmark::State& state) { run_disparity(state, 8); }
void BM_Disparity4Paths(benchmark::State& state) { run_disparity(state, 4); }
void BM_Disparity4PathsBaseline(benchmark::State& state) {
  run_disparity(state, 4, rtfuse::vision::DisparityBackend::kBaseline);
}

void disparity_sizes(benchmark::internal::Benchmark* b) {
  b->ArgNames({"w", "h", "disp", "down"});
  b->Args({640, 480, 64, 1})->Args({640, 480, 128, 1})->Args({640, 480, 64, 2})->Args({640, 480, 128, 2});
  b->Args({1280, 720, 128, 1})->Args({1280, 720, 128, 2});
  b->Unit(benchmark::kMillisecond);
}

BENCHMARK(BM_Disparity)->Apply(disparity_sizes);
BENCHMARK(BM_Disparity4Paths)->Apply(disparity_sizes);
BENCHMARK(BM_Disparity4PathsBaseline)->Apply(disparity_sizes);

}  // namespace
