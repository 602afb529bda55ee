#pragma once
// Replay of a recorded camera (hal/recording_video_stream.hpp).
//
// ReplayVideoLog: the recorded VideoStream calls of one stream, in call
// order, with their frames in memory (loaded with the recording), handed
// back one by one. Each call is checked against the next recorded one
// (kind, device, dequeue's timeout, release's buffer index) by the rules
// every replay follows (hal/replay/replay_cursor.hpp); anything else stops
// the replay with a report naming the log event, the recorded call and the
// attempted call, e.g.
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
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "hal/replay/replay_cursor.hpp"
#include "hal/replay/report_text.hpp"
#include "hal/video_event.hpp"
#include "hal/video_stream.hpp"

namespace rtfuse::hal::replay {

class ReplayVideoLog : public ReplayCursor<ReplayVideoLog, VideoEvent> {
 public:
  explicit ReplayVideoLog(std::string name = "camera");

  // --- loading (before the replay starts) ---------------------------------
  // One recorded call and, when ev.has_frame(), its ev.data_size frame bytes
  // (kept zero-padded up to ev.length, so a driver may read the whole buffer).
  // Ignored after a hole.
  void append(const VideoEvent& ev, const std::uint8_t* data, std::int64_t log_event);
  // The recorder lost `lost` calls before the record at log_event, whose
  // frames_before is next_frames_before: the replay can only go this far.
  void mark_hole(std::int64_t log_event, std::uint32_t lost, std::int64_t next_frames_before);

  // --- replay (the stream's thread) ---------------------------------------
  // The recorded call, valid until the next take(), when `call` (kind,
  // device, timeout_ns / index) is the same; else nullptr and the divergence
  // is set (the first one wins). *frame: the recorded bytes of a frame.
  const VideoEvent* take(const VideoEvent& call, const std::uint8_t** frame) noexcept;

  // --- inspection (tools, tests) -------------------------------------------
  const VideoEvent& event(std::size_t i) const noexcept { return calls_[i].ev; }
  // The i-th call's frame bytes (ev.length of them, or data_size if larger); null without a frame.
  const std::uint8_t* data(std::size_t i) const noexcept;
  std::int64_t frames() const noexcept { return frames_; }  // recorded frames
  // First frame number the hole lost, -1 when it lost no frame (or there is none).
  std::int64_t first_lost_frame() const noexcept { return hole_frames_ > 0 ? hole_first_frame_ : -1; }
  std::int64_t lost_frames() const noexcept { return hole_frames_; }

 private:
  friend class ReplayCursor<ReplayVideoLog, VideoEvent>;
  static constexpr const char* kCallNoun = "calls";
  static constexpr const char* kNothingRecorded = "recorded video calls";

  struct Call {
    VideoEvent ev;
    std::size_t offset;  // into bytes_, when ev.has_frame()
  };
  const VideoEvent& recorded(std::size_t i) const noexcept { return calls_[i].ev; }
  // Of two calls of the same kind on the same device.
  static bool same_arguments(const VideoEvent& rec, const VideoEvent& call) noexcept;
  void describe_call(ReportText& t, const VideoEvent& ev, bool attempted) const noexcept;
  void describe_arguments(ReportText& t, const VideoEvent& ev) const noexcept;
  void describe_hole(ReportText& t, unsigned long long replayed) const noexcept;

  std::vector<Call> calls_;
  std::vector<std::uint8_t> bytes_;
  std::int64_t frames_ = 0;
  std::int64_t hole_first_frame_ = -1;
  std::int64_t hole_frames_ = 0;
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
