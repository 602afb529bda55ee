#pragma once
// rtfused --record FILE.lcm: the non-real-time side of HAL recording.
//
// The recording decorators (hal/recording_*.hpp) of each producing thread
// push BusEvents into that thread's ring (ring(stream)); the loop pushes one
// record per tick (record_tick) and the publisher a copy of every published
// message (record_output, or RecordingSink). None of these block or allocate:
// a full ring drops the record and counts it. The writer thread "rtfuse-rec"
// drains every ring, encodes (transport/hal_record_codec.hpp) and appends to
// an lcm-logger file, sleeping a few milliseconds whenever all rings are
// empty. The file starts with the recording_info_t, written by create(), so
// even a recorder killed at once leaves a recognisable recording.
//
// A camera records through a VideoRecordRing instead (add_video_ring before
// start): heads of every call plus large frame slots, sized from the
// negotiated format. The writer encodes one hal_video_t per call. At VGA
// side-by-side YUYV 30 fps that is ~30 MB/s to the disk; a disk slower than
// that fills the frame slots and the camera's decorator drops (and counts)
// records, the camera thread never waits.
//
// File order is drain order: events of one stream stay in call order, ticks
// in tick order, outputs in publish order; nothing orders one ring against
// another (replay does not need it: each thread replays its own stream).
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "core/fixed_string.hpp"
#include "core/spsc_ring.hpp"
#include "core/time.hpp"
#include "hal/bus_event.hpp"
#include "hal/video_event.hpp"
#include "runtime/config/config.hpp"
#include "runtime/pipeline/publisher.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"

namespace rtfuse::runtime {

struct RecorderRingSizes {
  std::size_t bus_events = 4096;  // per stream; a 1 kHz IMU thread makes ~3 events per sample
  std::size_t ticks = 1024;
  std::size_t outputs = 256;
};

struct RecorderStats {
  std::int64_t events_written = 0;  // log events, the recording_info_t included
  std::int64_t bytes_written = 0;   // as laid out in the file (headers, channels, data)
  std::int64_t write_errors = 0;    // records the file did not take (disk full...)
  std::int64_t encode_errors = 0;   // bus events for a device or call the info does not list
  // Per stream: bus events lost to a full ring, as the event after each loss
  // reports it (a loss at the very end of a run is only in the decorators'
  // own overflows() counters).
  std::vector<std::int64_t> bus_events_lost;
  std::int64_t ticks_lost = 0;        // tick ring full
  std::int64_t ticks_rejected = 0;    // more sensors than a tick record holds
  std::int64_t outputs_lost = 0;      // output ring full
  std::int64_t outputs_rejected = 0;  // larger than kMaxOutputBytes or a bad channel name
  std::int64_t inputs_lost = 0;       // device input ring full
  std::int64_t inputs_rejected = 0;   // as outputs_rejected
  // Video rings: frames written, and frames lost to a full ring as the
  // records after each hole report them (their calls also count in
  // bus_events_lost of the camera's stream).
  std::int64_t video_frames_written = 0;
  std::int64_t video_frames_lost = 0;
};

namespace recorder_detail {
constexpr int kMaxOutputBytes = 8192;
constexpr std::size_t kMaxChannelLength = 63;
// Sensors, then the devices' input channels (Hardware::input_count).
constexpr int kMaxTickInputs = 8;
constexpr int kMaxTickSensors = kMaxSensors + kMaxTickInputs;

// Ring slots (outside Recorder: a nested type is incomplete, for SpscRing's
// checks, until the class ends).
struct TickSlot {
  TimeNs time_ns = 0;
  std::int64_t seq = 0;
  std::int32_t n = 0;
  std::int64_t consumed[kMaxTickSensors] = {};
  std::uint32_t published = 0;
};
struct OutputSlot {
  TimeNs now = 0;
  std::int32_t size = 0;
  FixedString<kMaxChannelLength> channel;
  std::uint8_t data[kMaxOutputBytes] = {};
};
}  // namespace recorder_detail

class Recorder {
 public:
  static constexpr int kMaxOutputBytes = recorder_detail::kMaxOutputBytes;
  static constexpr std::size_t kMaxChannelLength = recorder_detail::kMaxChannelLength;
  static constexpr int kMaxTickSensors = recorder_detail::kMaxTickSensors;
  // How long the writer sleeps when every ring is empty.
  static constexpr TimeNs kIdleSleepNs = 2'000'000;

  // Opens (truncates) `path` and writes the recording_info_t. info.start_ns
  // 0 becomes now; config_hash is computed from config_text. Null with the
  // error when the info is invalid or the file cannot be written.
  static std::unique_ptr<Recorder> create(const std::string& path, transport::RecordingInfo info,
                                          const RecorderRingSizes& sizes, std::string* error);
  ~Recorder();  // stop()
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  const transport::RecordingInfo& info() const { return info_; }
  int stream_count() const { return static_cast<int>(rings_.size()); }
  // Index of a stream by name, -1 if none.
  int stream_index(std::string_view name) const;
  // The ring the decorators of `stream`'s thread push into (0 <= stream < stream_count()).
  SpscRing<hal::BusEvent>& ring(int stream) { return *rings_[static_cast<std::size_t>(stream)]; }

  // The ring a camera's RecordingVideoStream pushes into, for `stream` (the
  // camera's own stream: info lists only video devices on it). slot_bytes:
  // the negotiated format's image_size; frame_slots: frames it can hold
  // while the disk lags (each slot_bytes of memory); events: call heads
  // (0: 4 per frame slot + 64, room for the releases and timeouts between
  // frames). Call before start(), from the thread that calls start(). Null
  // with the reason for a bad stream or size, or after start().
  hal::VideoRecordRing* add_video_ring(int stream, std::size_t slot_bytes, std::size_t frame_slots,
                                       std::size_t events = 0, std::string* error = nullptr);

  // Loop thread only. consumed[i]: samples taken from sensor i's ring since
  // start, up to and including this tick. False: not recorded (ring full, or
  // n outside 0..kMaxTickSensors), counted.
  // published: the outputs the loop queued for this tick (Publisher::OutputBit).
  bool record_tick(TimeNs t, std::uint64_t seq, const std::int64_t* consumed, int n,
                   std::uint32_t published = 0) noexcept;
  // The thread that delivers devices' LCM inputs (the LCM thread live, the
  // drive in lockstep) only: a message on a device's input channel, before
  // the device gets it, written on kRecordedInputPrefix + channel. The
  // tick records count how many of each the loop had taken, so a replay
  // hands them over at the same ticks. False as record_output.
  bool record_input(const char* channel, const std::uint8_t* data, int size, TimeNs now) noexcept;
  // Publisher thread only. The bytes are copied. False: not recorded (ring
  // full, too large, channel empty or longer than kMaxChannelLength), counted.
  bool record_output(const char* channel, const std::uint8_t* data, int size, TimeNs now) noexcept;

  // Starts the writer thread. False with the reason if it cannot.
  bool start(std::string* error);
  // Call after the producers stopped: drains every ring, flushes, closes the
  // file and joins. Idempotent. False with the first write error if any
  // record or the final flush failed.
  bool stop(std::string* error = nullptr);

  // Counters so far; allocates (call from a non-RT thread).
  RecorderStats stats() const;
  // Whether a record failed to reach the file (disk full, I/O error), and
  // the first reason, while the writer runs: rtfused says so at once
  // instead of at exit. Any thread but the writer; *why allocates.
  bool failed(std::string* why = nullptr) const;

  // True while some ring is more than half full. A lockstep producer (the
  // simulator, which runs as fast as the CPU allows) waits on it so the
  // writer keeps up and nothing is lost; the live loop never waits.
  bool backlogged() const noexcept;

 private:
  using TickSlot = recorder_detail::TickSlot;
  using OutputSlot = recorder_detail::OutputSlot;

  Recorder(transport::RecordingInfo info, const RecorderRingSizes& sizes);
  void run() noexcept;
  // One pass over every ring (a bounded batch each); records written.
  std::size_t drain_once() noexcept;
  void write(std::int64_t utime, std::string_view channel, const std::uint8_t* data, std::size_t size) noexcept;

  transport::RecordingInfo info_;
  transport::HalRecordCodec codec_;
  transport::EventLogWriter writer_;
  std::vector<std::unique_ptr<SpscRing<hal::BusEvent>>> rings_;
  struct VideoRing {
    int stream = 0;
    std::unique_ptr<hal::VideoRecordRing> ring;
    std::int64_t next_frame = 0;  // writer thread: frame number the next record should follow
  };
  std::vector<VideoRing> video_rings_;
  std::vector<std::uint8_t> video_buf_;  // encode buffer, sized by add_video_ring
  SpscRing<TickSlot> ticks_;
  SpscRing<OutputSlot> outputs_;
  SpscRing<OutputSlot> inputs_;
  // Producer-side staging: one per producing thread, so an 8 KiB slot is not
  // built on that thread's stack.
  TickSlot tick_staging_;
  OutputSlot output_staging_;
  OutputSlot input_staging_;

  std::thread thread_;
  std::atomic<bool> stop_requested_{false};
  bool stopped_ = false;
  std::string first_error_;  // writer thread; set once, then published by failed_
  std::atomic<bool> failed_{false};
  std::int64_t last_utime_ = 0;  // writer thread: the newest event's stamp, for the end record

  std::atomic<std::int64_t> events_written_{0};
  std::atomic<std::int64_t> bytes_written_{0};
  std::atomic<std::int64_t> write_errors_{0};
  std::atomic<std::int64_t> encode_errors_{0};
  std::unique_ptr<std::atomic<std::int64_t>[]> bus_lost_;
  std::atomic<std::int64_t> ticks_lost_{0};
  std::atomic<std::int64_t> ticks_rejected_{0};
  std::atomic<std::int64_t> outputs_lost_{0};
  std::atomic<std::int64_t> outputs_rejected_{0};
  std::atomic<std::int64_t> inputs_lost_{0};
  std::atomic<std::int64_t> inputs_rejected_{0};
  std::atomic<std::int64_t> video_frames_written_{0};
  std::atomic<std::int64_t> video_frames_lost_{0};
};

// A MessageSink that publishes through `inner` and records every message it
// was given into the recorder (the publisher thread's end of record_output).
class RecordingSink final : public MessageSink {
 public:
  RecordingSink(MessageSink& inner, Recorder& recorder) : inner_(inner), recorder_(recorder) {}
  bool publish(const char* channel, const std::uint8_t* data, int size, TimeNs now) override {
    recorder_.record_output(channel, data, size, now);
    return inner_.publish(channel, data, size, now);
  }

 private:
  MessageSink& inner_;
  Recorder& recorder_;
};

}  // namespace rtfuse::runtime
