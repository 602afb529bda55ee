#pragma once
// A stereo camera as the robot's camera thread runs it, for the benchmarks:
// the camera driver (dequeue, checks, split + rectify into the frame pool)
// on a mock stream that delivers a side-by-side VGA YUYV frame every 1/30 s
// of CLOCK_MONOTONIC. The frame is rendered once by the simulator's renderer
// and copied into the buffer at each capture time, so what is measured is
// the camera thread's work on a robot, not the simulator's rendering.
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "core/frame_pool.hpp"
#include "drivers/camera/camera_modes.hpp"
#include "drivers/camera/stereo_camera.hpp"
#include "drivers/camera/zed_calibration.hpp"
#include "hal/linux/monotonic_clock.hpp"
#include "hal/mock/frame_generator.hpp"
#include "hal/mock/mock_video_stream.hpp"
#include "sim/camera_world.hpp"
#include "sim/stereo_renderer.hpp"

namespace rtfuse::bench {

class LiveCameraRig final : public hal::mock::FrameGenerator {
 public:
  // Null with *error when the calibration cannot be read or the driver refuses.
  // period_ns: time between captures (33.3 ms = 30 fps; shorter makes a
  // busier camera thread).
  static std::unique_ptr<LiveCameraRig> create(const std::string& calibration_path, std::string* error,
                                               TimeNs period_ns = kPeriodNs) {
    std::unique_ptr<LiveCameraRig> r(new LiveCameraRig());
    r->period_ = period_ns;
    drivers::ZedCalibration cal;
    if (!drivers::load_zed_calibration(calibration_path, drivers::ZedResolution::kVGA, 0, &cal, error)) return nullptr;
    r->format_ = hal::mock::yuyv_format(2 * cal.stereo.width, cal.stereo.height, 30, 4);
    r->frame_.assign(r->format_.image_size, 0);
    sim::CameraWorld world;
    sim::StereoRenderer renderer(cal.stereo, world);
    geometry::RigidTransform world_T_left;
    // Looking along +x from 0.35 m up: the optical frame's z is the world's x.
    world_T_left.translation = Eigen::Vector3d(0.0, 0.0, 0.35);
    Eigen::Matrix3d r_opt;
    r_opt << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    world_T_left.rotation = Eigen::Quaterniond(r_opt);
    renderer.render(world_T_left, 0, 0, r->frame_.data(), r->format_.bytes_per_line);
    r->next_ = r->clock_.now() + r->period_;
    r->stream_ = std::make_unique<hal::mock::MockVideoStream>(r->clock_, *r, r->format_);
    r->pool_ = std::make_unique<FramePool>(4, cal.stereo.width, cal.stereo.height);
    drivers::StereoCameraConfig config;
    config.resolution = "VGA";
    config.fps = 30;
    config.calibration = cal.stereo;
    r->camera_ = drivers::StereoCamera::create(config, *r->stream_, r->clock_, *r->pool_, error);
    if (!r->camera_) return nullptr;
    return r;
  }

  TimeNs next_frame_time() noexcept override { return next_; }
  std::uint32_t fill(TimeNs stamp, std::uint32_t, std::uint8_t* data, std::uint32_t capacity) noexcept override {
    next_ = stamp + period_;
    if (data == nullptr || capacity < frame_.size()) return 0;
    std::memcpy(data, frame_.data(), frame_.size());
    return static_cast<std::uint32_t>(frame_.size());
  }

  drivers::StereoCamera& camera() { return *camera_; }
  FramePool& pool() { return *pool_; }

  static constexpr TimeNs kPeriodNs = 33'333'333;

 private:
  LiveCameraRig() = default;
  hal::MonotonicClock clock_;
  hal::VideoFormat format_;
  std::vector<std::uint8_t> frame_;
  TimeNs next_ = 0;
  TimeNs period_ = kPeriodNs;
  std::unique_ptr<hal::mock::MockVideoStream> stream_;
  std::unique_ptr<FramePool> pool_;
  std::unique_ptr<drivers::StereoCamera> camera_;
};

}  // namespace rtfuse::bench
