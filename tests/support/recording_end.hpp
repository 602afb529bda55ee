#pragma once
// The rtfuse/rec/end record a test writes last into a hand-made HAL
// recording, as Recorder::stop does: without it the loader takes the log
// for one cut short.
#include <cstdint>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"

namespace rtfuse::test {

inline bool write_recording_end(transport::EventLogWriter& w, std::int64_t utime, std::string* err) {
  const std::vector<std::uint8_t> end = transport::encode_recording_end({utime_to_ns(utime), w.events_written(), 0});
  return w.write(utime, std::string(transport::kRecordingEndChannel), end.data(), end.size(), err);
}

}  // namespace rtfuse::test
