// A whole HAL recording as rtfuse-replay loads it: recording_info_t, the
// recorded files, every device's bus events, camera calls with frames, loop
// ticks, outputs and the end record. The first byte chooses whether a
// truncated log is allowed (rtfuse-replay --allow-truncated); the rest is
// the log. Property: loaded, or refused with a message; never both.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_check.hpp"
#include "memory_file.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "transport/event_log.hpp"

using rtfuse::HalRecording;
using rtfuse::HalRecordingOptions;
using rtfuse::load_hal_recording;
using rtfuse::transport::EventLogReader;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static rtfuse::fuzz::MemoryFile file;
  HalRecordingOptions options;
  options.allow_truncated = (data[0] & 1) != 0;
  // Under libFuzzer's 2 GiB limit, with room for ASan's own (rtfuse-replay
  // allows 4 GiB by default).
  options.max_frame_bytes = std::uint64_t{512} << 20;
  EventLogReader reader;
  std::string error;
  FUZZ_CHECK(reader.open(file.hold(data + 1, size - 1), &error), error.c_str());
  HalRecording rec;
  const bool ok = load_hal_recording(reader, options, &rec, &error);
  if (!ok) {
    FUZZ_CHECK(!error.empty(), "a refused recording says why");
    return 0;
  }
  FUZZ_CHECK(rec.streams.size() == rec.info.streams.size(), "one replay stream per recorded thread");
  FUZZ_CHECK(rec.videos.size() == rec.info.streams.size(), "one video log per recorded thread");
  FUZZ_CHECK(options.allow_truncated || !rec.truncated, "a truncated log loads only when allowed");
  FUZZ_CHECK(rec.events >= 1 && rec.lost_events >= 0 && rec.missing_ticks >= 0, "counts are possible");
  return 0;
}
