#include "hal/mock/mock_video_stream.hpp"

#include <cstdarg>
#include <cstdint>
#include <cstdio>

namespace rtfuse::hal::mock {

VideoFormat yuyv_format(int width, int height, int fps, int buffers) noexcept {
  VideoFormat f;
  f.pixel_format = kFourccYuyv;
  f.width = width;
  f.height = height;
  f.bytes_per_line = 2 * width;
  f.image_size = static_cast<std::uint32_t>(2 * width * height);
  f.fps_numerator = static_cast<std::uint32_t>(fps);
  f.fps_denominator = 1;
  f.buffers = buffers;
  return f;
}

MockVideoStream::MockVideoStream(Clock& clock, FrameGenerator& source, const VideoFormat& format)
    : clock_(clock), source_(source), format_(format) {
  nbuffers_ = format.buffers < 1 ? 1 : (format.buffers > kMaxVideoBuffers ? kMaxVideoBuffers : format.buffers);
  format_.buffers = nbuffers_;
  const std::size_t size = format_.image_size;
  storage_.reset(new std::uint8_t[size * static_cast<std::size_t>(nbuffers_) + 1]());
  for (int i = 0; i < nbuffers_; ++i) buffers_[i].data = storage_.get() + size * static_cast<std::size_t>(i);
  requeue_all();
}

void MockVideoStream::set_error(const char* fmt, ...) noexcept {
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(last_error_, sizeof last_error_, fmt, ap);
  va_end(ap);
}

int MockVideoStream::lent() const noexcept {
  int n = 0;
  for (int i = 0; i < nbuffers_; ++i) n += buffers_[i].state == State::kLent ? 1 : 0;
  return n;
}

void MockVideoStream::requeue_all() noexcept {
  queued_.clear();
  done_.clear();
  for (int i = 0; i < nbuffers_; ++i) {
    buffers_[i].state = State::kQueued;
    queued_.push(i);
  }
}

void MockVideoStream::discard_before(TimeNs now) noexcept {
  for (;;) {
    const TimeNs t = source_.next_frame_time();
    if (t < 0) {
      exhausted_ = true;
      return;
    }
    if (t >= now || (have_captured_ && t <= last_capture_)) return;
    source_.fill(t, 0, nullptr, 0);
    have_captured_ = true;
    last_capture_ = t;
  }
}

HalStatus MockVideoStream::start() noexcept {
  if (unplugged_) {
    set_error("mock video: start: the device is unplugged; reopen() it");
    return HalStatus::kClosed;
  }
  if (streaming_) return HalStatus::kOk;
  requeue_all();
  discard_before(clock_.now());
  // Like VIDIOC_STREAMON: the device counts from 0 again.
  next_sequence_ = 0;
  tracker_.reset();
  streaming_ = true;
  return HalStatus::kOk;
}

void MockVideoStream::stop() noexcept {
  streaming_ = false;
  requeue_all();
}

void MockVideoStream::unplug() noexcept {
  if (!unplugged_) ++stats_.lost;
  unplugged_ = true;
  streaming_ = false;
}

HalStatus MockVideoStream::capture_due(TimeNs now) noexcept {
  for (;;) {
    const TimeNs t = source_.next_frame_time();
    if (t < 0) {
      exhausted_ = true;
      return HalStatus::kOk;
    }
    if (t > now) return HalStatus::kOk;
    if (have_captured_ && t <= last_capture_) {
      // Would loop for ever: the source did not move on after fill().
      set_error("mock video: frame source gave frame time %lld after %lld (times must increase)",
                static_cast<long long>(t), static_cast<long long>(last_capture_));
      return HalStatus::kIoError;
    }
    have_captured_ = true;
    last_capture_ = t;
    const std::uint32_t seq = next_sequence_ + skip_;
    skip_ = 0;
    next_sequence_ = seq + 1;
    if (queued_.count == 0) {
      source_.fill(t, seq, nullptr, 0);
      ++overruns_;
      continue;
    }
    const int i = queued_.pop();
    Buffer& b = buffers_[i];
    std::uint32_t bytes = source_.fill(t, seq, b.data, format_.image_size);
    b.corrupted = false;
    if (has_bytes_override_) {
      bytes = bytes_override_;
      has_bytes_override_ = false;
    }
    if (corrupt_ > 0) {
      --corrupt_;
      b.corrupted = true;
    }
    if (bytes > format_.image_size) {
      // As V4l2Stream does: never let a consumer read past the buffer.
      bytes = format_.image_size;
      b.corrupted = true;
    }
    b.bytes_used = bytes;
    b.stamp = t;
    b.sequence = seq;
    b.state = State::kDone;
    done_.push(i);
  }
}

HalStatus MockVideoStream::dequeue(TimeNs timeout_ns, VideoFrame* frame) noexcept {
  if (unplugged_) {
    set_error("mock video: dequeue: the device is unplugged; reopen() it");
    return HalStatus::kClosed;
  }
  if (!streaming_) {
    set_error("mock video: dequeue while not streaming; call start() first");
    return HalStatus::kIoError;
  }
  const TimeNs begin = clock_.now();
  const TimeNs wait = timeout_ns > 0 ? timeout_ns : 0;
  const TimeNs deadline = wait > INT64_MAX - begin ? INT64_MAX : begin + wait;
  for (;;) {
    const TimeNs now = clock_.now();
    const HalStatus s = capture_due(now);
    if (s != HalStatus::kOk) return s;
    if (done_.count > 0) break;
    if (now >= deadline) {
      ++stats_.timeouts;
      return HalStatus::kTimeout;
    }
    const TimeNs t = source_.next_frame_time();
    clock_.sleep_until(t < 0 || t > deadline ? deadline : t);
    if (clock_.now() <= now) {
      // A clock that does not move (a replay clock after a divergence)
      // would make this spin.
      ++stats_.timeouts;
      return HalStatus::kTimeout;
    }
  }
  const int i = done_.pop();
  Buffer& b = buffers_[i];
  b.state = State::kLent;
  frame->index = i;
  frame->data = b.data;
  frame->bytes_used = b.bytes_used;
  frame->length = format_.image_size;
  frame->stamp = b.stamp;
  frame->sequence = b.sequence;
  frame->corrupted = b.corrupted;
  ++stats_.frames;
  const std::uint32_t gap = tracker_.observe(b.sequence);
  if (gap > 0) {
    stats_.dropped += gap;
    ++stats_.sequence_gaps;
  }
  if (b.corrupted) ++stats_.corrupted;
  return HalStatus::kOk;
}

HalStatus MockVideoStream::release(int index) noexcept {
  if (index < 0 || index >= nbuffers_ || buffers_[index].state != State::kLent) {
    set_error("mock video: release of buffer %d, which is not lent", index);
    return HalStatus::kIoError;
  }
  if (unplugged_) {
    buffers_[index].state = State::kQueued;  // a reopen queues every buffer anew
    set_error("mock video: release: the device is unplugged; reopen() it");
    return HalStatus::kClosed;
  }
  buffers_[index].state = State::kQueued;
  queued_.push(index);
  return HalStatus::kOk;
}

HalStatus MockVideoStream::reopen() noexcept {
  if (refuse_reopens_ > 0) {
    --refuse_reopens_;
    ++stats_.reopen_failures;
    set_error("mock video: reopen refused (the device is not back)");
    return HalStatus::kClosed;
  }
  unplugged_ = false;
  stop();
  const HalStatus s = start();
  if (s == HalStatus::kOk) ++stats_.reopens;
  return s;
}

}  // namespace rtfuse::hal::mock
