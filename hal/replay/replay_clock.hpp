#pragma once
// A Clock that answers from a recording: now() returns the recorded readings
// in order, sleep_until() checks the deadline against the recorded one and
// returns at once. After a divergence (the stream holds the report) time
// stands still at the last recorded reading and sleeps return at once: the
// thread keeps running but every bus call fails with kClosed, and the
// replayer stops on ReplayStream::diverged(). Never blocks or allocates.
#include <cstdint>

#include "hal/clock.hpp"
#include "hal/replay/replay_stream.hpp"

namespace rtfuse::hal::replay {

class ReplayClock final : public Clock {
 public:
  ReplayClock(ReplayStream& stream, std::uint8_t device) noexcept : stream_(stream), device_(device) {}

  TimeNs now() const noexcept override;
  void sleep_until(TimeNs t) noexcept override;

 private:
  ReplayStream& stream_;
  std::uint8_t device_;
  mutable TimeNs last_ = 0;  // now() is const in the interface; replaying moves the cursor
};

}  // namespace rtfuse::hal::replay
