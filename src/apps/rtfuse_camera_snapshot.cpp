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
#include <ctime>
#include <memory>
#include <string>

#include "apps/command_line.hpp"
#include "apps/stereo_png.hpp"
#include "hal/mock/sim_clock.hpp"
#include "hal/replay/replay_video_stream.hpp"
#include "runtime/devices/camera/camera_calibration.hpp"
#include "runtime/devices/camera/camera_device.hpp"
#include "runtime/config/config_loader.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "runtime/replay/hal_replay.hpp"
#include "runtime/pipeline/recording_tap.hpp"
#include "transport/hal_record_codec.hpp"
#include "runtime/devices/linux_hal.hpp"
#include "runtime/pipeline/tick_pipeline.hpp"
#include "sim/sim_robot.hpp"

namespace {

class NullSink final : public rtfuse::MessageSink {
 public:
  bool publish(const char*, const std::uint8_t*, int, rtfuse::TimeNs) override { return true; }
};

// What the PNG's header says of the pair: where it comes from, and the
// stamp that is t = 0 with what starts there (null: the wall-clock time).
struct PairOrigin {
  std::string source;
  rtfuse::TimeNs t0 = 0;
  const char* t0_name = nullptr;
};

std::string pair_when(const rtfuse::FramePool::Frame& f, const PairOrigin& origin) {
  char buf[128];
  if (origin.t0_name != nullptr) {
    std::snprintf(buf, sizeof buf, "frame counter %u, t = %.3f s into %s", f.sequence,
                  static_cast<double>(f.stamp - origin.t0) * 1e-9, origin.t0_name);
  } else {
    const std::time_t now = std::time(nullptr);
    char stamp[32] = "?";
    std::tm local{};
    if (localtime_r(&now, &local) != nullptr) std::strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S", &local);
    std::snprintf(buf, sizeof buf, "frame counter %u, taken %s", f.sequence, stamp);
  }
  return buf;
}

int write_pair(rtfuse::FramePool& pool, const rtfuse::drivers::StereoRectification& r,
               const rtfuse::drivers::StereoCameraStats& st, const std::string& out_path, int guide_px,
               const PairOrigin& origin) {
  rtfuse::FramePool::Handle h = pool.take_latest();
  if (!h.valid()) {
    std::fprintf(stderr, "rtfuse-camera-snapshot: no frame from the camera (%lld dequeued, %lld timeouts, %lld rejected): %s\n",
                 static_cast<long long>(st.frames), static_cast<long long>(st.stream.timeouts),
                 static_cast<long long>(st.rejected_size + st.rejected_corrupted), st.last_error);
    return 1;
  }
  const rtfuse::FramePool::Frame f = pool.frame(h);
  std::string error;
  const rtfuse::apps::StereoPngHeader header{origin.source, pair_when(f, origin), r.fx, r.cx, r.cy, r.baseline_m};
  const bool ok =
      rtfuse::apps::write_stereo_png(out_path, f.left, f.right, f.width, f.height, f.stride, guide_px, &header, &error);
  pool.release(h);
  if (!ok) {
    std::fprintf(stderr, "rtfuse-camera-snapshot: %s\n", error.c_str());
    return 1;
  }
  std::printf("{\"out\": \"%s\", \"width\": %d, \"height\": %d, \"sequence\": %u, \"fx\": %.3f, \"cx\": %.3f, "
              "\"cy\": %.3f, \"baseline_m\": %.5f, \"header_rows\": %d}\n",
              out_path.c_str(), f.width, f.height, f.sequence, r.fx, r.cx, r.cy, r.baseline_m,
              rtfuse::apps::stereo_png_header_rows(f.width));
  return 0;
}

// The pair after `skip` others from the recorded frames of a camera,
// through the same driver: what rtfused rectified while it recorded.
int from_recording(const std::string& log_path, const std::string& out_path, int guide_px, int skip) {
  rtfuse::transport::EventLogReader in;
  rtfuse::HalRecording rec;
  std::string error;
  rtfuse::HalRecordingOptions options;
  options.allow_truncated = true;  // a killed recorder's frames are still frames
  if (!in.open(log_path, &error) || !rtfuse::load_hal_recording(in, options, &rec, &error)) {
    std::fprintf(stderr, "rtfuse-camera-snapshot: %s\n", error.c_str());
    return 1;
  }
  const rtfuse::ConfigLoadResult loaded = rtfuse::load_config_string(rec.info.config_text, rec.info.config_path);
  if (!loaded.config) {
    for (const auto& e : loaded.errors) std::fprintf(stderr, "%s\n", e.to_string().c_str());
    return 2;
  }
  rtfuse::CameraSection camera = loaded.config->hardware.camera;
  for (const rtfuse::transport::RecordedFile& f : rec.info.files) {
    if (f.key == rtfuse::kCameraCalibrationKey) camera.calibration_text = f.text;
  }
  int stream = -1, device = -1;
  for (std::size_t d = 0; d < rec.info.devices.size(); ++d) {
    if (rec.info.devices[d].kind != rtfuse::transport::DeviceKind::kVideo) continue;
    stream = rec.info.devices[d].stream;
    device = static_cast<int>(d);
    break;
  }
  if (!camera.enabled || stream < 0) {
    std::fprintf(stderr, "rtfuse-camera-snapshot: %s holds no camera frames (its config has %s[camera])\n",
                 log_path.c_str(), camera.enabled ? "a " : "no ");
    return 2;
  }
  rtfuse::hal::replay::ReplayVideoLog& log = *rec.videos[static_cast<std::size_t>(stream)];
  rtfuse::hal::replay::ReplayVideoStream video(log, static_cast<std::uint8_t>(device));
  rtfuse::hal::mock::SimClock clock(rec.info.start_ns);
  rtfuse::drivers::StereoCameraConfig dcfg;
  if (!rtfuse::camera_driver_config(camera, &dcfg, &error)) {
    std::fprintf(stderr, "rtfuse-camera-snapshot: %s\n", error.c_str());
    return 1;
  }
  rtfuse::FramePool pool(camera.pool_frames, dcfg.calibration.width, dcfg.calibration.height);
  auto driver = rtfuse::drivers::StereoCamera::create(dcfg, video, clock, pool, &error);
  if (!driver) {
    std::fprintf(stderr, "rtfuse-camera-snapshot: %s\n", error.c_str());
    return 1;
  }
  const std::int64_t want = (skip < 0 ? 0 : skip) + 1;
  rtfuse::drivers::StereoFrameResult r;
  for (std::size_t k = 0; k < 2 * log.size() + 16 && !log.at_end() && !log.diverged() &&
                          driver->stats().rectified < want;
       ++k) {
    driver->step(rtfuse::kDeviceStepTimeoutNs, &r);
    // The newest pair is the one to keep; older ones go back to the pool.
    if (driver->stats().rectified < want) {
      rtfuse::FramePool::Handle h = pool.take_latest();
      if (h.valid()) pool.release(h);
    }
  }
  return write_pair(pool, driver->rectified(), driver->stats(), out_path, guide_px,
                    PairOrigin{"recording " + log_path, rec.info.start_ns, "the recording"});
}

}  // namespace

int main(int argc, char** argv) {
  rtfuse::apps::CommandLine cli{"rtfuse-camera-snapshot: one rectified stereo pair of the configured camera as a PNG with epipolar guide lines"};
  std::string config_path, out_path = "stereo_pair.png", scenario_path;
  int guide_px = 24;
  int skip = 5;
  double at_s = 5.0;
  std::string recording_path;
  auto config_opt = cli.option("-c,--config", &config_path, "robot config (TOML) with a [camera]");
  auto recording_opt =
      cli.option("-r,--recording", &recording_path, "an rtfused --record log with camera frames instead of a camera");
  config_opt.excludes(recording_opt);
  cli.option("-o,--out", &out_path, "PNG to write (default stereo_pair.png)");
  cli.option("-g,--guide", &guide_px, "a guide line every N rows (0: none; default 24)");
  cli.option("-n,--skip", &skip, "frames to let pass first, while exposure settles (default 5; of a recording: its first N)");
  cli.option("-s,--scenario", &scenario_path, "simulated robot: drive scenario (default: the config's)");
  cli.option("-t,--time", &at_s, "simulated robot: seconds into the drive (default 5)");
  if (const auto exit = cli.parse(argc, argv)) return *exit;
  if (!recording_path.empty()) return from_recording(recording_path, out_path, guide_px, skip);
  if (config_path.empty()) {
    std::fprintf(stderr, "rtfuse-camera-snapshot: give the camera's config (--config) or a recording (--recording)\n");
    return 2;
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
  std::unique_ptr<rtfuse::sim::SimRobot> robot;
  std::unique_ptr<rtfuse::LinuxHal> linux_hal;
  rtfuse::HalBuses buses;
  if (cfg.hardware.backend == rtfuse::HalBackend::kSim) {
    t0 = 1'000'000'000;
    sim_clock = std::make_unique<rtfuse::hal::mock::SimClock>(t0);
    robot = rtfuse::sim::SimRobot::create(cfg, scenario_path, *sim_clock, t0, &error);
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
  rtfuse::CameraDevice& camera = *pipeline->hardware()->find<rtfuse::CameraDevice>("camera");
  // The simulated drive's pose at --time: the camera's frames follow it.
  if (sim_clock) sim_clock->set(t0 + rtfuse::sec_to_ns(at_s));
  const std::int64_t want = (skip < 0 ? 0 : skip) + 1;
  // Ten seconds of steps at most: a camera that gives nothing is reported.
  for (int k = 0; k < 200 && camera.frames() < want; ++k) camera.step(rtfuse::kDeviceStepTimeoutNs);
  const std::string device(cfg.hardware.camera.device.view());
  const PairOrigin origin = sim_clock ? PairOrigin{"simulated camera of " + config_path, t0, "the simulated drive"}
                                      : PairOrigin{"camera " + device + " of " + config_path, 0, nullptr};
  return write_pair(camera.pool(), camera.rectified(), camera.stats(), out_path, guide_px, origin);
}
