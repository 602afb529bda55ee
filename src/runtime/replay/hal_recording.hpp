#pragma once
// Loading a whole HAL recording (rtfused --record, rtfuse-sim) for a replay
// (rtfuse-replay, rtfuse-camera-snapshot, the tests): the records the
// transport codec decodes (transport/hal_record_codec.hpp) become the replay
// streams the drivers' replay buses check their calls against
// (hal/replay). Here rather than in transport, so the codec does not depend
// on the replay buses. Loading allocates freely; it happens before a replay.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hal/replay/replay_stream.hpp"
#include "hal/replay/replay_video_stream.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"

namespace rtfuse {

// A recorded message that is not a record: a published output.
struct RecordedOutput {
  std::string channel;
  std::int64_t utime = 0;         // the log event's timestamp
  std::int64_t event_number = 0;  // in the log
  std::vector<std::uint8_t> bytes;
};

struct HalRecording {
  transport::RecordingInfo info;
  // One per info.streams entry, in that order, with every device's name set.
  std::vector<std::unique_ptr<hal::replay::ReplayStream>> streams;
  // One per info.streams entry too: the recorded camera calls of that stream
  // (empty for a stream without a video device), frames in memory.
  std::vector<std::unique_ptr<hal::replay::ReplayVideoLog>> videos;
  std::vector<transport::LoopTick> ticks;
  std::vector<RecordedOutput> outputs;
  // Devices' LCM inputs (the navigator's goals), in their order, each named
  // by its channel without kRecordedInputPrefix.
  std::vector<RecordedOutput> inputs;
  std::int64_t events = 0;         // log events loaded
  // The log ends mid-event or without its end record: the recorder was
  // killed or lost power (loaded with allow_truncated).
  bool truncated = false;
  std::int64_t lost_events = 0;    // bus events and video calls the recorder had no room for
  std::int64_t lost_frames = 0;    // camera frames among them
  std::int64_t missing_ticks = 0;  // gaps in the tick sequence
  std::vector<std::string> warnings;  // one line each: truncation, holes, missing ticks
};

struct HalRecordingOptions {
  // Keep the complete events of a log that ends mid-event or without its
  // end record (a killed recorder, a power loss).
  bool allow_truncated = false;
  // Camera frames are held in memory for the replay, each padded to its
  // buffer's capacity as the driver saw it. A recording whose frames need
  // more is refused with the figure (rtfuse-replay --frame-memory) rather
  // than left to the OOM killer: a corrupt buffer length in a few bytes of
  // log could otherwise ask for gigabytes.
  std::uint64_t max_frame_bytes = std::uint64_t{4} << 30;
};

// Reads the whole log from an open reader. False with one error naming the
// file, the event number and channel, and the likely fix when: the first
// event is not a recording_info_t (not a recording), its format version is
// not kHalRecordFormatVersion, the log is truncated or lacks its end record
// (unless allowed), an event cannot be decoded, an event follows the end
// record, the end record's count differs from the events read, or the log is
// corrupt.
// A stream whose recorder lost events (ring overflow) is loaded up to the
// hole; its end-of-stream report says so.
bool load_hal_recording(transport::EventLogReader& reader, const HalRecordingOptions& options, HalRecording* out,
                        std::string* error);

}  // namespace rtfuse
