#pragma once
// Replay of a recorded camera (hal/recording_video_stream.hpp).
//
// ReplayVideoLog: the recorded VideoStream calls of one stream, in call
// order, with their frames in memory (loaded with the recording), handed
// back one by one. Like ReplayStream, each call is checked against the next
// recorded one (kind, device, dequeue's timeout, release's buffer index);
// anything else stops the replay with a report naming the log event, the
// recorded call and the attempted call, e.g.
//
//   event 812: recorded dequeue timeout 100000000 ns, driver called release index 2
//
// A frame the recorder lost (its ring was full) ends the stream there, and
// the end-of-stream report names it:
//
//   frame 41 of stream camera was not recorded: the recorder's ring was full ...
//
// ReplayVideoStream: the VideoStream a driver is given. dequeue() lends the
// recorded frame (a pointer into the loaded recording, no copy) with the
// recorded index, stamp, sequence, bytes_used and error flag; format() is
// the recorded format. After a divergence every call returns kClosed.
//
// Loading allocates; take() and every VideoStream call never allocate, lock
// or block. One thread replays a log; diverged() and the report may be read
// from any other thread (the report once diverged() is true).
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "hal/replay/replay_stream.hpp"
#include "hal/video_event.hpp"
#include "hal/video_stream.hpp"

namespace rtfuse::hal::replay {

class ReplayVideoLog {
 public:
  static constexpr std::size_t kReportSize = 512;

  explicit ReplayVideoLog(std::string name = "camera");
  ReplayVideoLog(const ReplayVideoLog&) = delete;
  ReplayVideoLog& operator=(const ReplayVideoLog&) = delete;

  // --- loading (before the replay starts) ---------------------------------
  // One recorded call and, when ev.has_frame(), its ev.data_size frame bytes
  // (kept zero-padded up to ev.length, so a driver may read the whole buffer).
  void append(const VideoEvent& ev, const std::uint8_t* data, std::int64_t log_event);
  // The recorder lost `lost` calls before the record at log_event, whose
  // frames_before is next_frames_before: the replay can only go this far.
  void mark_hole(std::int64_t log_event, std::uint32_t lost, std::int64_t next_frames_before);
  void set_device_name(std::uint8_t device, std::string name);

  // --- replay (the stream's thread) ---------------------------------------
  // The recorded call, valid until the next take(), when `call` (kind,
  // device, timeout_ns / index) is the same; else nullptr and the divergence
  // is set (the first one wins). *frame: the recorded bytes of a frame.
  const VideoEvent* take(const VideoEvent& call, const std::uint8_t** frame) noexcept;

  bool diverged() const noexcept { return kind_.load(std::memory_order_acquire) != DivergenceKind::kNone; }
  DivergenceKind divergence_kind() const noexcept { return kind_.load(std::memory_order_acquire); }
  const char* divergence() const noexcept { return diverged() ? report_ : ""; }
  std::int64_t divergence_event() const noexcept { return diverged() ? report_event_ : -1; }
  bool at_end() const noexcept {
    return position() == size() && divergence_kind() != DivergenceKind::kMismatch;
  }
  std::size_t position() const noexcept { return position_.load(std::memory_order_acquire); }
  std::size_t size() const noexcept { return calls_.size(); }
  std::size_t remaining() const noexcept { return size() - position(); }

  // --- inspection (tools, tests) -------------------------------------------
  const std::string& name() const { return name_; }
  const VideoEvent& event(std::size_t i) const noexcept { return calls_[i].ev; }
  // The i-th call's frame bytes (ev.length of them, or data_size if larger); null without a frame.
  const std::uint8_t* data(std::size_t i) const noexcept;
  std::int64_t log_event(std::size_t i) const noexcept { return calls_[i].log_event; }
  std::int64_t frames() const noexcept { return frames_; }  // recorded frames
  bool has_hole() const noexcept { return hole_lost_ > 0; }
  std::int64_t hole_event() const noexcept { return hole_event_; }
  // First frame number the hole lost, -1 when it lost no frame (or there is none).
  std::int64_t first_lost_frame() const noexcept { return hole_frames_ > 0 ? hole_first_frame_ : -1; }
  std::int64_t lost_frames() const noexcept { return hole_frames_; }

 private:
  struct Call {
    VideoEvent ev;
    std::int64_t log_event;
    std::size_t offset;  // into bytes_, when ev.has_frame()
  };
  void diverge(DivergenceKind kind, std::int64_t log_event, const VideoEvent* recorded,
               const VideoEvent& call) noexcept;
  int describe(char* buf, std::size_t size, const VideoEvent& ev, bool attempted, bool with_device) const noexcept;

  std::string name_;
  std::vector<Call> calls_;
  std::vector<std::uint8_t> bytes_;
  std::vector<std::string> device_names_;
  std::int64_t frames_ = 0;
  std::int64_t hole_event_ = -1;
  std::uint32_t hole_lost_ = 0;
  std::int64_t hole_first_frame_ = -1;
  std::int64_t hole_frames_ = 0;

  std::atomic<std::size_t> position_{0};
  std::atomic<DivergenceKind> kind_{DivergenceKind::kNone};
  std::int64_t report_event_ = -1;
  char report_[kReportSize] = {};
};

class ReplayVideoStream final : public VideoStream {
 public:
  // format() starts as the first recorded call's format (what the live
  // stream had negotiated before its first call) and follows each call.
  ReplayVideoStream(ReplayVideoLog& log, std::uint8_t device) noexcept;

  const VideoFormat& format() const noexcept override { return format_; }
  HalStatus start() noexcept override;
  void stop() noexcept override;
  HalStatus dequeue(TimeNs timeout_ns, VideoFrame* frame) noexcept override;
  HalStatus release(int index) noexcept override;
  HalStatus reopen() noexcept override;
  // Counted from the replayed results as a device backend counts them.
  const VideoStreamStats& stats() const noexcept override { return stats_; }
  const char* last_error() const noexcept override;

  std::uint8_t device() const noexcept { return device_; }

 private:
  const VideoEvent* take(VideoCallKind kind, TimeNs timeout_ns, int index, const std::uint8_t** frame) noexcept;

  ReplayVideoLog& log_;
  std::uint8_t device_;
  VideoFormat format_;
  VideoStreamStats stats_;
  SequenceTracker tracker_;
  HalStatus last_status_ = HalStatus::kOk;
};

}  // namespace rtfuse::hal::replay
