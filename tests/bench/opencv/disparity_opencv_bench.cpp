// rtfuse_bench_opencv: the dense stereo matcher side by side with OpenCV
// 4.6's StereoSGBM (test-only) on the Middlebury 2003 pairs of
// RTFUSE_SHARED_DATA, one thread each (issue 27, docs/performance.md).
//
//   BM_SgbmSideBySide/<pair>/<paths>/<simd>: each iteration runs OpenCV
//   (MODE_SGBM, block 5, P1 = 8 * 25, P2 = 32 * 25, disp12MaxDiff 1,
//   uniqueness 10, speckles 100 / 2, 64 disparities) and then ours on the
//   same grey pair, timing each: interleaved, so both see the same machine.
//   simd 0: ours on the fastest backend this CPU runs (AVX2 on most x86-64,
//   chosen at run time as OpenCV chooses its own); 1: on the build's
//   baseline (SSE2, NEON), to show what the dispatch gains. The label names
//   the pair and the backend. Counters: the
//   median ms of each, speedup = OpenCV / ours, and the share of known
//   ground-truth pixels off by more than 1 px (unestimated counted as off),
//   bad1_ours and bad1_opencv, in %. The benchmark's own time is the pair of
//   runs together.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "apps/grey_png.hpp"
#include "vision/semi_global_matcher.hpp"

namespace {

const char* const kPairs[] = {"teddy", "cones"};

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Percentage of known pixels (truth > 0, scaled by 4) whose estimate
// (negative: none) is off by more than 1 px.
template <class Est>
double bad1_percent(const rtfuse::apps::GreyPng& truth, Est est) {
  long known = 0, bad = 0;
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      const int t = truth.pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(truth.width) +
                                 static_cast<std::size_t>(x)];
      if (t == 0) continue;
      ++known;
      const double e = est(x, y);
      bad += e < 0.0 || std::fabs(e - t / 4.0) > 1.0 ? 1 : 0;
    }
  }
  return known > 0 ? 100.0 * static_cast<double>(bad) / static_cast<double>(known) : 100.0;
}

void BM_SgbmSideBySide(benchmark::State& state) {
  const std::string dir = std::string(RTFUSE_SHARED_DATA) + "/middlebury/" + kPairs[state.range(0)];
  rtfuse::apps::GreyPng left, right, truth;
  std::string error;
  if (!rtfuse::apps::read_luma_png(dir + "/im2.png", &left, &error) ||
      !rtfuse::apps::read_luma_png(dir + "/im6.png", &right, &error) ||
      !rtfuse::apps::read_grey_png(dir + "/disp2.png", &truth, &error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  const int w = left.width, h = left.height;
  cv::setNumThreads(1);
  const cv::Mat l(h, w, CV_8UC1, left.pixels.data()), r(h, w, CV_8UC1, right.pixels.data());
  cv::Ptr<cv::StereoSGBM> sgbm =
      cv::StereoSGBM::create(0, 64, 5, 8 * 25, 32 * 25, 1, 0, 10, 100, 2, cv::StereoSGBM::MODE_SGBM);
  cv::Mat cv_disp;
  rtfuse::vision::DisparityParams params;
  params.paths = static_cast<int>(state.range(1));
  const auto backend =
      state.range(2) == 0 ? rtfuse::vision::DisparityBackend::kAuto : rtfuse::vision::DisparityBackend::kBaseline;
  rtfuse::vision::SemiGlobalMatcher matcher(w, h, params, backend);
  state.SetLabel(std::string(kPairs[state.range(0)]) + " " + rtfuse::vision::to_string(matcher.backend()));
  rtfuse::vision::Plane<std::uint16_t> ours(w, h);
  const rtfuse::vision::GreyView lv{left.pixels.data(), w, h, w}, rv{right.pixels.data(), w, h, w};
  std::vector<double> ms_cv, ms_ours;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    sgbm->compute(l, r, cv_disp);
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(matcher.compute(lv, rv, rtfuse::vision::view_of(ours)));
    const auto t2 = std::chrono::steady_clock::now();
    ms_cv.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    ms_ours.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
  }
  const double cv_ms = median_of(ms_cv), our_ms = median_of(ms_ours);
  state.counters["opencv_ms"] = cv_ms;
  state.counters["ours_ms"] = our_ms;
  state.counters["speedup"] = our_ms > 0.0 ? cv_ms / our_ms : 0.0;
  state.counters["bad1_opencv"] = bad1_percent(truth, [&](int x, int y) {
    const int v = cv_disp.at<std::int16_t>(y, x);
    return v < 0 ? -1.0 : v / 16.0;
  });
  state.counters["bad1_ours"] = bad1_percent(truth, [&](int x, int y) {
    const int v = ours.at(x, y);
    return v == rtfuse::vision::kInvalidDisparity ? -1.0 : v / static_cast<double>(rtfuse::vision::kDisparityScale);
  });
}

BENCHMARK(BM_SgbmSideBySide)
    ->ArgNames({"pair", "paths", "simd"})
    ->Args({0, 8, 0})
    ->Args({1, 8, 0})
    ->Args({0, 4, 0})
    ->Args({1, 4, 0})
    ->Args({0, 4, 1})
    ->Args({1, 4, 1})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
