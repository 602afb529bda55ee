// The visual odometry's time per frame (issue 10) for docs/performance.md:
//
//   BM_StereoOdometryKitti   StereoOdometry::process on the real KITTI 06
//                            pairs of ../shared/data (1226 x 370), one frame
//                            per iteration in order (wrapping round after the
//                            last with a reset), as rtfuse-vo runs it;
//                            counters: bench/vo_pairs_run.hpp's.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>
#include <vector>

#include "apps/grey_png.hpp"
#include "apps/kitti_sequence.hpp"
#include "bench/vo_pairs_run.hpp"
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
  std::vector<rtfuse::vision::GreyView> lv, rv;
  for (std::size_t k = 0; k < left.size(); ++k) {
    lv.push_back({left[k].pixels.data(), w, h, w});
    rv.push_back({right[k].pixels.data(), w, h, w});
  }
  rtfuse::bench::run_vo_pairs(state, vo, lv, rv);
}

BENCHMARK(BM_StereoOdometryKitti)->Unit(benchmark::kMillisecond)->Iterations(100);

}  // namespace
