#include "hal/replay/replay_video_stream.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

#include "hal/replay/report_text.hpp"

namespace rtfuse::hal::replay {

ReplayVideoLog::ReplayVideoLog(std::string name) : ReplayCursor(std::move(name)) {}

void ReplayVideoLog::append(const VideoEvent& ev, const std::uint8_t* data, std::int64_t log_event) {
  if (!add_call(log_event)) return;
  Call c{ev, bytes_.size()};
  if (ev.has_frame()) {
    // Zero-padded to the buffer's capacity: a driver may look past bytes_used
    // (a short frame) without reading outside the loaded recording.
    const std::size_t keep = std::max<std::size_t>(ev.data_size, ev.length);
    bytes_.resize(bytes_.size() + keep, 0);
    if (data != nullptr && ev.data_size > 0) std::memcpy(bytes_.data() + c.offset, data, ev.data_size);
    ++frames_;
  }
  calls_.push_back(c);
}

void ReplayVideoLog::mark_hole(std::int64_t log_event, std::uint32_t lost, std::int64_t next_frames_before) {
  if (!ReplayCursor::mark_hole(log_event, lost)) return;
  std::int64_t next_frame = 0;
  if (!calls_.empty()) {
    const VideoEvent& last = calls_.back().ev;
    next_frame = last.frames_before + (last.has_frame() ? 1 : 0);
  }
  hole_first_frame_ = next_frame;
  hole_frames_ = std::max<std::int64_t>(0, next_frames_before - next_frame);
}

const std::uint8_t* ReplayVideoLog::data(std::size_t i) const noexcept {
  if (i >= calls_.size() || !calls_[i].ev.has_frame()) return nullptr;
  return bytes_.data() + calls_[i].offset;
}

const VideoEvent* ReplayVideoLog::take(const VideoEvent& call, const std::uint8_t** frame) noexcept {
  if (frame != nullptr) *frame = nullptr;
  std::size_t taken = 0;
  const VideoEvent* rec = take_next(call, &taken);
  if (rec != nullptr && frame != nullptr) *frame = data(taken);
  return rec;
}

bool ReplayVideoLog::same_arguments(const VideoEvent& rec, const VideoEvent& call) noexcept {
  switch (rec.kind) {
    case VideoCallKind::kDequeue: return rec.timeout_ns == call.timeout_ns;
    case VideoCallKind::kRelease: return rec.index == call.index;
    case VideoCallKind::kStart:
    case VideoCallKind::kStop:
    case VideoCallKind::kReopen:
    case VideoCallKind::kNone: return true;
  }
  return false;
}

void ReplayVideoLog::describe_call(ReportText& t, const VideoEvent& ev, bool attempted) const noexcept {
  t.add(attempted ? "called %s" : "%s", to_string(ev.kind));
}

void ReplayVideoLog::describe_arguments(ReportText& t, const VideoEvent& ev) const noexcept {
  if (ev.kind == VideoCallKind::kDequeue) t.add(" timeout %lld ns", static_cast<long long>(ev.timeout_ns));
  if (ev.kind == VideoCallKind::kRelease) t.add(" index %d", ev.index);
}

void ReplayVideoLog::describe_hole(ReportText& t, unsigned long long replayed) const noexcept {
  if (hole_frames_ > 0) {
    // Frames are what a camera replay is for: name the first one missing.
    t.add(": frame %lld of stream %s was not recorded: the recorder's ring was full (%lld frames, %u calls lost; "
          "%llu calls replayed)",
          static_cast<long long>(hole_first_frame_), name().c_str(), static_cast<long long>(hole_frames_),
          hole_lost(), replayed);
  } else {
    describe_lost_calls(t, replayed, "no frame among them; ");
  }
}

// ---------------------------------------------------------------- stream

ReplayVideoStream::ReplayVideoStream(ReplayVideoLog& log, std::uint8_t device) noexcept
    : log_(log), device_(device) {
  if (log_.size() > 0) format_ = log_.event(0).format();
}

const VideoEvent* ReplayVideoStream::take(VideoCallKind kind, TimeNs timeout_ns, int index,
                                          const std::uint8_t** frame) noexcept {
  VideoEvent call;
  call.kind = kind;
  call.device = device_;
  call.timeout_ns = timeout_ns;
  call.index = index;
  const VideoEvent* rec = log_.take(call, frame);
  if (rec == nullptr) {
    last_status_ = HalStatus::kClosed;
    return nullptr;
  }
  last_status_ = rec->status;
  format_ = rec->format();
  return rec;
}

HalStatus ReplayVideoStream::start() noexcept {
  const VideoEvent* rec = take(VideoCallKind::kStart, 0, -1, nullptr);
  if (rec != nullptr && rec->status == HalStatus::kOk) tracker_.reset();
  return last_status_;
}

void ReplayVideoStream::stop() noexcept { take(VideoCallKind::kStop, 0, -1, nullptr); }

HalStatus ReplayVideoStream::dequeue(TimeNs timeout_ns, VideoFrame* frame) noexcept {
  const std::uint8_t* data = nullptr;
  const VideoEvent* rec = take(VideoCallKind::kDequeue, timeout_ns, -1, &data);
  if (rec == nullptr) return last_status_;
  switch (rec->status) {
    case HalStatus::kOk: break;
    case HalStatus::kTimeout: ++stats_.timeouts; return rec->status;
    case HalStatus::kClosed: ++stats_.lost; return rec->status;
    default: return rec->status;
  }
  ++stats_.frames;
  const std::uint32_t gap = tracker_.observe(rec->sequence);
  if (gap > 0) {
    stats_.dropped += gap;
    ++stats_.sequence_gaps;
  }
  if (rec->corrupted != 0) ++stats_.corrupted;
  if (frame != nullptr) {
    frame->index = rec->index;
    frame->data = data;
    frame->bytes_used = rec->bytes_used;
    frame->length = rec->length;
    frame->stamp = rec->stamp;
    frame->sequence = rec->sequence;
    frame->corrupted = rec->corrupted != 0;
  }
  return rec->status;
}

HalStatus ReplayVideoStream::release(int index) noexcept {
  take(VideoCallKind::kRelease, 0, index, nullptr);
  return last_status_;
}

HalStatus ReplayVideoStream::reopen() noexcept {
  const VideoEvent* rec = take(VideoCallKind::kReopen, 0, -1, nullptr);
  if (rec == nullptr) return last_status_;
  if (rec->status == HalStatus::kOk) {
    ++stats_.reopens;
    tracker_.reset();
  } else {
    ++stats_.reopen_failures;
  }
  return rec->status;
}

const char* ReplayVideoStream::last_error() const noexcept {
  return log_.diverged() ? log_.divergence() : to_string(last_status_);
}

}  // namespace rtfuse::hal::replay
