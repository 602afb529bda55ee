#pragma once
// GPIO lines that answer from a recording: the data-ready edge source gives
// back the recorded edges (stamp and direction) and statuses, the output
// checks each level set against the recorded one. After a divergence every
// call returns kClosed. Never block or allocate.
#include <cstdint>

#include "hal/gpio.hpp"
#include "hal/replay/replay_stream.hpp"

namespace rtfuse::hal::replay {

class ReplayEdgeSource final : public GpioEdgeSource {
 public:
  ReplayEdgeSource(ReplayStream& stream, std::uint8_t device) noexcept : stream_(stream), device_(device) {}

  // The timeout must be the recorded one; *out is written only on kOk.
  HalStatus wait_edge(TimeNs timeout_ns, GpioEdge* out) noexcept override;
  const char* last_error() const noexcept override;

 private:
  ReplayStream& stream_;
  std::uint8_t device_;
  HalStatus last_status_ = HalStatus::kOk;
};

class ReplayGpioOutput final : public GpioOutput {
 public:
  ReplayGpioOutput(ReplayStream& stream, std::uint8_t device) noexcept : stream_(stream), device_(device) {}

  HalStatus set(bool high) noexcept override;
  const char* last_error() const noexcept override;
  // The level of the last set() the recording accepted.
  bool level() const noexcept { return level_; }

 private:
  ReplayStream& stream_;
  std::uint8_t device_;
  HalStatus last_status_ = HalStatus::kOk;
  bool level_ = false;
};

}  // namespace rtfuse::hal::replay
