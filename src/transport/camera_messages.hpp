#pragma once
// LCM messages of the stereo camera, as ROS drivers publish them:
// camera_info_t (sensor_msgs/CameraInfo) for each rectified eye and a
// downscaled image_t (sensor_msgs/Image) preview of the pair.
//
// Both encoders allocate once, in create(), and never again: lcm-gen's C++
// types hold std::string / std::vector members that allocate on assignment,
// so the strings and array sizes are set at construction and encode() only
// changes numbers (stamps, sequence numbers, pixels) before encoding into a
// buffer sized then. The runtime can encode on the publishing thread.
//
// Transport may not include drivers/, so the camera comes in as plain values
// (StereoCameraInfo), which the runtime copies from the driver's
// drivers::StereoRectification.
#include <cstdint>
#include <memory>
#include <string>

#include "core/time.hpp"

namespace rtfuse::transport {

// The rectified pair: both eyes share one undistorted pinhole; the right eye
// sits at +baseline_m along the left rectified camera's x axis.
struct StereoCameraInfo {
  int width = 0;  // one eye, pixels
  int height = 0;
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  // rectified pinhole, pixels
  double baseline_m = 0.0;                        // > 0, metres
  // header.frame_id of each eye's camera_info_t: the optical frames
  // (x right, y down, z forward).
  std::string left_frame_id;
  std::string right_frame_id;
};

// Bytes of one encoded message; valid until the encoder's next encode().
// size 0 (ok() false) when encoding failed.
struct EncodedMessage {
  const std::uint8_t* data = nullptr;
  int size = 0;
  bool ok() const noexcept { return size > 0; }
};

enum class StereoEye { kLeft, kRight };

// camera_info_t of each rectified eye in the ROS stereo convention
// (what stereo_image_proc and image_geometry expect): D five zeros with
// "plumb_bob", R identity (the images are already rectified),
// K = [fx 0 cx; 0 fy cy; 0 0 1], P = [fx 0 cx Tx; 0 fy cy 0; 0 0 1 0] with
// Tx = 0 for the left eye and Tx = -fx * baseline_m for the right one.
class CameraInfoEncoder {
 public:
  // nullptr and *error saying which value is wrong for a model with
  // non-positive sizes, focal lengths or baseline, or non-finite values.
  // Allocates (start-up).
  static std::unique_ptr<CameraInfoEncoder> create(const StereoCameraInfo& model, std::string* error);

  ~CameraInfoEncoder();
  CameraInfoEncoder(const CameraInfoEncoder&) = delete;
  CameraInfoEncoder& operator=(const CameraInfoEncoder&) = delete;

  // The eye's message with header.utime from stamp (the capture time of the
  // frame it describes) and header.seq counting this eye's encodes from 0.
  // No allocation.
  EncodedMessage encode(StereoEye eye, TimeNs stamp) noexcept;

  std::int64_t encode_failures() const noexcept;

 private:
  struct Impl;
  explicit CameraInfoEncoder(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// One 8-bit grey image, read in place (a FramePool::Frame eye).
struct GreyImage {
  const std::uint8_t* pixels = nullptr;
  int width = 0;
  int height = 0;
  int stride = 0;  // bytes from one row to the next, >= width
};

// A "mono8" image_t of both eyes side by side (left | right), each shrunk by
// an integer factor with a box filter: every preview pixel is the rounded
// mean of a factor x factor block, in integers, so the bytes are the same on
// every machine. Columns and rows beyond the last whole block are dropped
// (672 x 376 per eye, factor 2 -> 672 x 188; factor 3 -> 448 x 125).
class PreviewEncoder {
 public:
  static constexpr int kMaxFactor = 16;

  // width x height: one eye of the full-size pair; factor 1..kMaxFactor.
  // nullptr and *error for bad sizes, a factor out of range or an eye
  // smaller than one block. Allocates (start-up).
  static std::unique_ptr<PreviewEncoder> create(int width, int height, int factor, const std::string& frame_id,
                                                std::string* error);

  ~PreviewEncoder();
  PreviewEncoder(const PreviewEncoder&) = delete;
  PreviewEncoder& operator=(const PreviewEncoder&) = delete;

  // Shrinks the pair and encodes it, header.utime from stamp (capture time)
  // and header.seq counting encodes from 0. An empty result (counted in
  // encode_failures()) when an eye is null or not the size given to
  // create(). No allocation.
  EncodedMessage encode(const GreyImage& left, const GreyImage& right, TimeNs stamp) noexcept;

  int preview_width() const noexcept;  // both eyes
  int preview_height() const noexcept;
  std::int64_t encode_failures() const noexcept;

 private:
  struct Impl;
  explicit PreviewEncoder(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rtfuse::transport
