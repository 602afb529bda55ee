// The visual odometry's time per frame (issue 10) for docs/performance.md:
//
//   BM_StereoOdometryKitti   StereoOdometry::process on the real KITTI 06
//                            pairs of ../shared/data (1226 x 370), one frame
//                            per iteration in order (wrapping round after the
//                            last with a reset), as rtfuse-vo runs it;
//                            counters: allocations per frame (must be 0),
//                            inliers and failures.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>
#include <vector>

#include "apps/grey_png.hpp"
#include "apps/kitti_sequence.hpp"
#include "support/alloc_counter.hpp"
#include "vision/stereo_odometry.hpp"

namespace {

const std::string kSeq = std::string(RTFUSE_SHARED_DATA) + "/kitti/kitti06_0000_0050";

void BM_StereoOdometryKitti(benchmark::State& state) {
  rtfuse::apps::KittiSequence seq;
  std::string error;
  if (!rtfuse::apps::open_kitti_sequence(kSeq, &seq, &error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  std::vector<rtfuse::apps::GreyPng> left(seq.left.size()), right(seq.left.size());
  for (std::size_t k = 0; k < seq.left.size(); ++k) {
    if (!rtfuse::apps::read_grey_png(seq.left[k], &left[k], &error) ||
        !rtfuse::apps::read_grey_png(seq.right[k], &right[k], &error)) {
      state.SkipWithError(error.c_str());
      return;
    }
  }
  const int w = left[0].width, h = left[0].height;
  rtfuse::vision::StereoOdometry vo(w, h, seq.camera, rtfuse::vision::StereoOdometryParams{});
  std::size_t k = 0;
  std::int64_t frames = 0, inliers = 0, failed = 0;
  std::size_t allocations = 0;
  {
    rtfuse::test::AllocScope allocs;
    for (auto _ : state) {
      if (k == left.size()) {
        k = 0;
        vo.reset();
      }
      const rtfuse::vision::GreyView l{left[k].pixels.data(), w, h, w}, r{right[k].pixels.data(), w, h, w};
      const rtfuse::vision::StereoOdometryResult res = vo.process(l, r, k);
      benchmark::DoNotOptimize(res.motion.params.data());
      if (res.status == rtfuse::vision::VoStatus::kMotion) {
        inliers += res.motion.inliers;
      } else if (res.status != rtfuse::vision::VoStatus::kFirstFrame) {
        ++failed;
      }
      ++frames;
      ++k;
    }
    allocations = allocs.count();
  }
  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocations), benchmark::Counter::kAvgIterations);
  state.counters["inliers_per_frame"] = static_cast<double>(inliers) / static_cast<double>(std::max<std::int64_t>(1, frames));
  state.counters["failed"] = static_cast<double>(failed);
}

BENCHMARK(BM_StereoOdometryKitti)->Unit(benchmark::kMillisecond)->Iterations(100);

}  // namespace
