#pragma once
// A VideoStream that forwards every call to the real one and records the call
// and its result (for a dequeue that returned a frame: the frame's bytes) into
// a VideoRecordRing. Records one VideoEvent per call, on the camera thread.
//
// Never blocks, locks or allocates after construction: when the ring is full
// the record is dropped and counted, and the next record that gets through
// says how many went missing (lost_before), as the bus rings do. The camera
// thread is never held up by the disk; a slow disk costs frames in the
// recording, not in the live run.
//
// The frame copy happens here, on the camera thread, straight into the
// ring's slot: a memcpy of ~1 MB (VGA side-by-side YUYV), ~0.1 ms at the
// ~10 GB/s a board's memory copies at. It must: the buffer goes back to the
// device at release(), and the writer may be seconds behind.
//
// One instance per camera, used by one thread (the ring's producer).
#include <atomic>
#include <cstdint>

#include "hal/clock.hpp"
#include "hal/video_event.hpp"
#include "hal/video_stream.hpp"

namespace rtfuse::hal {

class RecordingVideoStream final : public VideoStream {
 public:
  // ring: its slots should hold inner.format().image_size bytes (the
  // recorder sizes them from the negotiated format); a frame larger than a
  // slot is recorded clipped to it (data_size says so). clock stamps the
  // records (time_ns), may be null.
  RecordingVideoStream(VideoStream& inner, VideoRecordRing& ring, std::uint8_t device,
                       const Clock* clock = nullptr) noexcept
      : inner_(inner), ring_(ring), device_(device), clock_(clock) {}

  const VideoFormat& format() const noexcept override { return inner_.format(); }
  HalStatus start() noexcept override;
  void stop() noexcept override;
  HalStatus dequeue(TimeNs timeout_ns, VideoFrame* frame) noexcept override;
  HalStatus release(int index) noexcept override;
  HalStatus reopen() noexcept override;
  const VideoStreamStats& stats() const noexcept override { return inner_.stats(); }
  const char* last_error() const noexcept override { return inner_.last_error(); }

  std::uint8_t device() const noexcept { return device_; }
  // Readable from any thread: calls and, among them, frames lost to a full ring.
  std::int64_t overflows() const noexcept { return overflows_.load(std::memory_order_relaxed); }
  std::int64_t frames_lost() const noexcept { return frames_lost_.load(std::memory_order_relaxed); }
  std::int64_t frames_recorded() const noexcept { return frames_recorded_.load(std::memory_order_relaxed); }

 private:
  VideoEvent begin(VideoCallKind kind) const noexcept;
  // Pushes ev (and, for a frame, data's ev.data_size bytes) or counts the loss.
  void push(VideoEvent& ev, const std::uint8_t* data) noexcept;

  VideoStream& inner_;
  VideoRecordRing& ring_;
  std::uint8_t device_;
  const Clock* clock_;
  std::int64_t frames_ = 0;  // frames the inner stream lent so far
  std::uint32_t pending_lost_ = 0;
  std::atomic<std::int64_t> overflows_{0};
  std::atomic<std::int64_t> frames_lost_{0};
  std::atomic<std::int64_t> frames_recorded_{0};
  static_assert(std::atomic<std::int64_t>::is_always_lock_free, "RT path needs lock-free atomics");
};

}  // namespace rtfuse::hal
