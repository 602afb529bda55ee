#pragma once
// What the daemon publishes of its camera, on the publisher thread: the
// rectified left and right camera info (<info_channel>/left and /right, as
// a ROS stereo driver's left/ and right/camera_info) and a downscaled
// side-by-side preview
// of the newest rectified pair, at camera.preview_rate, so a user sees what
// the robot sees (lcm-spy, or a viewer of image_t) without recording.
// Taken from the frame pool by handle, never copied through a ring.
#include <memory>
#include <string>

#include "core/frame_pool.hpp"
#include "drivers/camera/stereo_rectification.hpp"
#include "runtime/config/config.hpp"
#include "transport/message_sink.hpp"
#include "transport/camera_messages.hpp"

namespace rtfuse {

class CameraOutputs {
 public:
  // Null with *error when the encoders refuse the camera's geometry.
  static std::unique_ptr<CameraOutputs> create(FramePool& pool, const drivers::StereoRectification& rectified,
                                               const CameraSection& config, std::string* error);
  // Publisher thread: when due, the newest pair's preview and both camera
  // infos (stamped with its capture time). No allocation.
  void publish_due(TimeNs now, transport::MessageSink& sink) noexcept;
  std::int64_t published() const noexcept { return published_; }

 private:
  CameraOutputs(FramePool& pool, const CameraSection& config) : pool_(pool), config_(config) {}

  FramePool& pool_;
  const CameraSection& config_;
  std::unique_ptr<transport::CameraInfoEncoder> info_;
  std::unique_ptr<transport::PreviewEncoder> preview_;
  std::string left_info_channel_, right_info_channel_;  // built once: publishing allocates nothing
  TimeNs period_ = 0;
  TimeNs next_ = 0;
  std::uint64_t last_frame_ = 0;
  std::int64_t published_ = 0;
};

}  // namespace rtfuse
