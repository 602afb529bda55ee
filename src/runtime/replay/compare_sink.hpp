#pragma once
// Where a HAL replay's outputs go: written to the output log (if any) and,
// for the estimate channels, compared one by one with the messages the live
// run published on the same channel, in publishing order.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "runtime/config/config.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "transport/event_log.hpp"
#include "transport/message_sink.hpp"

namespace rtfuse {

class CompareSink final : public transport::MessageSink {
 public:
  // Only the estimate channels are compared: other recorded channels (the
  // simulator's ground truth) are not the publisher's, and diagnostics hold
  // the live machine's timings.
  CompareSink(const HalRecording& rec, const RuntimeConfig& cfg, transport::EventLogWriter* out);

  bool publish(const char* channel, const std::uint8_t* data, int size, TimeNs now) override;
  // Recorded estimate messages the replay has not published (yet).
  std::int64_t not_reproduced() const;

  std::int64_t published = 0, compared = 0, identical = 0;
  std::string first_mismatch;  // "" while every compared message was identical
  std::string error;           // writing the output log

 private:
  std::string diagnostics_;
  transport::EventLogWriter* out_;
  std::map<std::string, std::vector<const RecordedOutput*>> recorded_;
  std::map<std::string, std::size_t> next_;
};

}  // namespace rtfuse
