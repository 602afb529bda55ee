// The lcm-logger file reader every replay and recording check starts from.
// Property: the reader ends at kEnd or kError (with a message) within as
// many events as the file can hold, and every event lies inside the file.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_check.hpp"
#include "memory_file.hpp"
#include "transport/event_log.hpp"

using rtfuse::transport::EventLogReader;
using rtfuse::transport::LogEvent;
using rtfuse::transport::ReadStatus;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static rtfuse::fuzz::MemoryFile file;
  EventLogReader reader;
  std::string error;
  FUZZ_CHECK(reader.open(file.hold(data, size), &error), error.c_str());
  const std::size_t max_events = size / rtfuse::transport::kEventHeaderSize;
  std::size_t bytes = 0;
  for (std::size_t n = 0;; ++n) {
    LogEvent ev;
    const ReadStatus s = reader.next(&ev, &error);
    if (s == ReadStatus::kEnd) {
      FUZZ_CHECK(reader.offset() == size, "a clean end is the end of the file");
      break;
    }
    if (s == ReadStatus::kError) {
      FUZZ_CHECK(!error.empty(), "a corrupt log says why");
      // Sticky: the same answer again.
      std::string again;
      FUZZ_CHECK(reader.next(&ev, &again) == ReadStatus::kError && again == error, "errors are sticky");
      break;
    }
    FUZZ_CHECK(n < max_events, "no more events than headers fit in the file");
    bytes += rtfuse::transport::kEventHeaderSize + ev.channel.size() + ev.size;
    FUZZ_CHECK(bytes <= size && reader.offset() == bytes, "events lie inside the file");
  }
  return 0;
}
