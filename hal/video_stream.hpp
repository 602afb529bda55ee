#pragma once
// A video capture stream: a fixed set of driver-owned buffers, filled by the
// device, lent to the caller one at a time and given back. No device
// knowledge (a stereo camera's side-by-side layout is drivers/camera's).
//
// The HAL copies nothing: dequeue() lends a buffer (pointer into the mmap'd
// or mock-owned memory) until release() hands it back to the device. While a
// buffer is lent the device cannot fill it, so a caller that holds buffers
// too long makes the device drop frames, which the sequence numbers show.
#include <cstdint>

#include "core/time.hpp"
#include "hal/status.hpp"

namespace rtfuse::hal {

constexpr std::uint32_t fourcc(char a, char b, char c, char d) noexcept {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(a)) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(b)) << 8) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(c)) << 16) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(d)) << 24);
}
constexpr std::uint32_t kFourccYuyv = fourcc('Y', 'U', 'Y', 'V');
constexpr std::uint32_t kFourccGrey = fourcc('G', 'R', 'E', 'Y');

// Fixed-capacity buffer count: enough to ride out a consumer waking late at
// 100 fps, few enough that a lagging consumer sees fresh frames.
constexpr int kMaxVideoBuffers = 8;

// What to ask the device for.
struct VideoRequest {
  std::uint32_t pixel_format = kFourccYuyv;
  int width = 0;   // whole frame (a side-by-side stereo frame is twice an eye)
  int height = 0;
  int fps = 0;     // frames per second; 0 leaves the device's rate
  int buffers = 4; // mmap buffers, 2..kMaxVideoBuffers
};

// What the device agreed to (read back after VIDIOC_S_FMT / VIDIOC_S_PARM).
struct VideoFormat {
  std::uint32_t pixel_format = 0;
  int width = 0;
  int height = 0;
  int bytes_per_line = 0;
  std::uint32_t image_size = 0;    // bytes of one complete frame
  std::uint32_t fps_numerator = 0;   // frame rate = numerator / denominator
  std::uint32_t fps_denominator = 1;
  int buffers = 0;                 // buffers actually allocated
};

// One filled buffer, lent to the caller until release(index).
struct VideoFrame {
  int index = -1;                    // buffer index, for release()
  const std::uint8_t* data = nullptr;
  std::uint32_t bytes_used = 0;      // as the device reports it; may differ from image_size on a bad frame
  std::uint32_t length = 0;          // capacity of the buffer
  TimeNs stamp = 0;                  // CLOCK_MONOTONIC ns of capture (the kernel's buffer timestamp)
  std::uint32_t sequence = 0;        // the device's frame counter
  bool corrupted = false;            // the device flagged the buffer (V4L2_BUF_FLAG_ERROR)
};

struct VideoStreamStats {
  std::int64_t frames = 0;          // buffers dequeued
  std::int64_t dropped = 0;         // frames missing from the sequence (sum of the gaps)
  std::int64_t sequence_gaps = 0;   // dequeues that followed a gap
  std::int64_t corrupted = 0;       // buffers flagged as errors by the device
  std::int64_t timeouts = 0;        // dequeues that waited in vain
  std::int64_t lost = 0;            // times the device went away (ENODEV, unplugged)
  std::int64_t reopens = 0;         // successful reopen() calls
  std::int64_t reopen_failures = 0; // reopen() calls that failed
};

class VideoStream {
 public:
  virtual ~VideoStream() = default;
  // The negotiated format: valid from a successful open until destruction.
  virtual const VideoFormat& format() const noexcept = 0;
  // Queues every buffer and starts streaming (VIDIOC_STREAMON).
  virtual HalStatus start() noexcept = 0;
  // Stops streaming; every buffer returns to the stream (lent ones too).
  virtual void stop() noexcept = 0;
  // Waits at most timeout_ns for a filled buffer. kOk: *frame is lent until
  // release(frame->index). kTimeout: nothing came. kClosed: the device went
  // away (unplugged); call reopen() later. kIoError: see last_error().
  virtual HalStatus dequeue(TimeNs timeout_ns, VideoFrame* frame) noexcept = 0;
  // Gives a lent buffer back to the device (VIDIOC_QBUF).
  virtual HalStatus release(int index) noexcept = 0;
  // After kClosed: opens the same device again with the same request and
  // starts streaming. kOk, or the failure (the caller backs off and retries).
  // May allocate (buffers are mapped anew); never called on a healthy stream.
  virtual HalStatus reopen() noexcept = 0;
  virtual const VideoStreamStats& stats() const noexcept = 0;
  // Text of the last failure, for diagnostics (fixed storage, never allocates).
  virtual const char* last_error() const noexcept = 0;
};

// Counts drops from the device's frame sequence numbers (a gap of n means n
// frames never reached us). Shared by every backend so they count alike.
class SequenceTracker {
 public:
  // Returns the frames missing before `sequence` (0 for the first frame and
  // for a restart after reset()).
  std::uint32_t observe(std::uint32_t sequence) noexcept {
    std::uint32_t gap = 0;
    if (have_) gap = sequence - last_ - 1u;  // unsigned: wraps like the counter
    // A sequence that went backwards (a device restart) is not a drop.
    if (have_ && sequence <= last_ && last_ - sequence < 0x80000000u) gap = 0;
    last_ = sequence;
    have_ = true;
    return gap;
  }
  void reset() noexcept { have_ = false; }

 private:
  std::uint32_t last_ = 0;
  bool have_ = false;
};

}  // namespace rtfuse::hal
