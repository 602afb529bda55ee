#pragma once
// One VideoStream call a driver made and what it got back (VideoEvent), and
// the SPSC ring that carries these records, with the frame bytes, from the
// camera thread to the recorder (VideoRecordRing).
//
// Frames do not fit the 512-byte BusEvent rings: a VGA side-by-side YUYV
// frame is 1344*376*2 = 1 MB. The ring keeps two FIFOs that advance in the
// same order: small event heads (every call: dequeue, release, start, stop,
// reopen) and large frame slots, sized once at construction (one per dequeue
// that returned a frame). A release costs a 100-byte head, not a 1 MB slot.
// Every call of a camera goes through this one ring, so the log keeps their
// order (a second ring for the small calls would lose it).
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <type_traits>

#include "core/time.hpp"
#include "hal/status.hpp"
#include "hal/video_stream.hpp"

namespace rtfuse::hal {

enum class VideoCallKind : std::uint8_t { kNone, kDequeue, kRelease, kStart, kStop, kReopen };

inline const char* to_string(VideoCallKind k) noexcept {
  switch (k) {
    case VideoCallKind::kNone: return "none";
    case VideoCallKind::kDequeue: return "dequeue";
    case VideoCallKind::kRelease: return "release";
    case VideoCallKind::kStart: return "start";
    case VideoCallKind::kStop: return "stop";
    case VideoCallKind::kReopen: return "reopen";
  }
  return "unknown";
}

// Trivially copyable, no padding (equal events are equal bytes). Fields a
// kind does not use are zero, except index (-1 when no buffer is involved).
struct VideoEvent {
  TimeNs time_ns = 0;     // clock time of the call; 0 when the decorator has no clock
  TimeNs timeout_ns = 0;  // dequeue: the timeout argument
  TimeNs stamp = 0;       // dequeue with a frame: the capture stamp
  // Frames the stream had lent before this call (a dequeue that returned a
  // frame: that frame's number, from 0). Tells which frames a hole lost.
  std::int64_t frames_before = 0;
  std::uint32_t sequence = 0;    // dequeue with a frame: the device's counter
  std::uint32_t bytes_used = 0;  // dequeue with a frame: as the device reported it
  std::uint32_t length = 0;      // dequeue with a frame: the buffer's capacity
  std::uint32_t data_size = 0;   // frame bytes carried (min of bytes_used, length, the slot)
  // Calls of the same decorator that found the ring full just before this one.
  std::uint32_t lost_before = 0;
  std::int32_t index = -1;  // dequeue with a frame: buffer lent; release: the argument
  // format() after the call: the replay's format() gives it back, and the
  // driver reads it to lay out the frame. 32 bytes against a 1 MB frame.
  std::uint32_t pixel_format = 0;
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::int32_t bytes_per_line = 0;
  std::uint32_t image_size = 0;
  std::uint32_t fps_numerator = 0;
  std::uint32_t fps_denominator = 0;
  std::int32_t buffers = 0;
  VideoCallKind kind = VideoCallKind::kNone;
  std::uint8_t device = 0;  // index in the recording's device table
  HalStatus status = HalStatus::kOk;
  std::uint8_t corrupted = 0;  // dequeue with a frame: the device's error flag
  std::uint8_t reserved[4] = {};

  bool has_frame() const noexcept { return kind == VideoCallKind::kDequeue && status == HalStatus::kOk; }
  void set_format(const VideoFormat& f) noexcept {
    pixel_format = f.pixel_format;
    width = f.width;
    height = f.height;
    bytes_per_line = f.bytes_per_line;
    image_size = f.image_size;
    fps_numerator = f.fps_numerator;
    fps_denominator = f.fps_denominator;
    buffers = f.buffers;
  }
  VideoFormat format() const noexcept {
    VideoFormat f;
    f.pixel_format = pixel_format;
    f.width = width;
    f.height = height;
    f.bytes_per_line = bytes_per_line;
    f.image_size = image_size;
    f.fps_numerator = fps_numerator;
    f.fps_denominator = fps_denominator;
    f.buffers = buffers;
    return f;
  }
};

static_assert(std::is_trivially_copyable_v<VideoEvent>, "VideoEvent travels through the ring by copy");
static_assert(std::has_unique_object_representations_v<VideoEvent>, "no padding: equal events are equal bytes");

inline bool operator==(const VideoEvent& a, const VideoEvent& b) noexcept {
  return std::memcmp(&a, &b, sizeof(VideoEvent)) == 0;
}
inline bool operator!=(const VideoEvent& a, const VideoEvent& b) noexcept { return !(a == b); }

// Single producer (the camera thread), single consumer (the recorder's
// writer). All memory is allocated by the constructor; push and pop never
// allocate, lock or block. The producer reserves, copies the frame straight
// into its slot (no staging copy), then commits.
class VideoRecordRing {
 public:
  // events: heads (calls) it holds; frames: frame slots of slot_bytes each.
  VideoRecordRing(std::size_t slot_bytes, std::size_t frames, std::size_t events)
      : slot_bytes_(slot_bytes),
        frame_count_((frames > 0 ? frames : 1) + 1),
        event_count_((events > 0 ? events : 1) + 1),
        frames_(new std::uint8_t[slot_bytes_ * frame_count_]),
        events_(new VideoEvent[event_count_]) {}
  VideoRecordRing(const VideoRecordRing&) = delete;
  VideoRecordRing& operator=(const VideoRecordRing&) = delete;

  std::size_t slot_bytes() const noexcept { return slot_bytes_; }
  std::size_t frame_capacity() const noexcept { return frame_count_ - 1; }
  std::size_t event_capacity() const noexcept { return event_count_ - 1; }

  // --- producer -----------------------------------------------------------
  // Room for one more call (and its frame when with_frame): the slot to copy
  // the frame into (non-null) when with_frame, else a non-null dummy; null
  // when the ring is full. Nothing is visible to the consumer until commit().
  std::uint8_t* reserve(bool with_frame) noexcept {
    const std::size_t et = event_tail_.load(std::memory_order_relaxed);
    if (advance(et, event_count_) == event_head_.load(std::memory_order_acquire)) return nullptr;
    if (!with_frame) return events_[et].reserved;  // any non-null pointer
    const std::size_t ft = frame_tail_.load(std::memory_order_relaxed);
    if (advance(ft, frame_count_) == frame_head_.load(std::memory_order_acquire)) return nullptr;
    return frames_.get() + ft * slot_bytes_;
  }
  // After a successful reserve(ev.has_frame()); the slot's bytes were written.
  void commit(const VideoEvent& ev) noexcept {
    const std::size_t et = event_tail_.load(std::memory_order_relaxed);
    events_[et] = ev;
    if (ev.has_frame()) {
      frame_tail_.store(advance(frame_tail_.load(std::memory_order_relaxed), frame_count_),
                        std::memory_order_release);
    }
    // Release: the head, and the frame bytes written before it, are visible
    // to the consumer that sees the new tail.
    event_tail_.store(advance(et, event_count_), std::memory_order_release);
  }

  // --- consumer -----------------------------------------------------------
  // The oldest call, or null when empty; *frame: its bytes (null if none).
  // Valid until pop().
  const VideoEvent* peek(const std::uint8_t** frame) const noexcept {
    const std::size_t eh = event_head_.load(std::memory_order_relaxed);
    if (eh == event_tail_.load(std::memory_order_acquire)) return nullptr;
    const VideoEvent* ev = &events_[eh];
    if (frame != nullptr) {
      *frame = ev->has_frame() ? frames_.get() + frame_head_.load(std::memory_order_relaxed) * slot_bytes_ : nullptr;
    }
    return ev;
  }
  void pop() noexcept {
    const std::size_t eh = event_head_.load(std::memory_order_relaxed);
    if (events_[eh].has_frame()) {
      frame_head_.store(advance(frame_head_.load(std::memory_order_relaxed), frame_count_),
                        std::memory_order_release);
    }
    event_head_.store(advance(eh, event_count_), std::memory_order_release);
  }

  // Snapshots, safe from either side.
  std::size_t events() const noexcept {
    return distance(event_head_.load(std::memory_order_acquire), event_tail_.load(std::memory_order_acquire),
                    event_count_);
  }
  std::size_t frames() const noexcept {
    return distance(frame_head_.load(std::memory_order_acquire), frame_tail_.load(std::memory_order_acquire),
                    frame_count_);
  }

 private:
  static std::size_t advance(std::size_t i, std::size_t n) noexcept { return i + 1 == n ? 0 : i + 1; }
  static std::size_t distance(std::size_t head, std::size_t tail, std::size_t n) noexcept {
    return tail >= head ? tail - head : tail + n - head;
  }
  static constexpr std::size_t kCacheLine = 64;

  const std::size_t slot_bytes_;
  const std::size_t frame_count_;
  const std::size_t event_count_;
  const std::unique_ptr<std::uint8_t[]> frames_;
  const std::unique_ptr<VideoEvent[]> events_;
  // Producer-owned line.
  alignas(kCacheLine) std::atomic<std::size_t> event_tail_{0};
  std::atomic<std::size_t> frame_tail_{0};
  // Consumer-owned line.
  alignas(kCacheLine) std::atomic<std::size_t> event_head_{0};
  std::atomic<std::size_t> frame_head_{0};
};

}  // namespace rtfuse::hal
