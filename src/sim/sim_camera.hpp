#pragma once
// The simulated robot's stereo camera: a mock video stream whose frames are
// rendered, when the camera thread dequeues them, from the ground-truth pose
// at their capture time through the configured mount (base_link -> the
// camera's optical frame) and calibration, distortion included. The same
// camera driver runs on it as on a real camera.
#include <cstdint>
#include <memory>
#include <vector>
#include <string>

#include "drivers/camera/stereo_calibration.hpp"
#include "geometry/rigid_transform.hpp"
#include "hal/clock.hpp"
#include "hal/mock/frame_generator.hpp"
#include "hal/mock/mock_video_stream.hpp"
#include "runtime/config/config.hpp"
#include "sim/camera_world.hpp"
#include "sim/sim_device.hpp"
#include "sim/stereo_renderer.hpp"
#include "sim/truth_source.hpp"

namespace rtfuse::sim {

// The camera's counterpart (sim_device.hpp): the calibration file's camera,
// rendering the scenario's world from the robot's pose through its mount.
std::unique_ptr<SimDevice> make_sim_camera(const SimDeviceContext& ctx, std::string* error);

class SimCamera final : public hal::mock::FrameGenerator, public SimDevice {
 public:
  // The camera section's calibration file and mode, the mount from the
  // config's static transforms, the scenario's obstacles in its world;
  // `truth` is read on the camera's thread. Null with *error when they do
  // not fit.
  static std::unique_ptr<SimCamera> create(const RuntimeConfig& cfg, TruthSource& truth, hal::Clock& clock,
                                           TimeNs t0, std::uint64_t seed, const std::vector<ObstacleBox>& obstacles,
                                           std::string* error);

  hal::VideoStream& stream() { return *stream_; }
  // Fault injection (unplug, refused reopens): drive it from the camera's thread.
  hal::mock::MockVideoStream& mock_stream() { return *stream_; }
  // The sensor stops delivering until `until` (a USB stall, a hung ISP): the
  // frames due meanwhile are never captured, and the next one is the first
  // of the camera's cadence after `until`. A time already past does nothing.
  void stall_until(TimeNs until) noexcept;
  // Capture time of the next frame: what the lockstep drive steps the camera thread up to.
  TimeNs next_frame_time() noexcept override { return next_; }

  // SimDevice: its video stream and the robot's clock.
  void provide(DeviceBuses& out, hal::Clock& clock) noexcept override;
  TimeNs next_event_time() noexcept override { return next_; }
  std::uint32_t fill(TimeNs stamp, std::uint32_t sequence, std::uint8_t* data, std::uint32_t capacity) noexcept override;

 private:
  SimCamera() = default;

  TruthSource* truth_ = nullptr;
  TimeNs t0_ = 0;
  TimeNs period_ = 0;
  TimeNs next_ = 0;
  geometry::RigidTransform base_T_camera_;
  hal::VideoFormat format_;
  std::unique_ptr<CameraWorld> world_;
  std::unique_ptr<StereoRenderer> renderer_;
  std::unique_ptr<hal::mock::MockVideoStream> stream_;
};

}  // namespace rtfuse::sim
