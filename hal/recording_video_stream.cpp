#include "hal/recording_video_stream.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

namespace rtfuse::hal {

VideoEvent RecordingVideoStream::begin(VideoCallKind kind) const noexcept {
  VideoEvent ev;
  ev.kind = kind;
  ev.device = device_;
  ev.time_ns = clock_ != nullptr ? clock_->now() : 0;
  ev.frames_before = frames_;
  return ev;
}

void RecordingVideoStream::push(VideoEvent& ev, const std::uint8_t* data) noexcept {
  ev.set_format(inner_.format());
  ev.lost_before = pending_lost_;
  const bool with_frame = ev.has_frame();
  std::uint8_t* slot = ring_.reserve(with_frame);
  if (slot == nullptr) {
    if (pending_lost_ < std::numeric_limits<std::uint32_t>::max()) ++pending_lost_;
    overflows_.fetch_add(1, std::memory_order_relaxed);
    if (with_frame) frames_lost_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (with_frame && ev.data_size > 0 && data != nullptr) std::memcpy(slot, data, ev.data_size);
  ring_.commit(ev);
  pending_lost_ = 0;
  if (with_frame) frames_recorded_.fetch_add(1, std::memory_order_relaxed);
}

HalStatus RecordingVideoStream::start() noexcept {
  VideoEvent ev = begin(VideoCallKind::kStart);
  ev.status = inner_.start();
  push(ev, nullptr);
  return ev.status;
}

void RecordingVideoStream::stop() noexcept {
  VideoEvent ev = begin(VideoCallKind::kStop);
  inner_.stop();
  push(ev, nullptr);
}

HalStatus RecordingVideoStream::dequeue(TimeNs timeout_ns, VideoFrame* frame) noexcept {
  VideoEvent ev = begin(VideoCallKind::kDequeue);
  ev.timeout_ns = timeout_ns;
  ev.status = inner_.dequeue(timeout_ns, frame);
  if (ev.status == HalStatus::kOk) {
    ++frames_;
    if (frame != nullptr) {
      ev.index = frame->index;
      ev.stamp = frame->stamp;
      ev.sequence = frame->sequence;
      ev.bytes_used = frame->bytes_used;
      ev.length = frame->length;
      ev.corrupted = frame->corrupted ? 1 : 0;
      // The whole buffer as used, byte for byte, YUYV chroma included: the
      // replay must hand the driver exactly what it read, and the HAL does
      // not know which bytes a driver looks at (luma only would halve the
      // rate, ~15 MB/s at VGA 30 fps, but a driver or a later consumer that
      // reads chroma would silently replay other pixels, and the rectified
      // pairs would differ). bytes_used beyond the buffer is not data.
      const std::size_t used = std::min<std::size_t>(frame->bytes_used, frame->length);
      ev.data_size = frame->data == nullptr ? 0u : static_cast<std::uint32_t>(std::min(used, ring_.slot_bytes()));
    }
  }
  push(ev, frame != nullptr ? frame->data : nullptr);
  return ev.status;
}

HalStatus RecordingVideoStream::release(int index) noexcept {
  VideoEvent ev = begin(VideoCallKind::kRelease);
  ev.index = index;
  ev.status = inner_.release(index);
  push(ev, nullptr);
  return ev.status;
}

HalStatus RecordingVideoStream::reopen() noexcept {
  VideoEvent ev = begin(VideoCallKind::kReopen);
  ev.status = inner_.reopen();
  push(ev, nullptr);
  return ev.status;
}

}  // namespace rtfuse::hal
