#pragma once
// The navigator's messages: goals (pose_stamped_t on rtfuse/goal) and stops
// (nav_stop_t on rtfuse/stop) in, paths (path_t on rtfuse/path) out.
// Decoding runs wherever the bytes arrive (the LCM thread, a replay, the
// simulator's goal sequence) and checks the wire before lcm-gen's decoder
// sees it, as the sensors' decoder does; encoding writes into a buffer
// sized at construction. Neither allocates after construction (frame ids
// and reasons beyond kStringReserve characters excepted).
#include <cstdint>
#include <memory>
#include <string>

#include "core/time.hpp"
#include "transport/camera_messages.hpp"
#include "transport/sample_decoder.hpp"

namespace rtfuse::transport {

struct NavGoal {
  TimeNs stamp = 0;
  double x = 0.0, y = 0.0;
  // A goal whose orientation is all zero asks for a position only.
  bool has_yaw = false;
  double yaw = 0.0;
};

struct NavStop {
  TimeNs stamp = 0;
  bool stop = false;
};

class NavInputDecoder {
 public:
  static constexpr std::size_t kStringReserve = 256;
  NavInputDecoder();
  ~NavInputDecoder();

  // *out is written on kOk only. The goal's frame id (kept until the next
  // call) is the caller's to check: kUnknownFrame here means an empty one.
  DecodeResult decode_goal(const void* data, int size, NavGoal* out) noexcept;
  const std::string& goal_frame() const noexcept;
  DecodeResult decode_stop(const void* data, int size, NavStop* out) noexcept;
  // The last stop's reason (kept until the next call).
  const std::string& stop_reason() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct PathPoint2 {
  double x = 0.0, y = 0.0;
};

class PathEncoder {
 public:
  // For paths of at most max_points points in frame_id. nullptr and *error
  // when max_points is not positive or the message could not fit in LCM's
  // largest.
  static std::unique_ptr<PathEncoder> create(int max_points, const std::string& frame_id, std::string* error);
  ~PathEncoder();
  PathEncoder(const PathEncoder&) = delete;
  PathEncoder& operator=(const PathEncoder&) = delete;

  // Orientations point along the segments (the last one along the
  // segment that arrives). More than max_points points: an empty message
  // (ok() false) and a counted failure. No allocation.
  EncodedMessage encode(const PathPoint2* points, int count, std::int32_t goal_seq, double cost,
                        TimeNs stamp) noexcept;
  std::int64_t encode_failures() const noexcept;

 private:
  struct Impl;
  explicit PathEncoder(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rtfuse::transport
