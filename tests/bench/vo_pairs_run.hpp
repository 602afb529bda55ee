#pragma once
// The visual odometry benchmarks' timed loop (vo_bench.cpp, vo_zed_bench.cpp):
// StereoOdometry::process on stored pairs in order, one pair per iteration,
// wrapping round to the first after the last with a reset, as a camera
// thread runs it. Counters: allocs_per_iter (must be 0), inliers per pair,
// pairs without a motion, and each pair's own time as p50_ms and p99_ms.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <vector>

#include "support/alloc_counter.hpp"
#include "vision/stereo_odometry.hpp"

namespace rtfuse::bench {

inline void run_vo_pairs(benchmark::State& state, vision::StereoOdometry& vo,
                         const std::vector<vision::GreyView>& left, const std::vector<vision::GreyView>& right) {
  std::size_t k = 0;
  std::int64_t pairs = 0, inliers = 0, failed = 0;
  std::size_t allocations = 0;
  std::vector<double> pair_ms;
  pair_ms.reserve(1 << 16);
  {
    test::AllocScope allocs;
    for (auto _ : state) {
      if (k == left.size()) {
        k = 0;
        vo.reset();
      }
      const auto start = std::chrono::steady_clock::now();
      const vision::StereoOdometryResult res = vo.process(left[k], right[k], k);
      const std::chrono::duration<double, std::milli> took = std::chrono::steady_clock::now() - start;
      if (pair_ms.size() < pair_ms.capacity()) pair_ms.push_back(took.count());
      benchmark::DoNotOptimize(res.motion.params.data());
      if (res.status == vision::VoStatus::kMotion) {
        inliers += res.motion.inliers;
      } else if (res.status != vision::VoStatus::kFirstFrame) {
        ++failed;
      }
      ++pairs;
      ++k;
    }
    allocations = allocs.count();
  }
  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocations), benchmark::Counter::kAvgIterations);
  state.counters["inliers_per_frame"] = static_cast<double>(inliers) / static_cast<double>(std::max<std::int64_t>(1, pairs));
  state.counters["failed"] = static_cast<double>(failed);
  if (!pair_ms.empty()) {
    std::sort(pair_ms.begin(), pair_ms.end());
    state.counters["p50_ms"] = pair_ms[pair_ms.size() / 2];
    state.counters["p99_ms"] = pair_ms[std::min(pair_ms.size() - 1, pair_ms.size() * 99 / 100)];
  }
}

}  // namespace rtfuse::bench
