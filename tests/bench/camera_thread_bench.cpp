// The camera thread at VGA 30 fps in real time: the CPU it takes per frame
// (thread CPU time, so waiting for the next frame does not count) and the
// latency from a frame's capture stamp to the rectified pair being ready in
// the pool. Each iteration is one frame (1/30 s of wall time).
#include <benchmark/benchmark.h>
#include <time.h>

#include <algorithm>
#include <string>
#include <vector>

#include "live_camera_rig.hpp"
#include "support/alloc_counter.hpp"

namespace {

using rtfuse::TimeNs;

TimeNs thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

constexpr int kFrames = 90;  // 3 s

void BM_CameraThreadVga30(benchmark::State& state) {
  std::string error;
  auto rig = rtfuse::bench::LiveCameraRig::create(std::string(RTFUSE_SOURCE_DIR) + "/config/calibration/SN10000001.conf",
                                                  &error);
  if (!rig) {
    state.SkipWithError(error.c_str());
    return;
  }
  rtfuse::drivers::StereoFrameResult result;
  // One frame first: the stream starts and the pool's pages are touched.
  rig->camera().step(200'000'000, &result);
  std::vector<double> cpu_ms, latency_ms;
  cpu_ms.reserve(kFrames);
  latency_ms.reserve(kFrames);
  std::size_t allocations = 0;
  {
    rtfuse::test::AllocScope allocs;
    for (auto _ : state) {
      const TimeNs c0 = thread_cpu_ns();
      rig->camera().step(200'000'000, &result);
      const TimeNs ready = rtfuse::monotonic_now_ns();
      const TimeNs c1 = thread_cpu_ns();
      if (cpu_ms.size() < cpu_ms.capacity()) cpu_ms.push_back(static_cast<double>(c1 - c0) * 1e-6);
      if (result.published > 0 && latency_ms.size() < latency_ms.capacity()) {
        latency_ms.push_back(static_cast<double>(ready - result.stamp) * 1e-6);
      }
    }
    allocations = allocs.count();
  }
  state.counters["allocs_per_iter"] =
      benchmark::Counter(static_cast<double>(allocations), benchmark::Counter::kAvgIterations);
  if (latency_ms.size() < static_cast<std::size_t>(kFrames) * 9 / 10) {
    state.SkipWithError("the camera did not deliver a frame per step");
    return;
  }
  double cpu_sum = 0.0;
  for (double c : cpu_ms) cpu_sum += c;
  std::sort(cpu_ms.begin(), cpu_ms.end());
  std::sort(latency_ms.begin(), latency_ms.end());
  const auto p99 = [](const std::vector<double>& v) { return v[(v.size() * 99 + 99) / 100 - 1]; };
  state.counters["cpu_per_frame_median_ms"] = cpu_ms[cpu_ms.size() / 2];
  state.counters["cpu_share_at_30fps"] = cpu_sum / static_cast<double>(cpu_ms.size()) / 33.333;
  state.counters["latency_median_ms"] = latency_ms[latency_ms.size() / 2];
  state.counters["latency_p99_ms"] = p99(latency_ms);
  state.counters["drops"] = static_cast<double>(rig->camera().stats().stream.dropped);
}
BENCHMARK(BM_CameraThreadVga30)->Iterations(kFrames)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
