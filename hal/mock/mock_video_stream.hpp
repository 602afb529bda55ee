#pragma once
// A VideoStream without a device: frames come from a FrameGenerator at the
// times it gives, on the stream's Clock (a SimClock jumps to the next frame,
// a MonotonicClock sleeps until it). Buffers are allocated at construction
// and behave like a V4L2 queue: a captured frame lands in a free buffer and
// waits there until dequeued; when every buffer is lent or waiting, the
// frame is lost as on a real device, its sequence number consumed, so the
// consumer sees the gap. Frames are captured lazily, when dequeue() looks
// at the clock, which gives the same result as a device capturing on time.
//
// Fault injection (tests): sequence skips, unplug with refused reopens, the
// error flag, a wrong bytes_used. Not thread-safe: drive it, and inject
// faults, from the consumer's thread.
#include <cstdint>
#include <memory>

#include "hal/clock.hpp"
#include "hal/mock/frame_generator.hpp"
#include "hal/video_stream.hpp"

namespace rtfuse::hal::mock {

// Packed YUYV (2 bytes a pixel) width x height at fps frames per second.
VideoFormat yuyv_format(int width, int height, int fps, int buffers = 4) noexcept;

class MockVideoStream final : public VideoStream {
 public:
  // format is what open() would have negotiated; format.buffers buffers
  // (clamped to 1..kMaxVideoBuffers) of format.image_size bytes each.
  MockVideoStream(Clock& clock, FrameGenerator& source, const VideoFormat& format);
  MockVideoStream(const MockVideoStream&) = delete;
  MockVideoStream& operator=(const MockVideoStream&) = delete;

  const VideoFormat& format() const noexcept override { return format_; }
  // Frames captured before start() never existed, as on a device not yet streaming.
  HalStatus start() noexcept override;
  void stop() noexcept override;
  HalStatus dequeue(TimeNs timeout_ns, VideoFrame* frame) noexcept override;
  HalStatus release(int index) noexcept override;
  // Restarts streaming with the sequence from 0 (unless refused); frames
  // due while unplugged are gone.
  HalStatus reopen() noexcept override;
  const VideoStreamStats& stats() const noexcept override { return stats_; }
  const char* last_error() const noexcept override { return last_error_; }

  // --- fault injection ---
  // The next captured frame's sequence number jumps by n (n frames "dropped
  // by the device" before they reached a buffer).
  void skip_sequence(std::uint32_t n) noexcept { skip_ += n; }
  // The device goes away: dequeue/start/release give kClosed until a
  // reopen() succeeds. Counted in stats().lost.
  void unplug() noexcept;
  // The next k reopen() calls fail (the device is not back yet).
  void refuse_reopens(int k) noexcept { refuse_reopens_ = k; }
  // The next n captured frames carry the device's error flag.
  void corrupt_next(int n = 1) noexcept { corrupt_ = n; }
  // The next captured frame reports bytes instead of what the source returned.
  void set_next_bytes_used(std::uint32_t bytes) noexcept {
    bytes_override_ = bytes;
    has_bytes_override_ = true;
  }

  // --- observation ---
  bool streaming() const noexcept { return streaming_; }
  bool unplugged() const noexcept { return unplugged_; }
  int lent() const noexcept;
  // Frames lost because no buffer was free (the consumer holds or lags).
  std::int64_t overruns() const noexcept { return overruns_; }
  // The source said it has no more frames (a replay at its end).
  bool exhausted() const noexcept { return exhausted_; }

 private:
  enum class State : std::uint8_t { kQueued, kDone, kLent };
  struct Buffer {
    std::uint8_t* data = nullptr;
    State state = State::kQueued;
    TimeNs stamp = 0;
    std::uint32_t sequence = 0;
    std::uint32_t bytes_used = 0;
    bool corrupted = false;
  };
  // FIFO of buffer indices: the device fills queued buffers in the order
  // they were given back, and hands out filled ones oldest first.
  struct IndexFifo {
    int items[kMaxVideoBuffers] = {};
    int head = 0;
    int count = 0;
    void clear() noexcept { head = count = 0; }
    void push(int i) noexcept {
      items[(head + count) % kMaxVideoBuffers] = i;
      ++count;
    }
    int pop() noexcept {
      const int i = items[head];
      head = (head + 1) % kMaxVideoBuffers;
      --count;
      return i;
    }
  };

  // Captures every frame due at or before now; kIoError if the source breaks its contract.
  HalStatus capture_due(TimeNs now) noexcept;
  // Skips (without a sequence number) the frames due before now.
  void discard_before(TimeNs now) noexcept;
  void requeue_all() noexcept;
  void set_error(const char* fmt, ...) noexcept __attribute__((format(printf, 2, 3)));

  Clock& clock_;
  FrameGenerator& source_;
  VideoFormat format_;
  std::unique_ptr<std::uint8_t[]> storage_;
  Buffer buffers_[kMaxVideoBuffers];
  int nbuffers_ = 0;
  IndexFifo queued_;
  IndexFifo done_;
  bool streaming_ = false;
  bool unplugged_ = false;
  bool exhausted_ = false;
  std::uint32_t next_sequence_ = 0;
  bool have_captured_ = false;
  TimeNs last_capture_ = 0;
  SequenceTracker tracker_;
  VideoStreamStats stats_;
  std::int64_t overruns_ = 0;
  // Fault injection.
  std::uint32_t skip_ = 0;
  int refuse_reopens_ = 0;
  int corrupt_ = 0;
  std::uint32_t bytes_override_ = 0;
  bool has_bytes_override_ = false;
  char last_error_[256] = {};
};

}  // namespace rtfuse::hal::mock
