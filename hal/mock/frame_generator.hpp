#pragma once
// Where a MockVideoStream's frames come from: a test's pattern, the
// simulator's camera renderer, a replayed recording. The stream decides when
// a frame is captured (its clock has reached next_frame_time()) and into
// which buffer; the source only says when and paints.
#include <cstdint>

#include "core/time.hpp"

namespace rtfuse::hal::mock {

class FrameGenerator {
 public:
  virtual ~FrameGenerator() = default;
  // Capture time of the next frame (CLOCK_MONOTONIC ns of the stream's
  // clock); a value < 0 means no more frames. The same value until fill()
  // takes that frame; strictly increasing from one frame to the next.
  virtual TimeNs next_frame_time() noexcept = 0;
  // Takes the frame captured at stamp: fills data (capacity bytes) and
  // returns bytes_used (a source may return a wrong size to simulate a bad
  // frame). data == nullptr with capacity 0: the frame is lost because every
  // buffer is taken (as a device drops it); skip it without painting.
  // Called on the consumer's dequeue path: must not allocate or block.
  virtual std::uint32_t fill(TimeNs stamp, std::uint32_t sequence, std::uint8_t* data,
                             std::uint32_t capacity) noexcept = 0;
};

}  // namespace rtfuse::hal::mock
