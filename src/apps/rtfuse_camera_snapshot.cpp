// rtfuse-camera-snapshot: one rectified stereo pair of the configured camera
// as a PNG, left | right, with horizontal guide lines: the picture an
// engineer looks at to trust a calibration (a feature must sit on the same
// line in both eyes). The camera is the config's: a V4L2 device with
// [hardware] backend = "linux", the simulated robot's rendered camera with
// backend = "sim" (at --time seconds into its drive). The same camera driver
// and rectification as rtfused.
//
// Exit: 0 written, 1 camera or file failure (the message says which), 2 usage/config.
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "apps/stereo_png.hpp"
#include "hal/mock/sim_clock.hpp"
#include "runtime/config_loader.hpp"
#include "runtime/linux_hal.hpp"
#include "runtime/tick_pipeline.hpp"
#include "sim/simulated_robot.hpp"

namespace {

class NullSink final : public rtfuse::MessageSink {
 public:
  bool publish(const char*, const std::uint8_t*, int, rtfuse::TimeNs) override { return true; }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rtfuse-camera-snapshot: one rectified stereo pair of the configured camera as a PNG with epipolar guide lines"};
  std::string config_path, out_path = "stereo_pair.png", scenario_path;
  int guide_px = 24;
  int skip = 5;
  double at_s = 5.0;
  app.add_option("-c,--config", config_path, "robot config (TOML) with a [camera]")->required();
  app.add_option("-o,--out", out_path, "PNG to write (default stereo_pair.png)");
  app.add_option("-g,--guide", guide_px, "a guide line every N rows (0: none; default 24)");
  app.add_option("-n,--skip", skip, "frames to let pass first, while exposure settles (default 5)");
  app.add_option("-s,--scenario", scenario_path, "simulated robot: drive scenario (default: the config's)");
  app.add_option("-t,--time", at_s, "simulated robot: seconds into the drive (default 5)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  const rtfuse::ConfigLoadResult loaded = rtfuse::load_config_file(config_path);
  if (!loaded.config) {
    for (const auto& e : loaded.errors) std::fprintf(stderr, "%s\n", e.to_string().c_str());
    return 2;
  }
  const rtfuse::RuntimeConfig& cfg = *loaded.config;
  if (!cfg.hardware.camera.enabled) {
    std::fprintf(stderr, "rtfuse-camera-snapshot: %s has no [camera]\n", config_path.c_str());
    return 2;
  }
  std::string error;
  rtfuse::TimeNs t0 = rtfuse::monotonic_now_ns();
  std::unique_ptr<rtfuse::hal::mock::SimClock> sim_clock;
  std::unique_ptr<rtfuse::sim::SimulatedRobot> robot;
  std::unique_ptr<rtfuse::LinuxHal> linux_hal;
  rtfuse::HalBuses buses;
  if (cfg.hardware.backend == rtfuse::HalBackend::kSim) {
    t0 = 1'000'000'000;
    sim_clock = std::make_unique<rtfuse::hal::mock::SimClock>(t0);
    robot = rtfuse::sim::SimulatedRobot::create(cfg, scenario_path, *sim_clock, t0, &error);
    if (!robot) {
      std::fprintf(stderr, "rtfuse-camera-snapshot: %s\n", error.c_str());
      return 1;
    }
    buses = robot->buses();
  } else {
    linux_hal = rtfuse::LinuxHal::open(cfg, &error);
    if (!linux_hal) {
      std::fprintf(stderr, "rtfuse-camera-snapshot: %s\n", error.c_str());
      return 1;
    }
    buses = linux_hal->buses();
  }
  NullSink sink;
  rtfuse::PipelineOptions options;
  options.sink = &sink;
  auto pipeline = rtfuse::TickPipeline::create(cfg, buses, options, &error);
  if (!pipeline || !pipeline->start(t0, &error)) {
    std::fprintf(stderr, "rtfuse-camera-snapshot: %s\n", error.c_str());
    return 1;
  }
  rtfuse::CameraDevice& camera = *pipeline->hardware()->camera();
  // The simulated drive's pose at --time: the camera's frames follow it.
  if (sim_clock) sim_clock->set(t0 + rtfuse::sec_to_ns(at_s));
  const std::int64_t want = (skip < 0 ? 0 : skip) + 1;
  // Ten seconds of steps at most: a camera that gives nothing is reported.
  for (int k = 0; k < 200 && camera.samples() < want; ++k) camera.step(rtfuse::kDeviceStepTimeoutNs);
  rtfuse::FramePool::Handle h = camera.pool().take_latest();
  if (!h.valid()) {
    const auto& st = camera.stats();
    std::fprintf(stderr, "rtfuse-camera-snapshot: no frame from the camera (%lld dequeued, %lld timeouts, %lld rejected): %s\n",
                 static_cast<long long>(st.frames), static_cast<long long>(st.stream.timeouts),
                 static_cast<long long>(st.rejected_size + st.rejected_corrupted), st.last_error);
    return 1;
  }
  const rtfuse::FramePool::Frame f = camera.pool().frame(h);
  const bool ok = rtfuse::apps::write_stereo_png(out_path, f.left, f.right, f.width, f.height, f.stride, guide_px, &error);
  camera.pool().release(h);
  if (!ok) {
    std::fprintf(stderr, "rtfuse-camera-snapshot: %s\n", error.c_str());
    return 1;
  }
  const rtfuse::drivers::StereoRectification& r = camera.rectified();
  std::printf("{\"out\": \"%s\", \"width\": %d, \"height\": %d, \"sequence\": %u, \"fx\": %.3f, \"cx\": %.3f, "
              "\"cy\": %.3f, \"baseline_m\": %.5f}\n",
              out_path.c_str(), f.width, f.height, f.sequence, r.fx, r.cx, r.cy, r.baseline_m);
  return 0;
}
