#pragma once
// A CanBus that answers from a recording: each send/receive is checked
// against the next recorded call of its ReplayStream and returns what the
// real bus returned then. On a divergence (or past the end of the stream)
// every call returns kClosed, as a bus that went away; the stream holds the
// report. Never blocks or allocates.
#include <cstdint>

#include "hal/can_bus.hpp"
#include "hal/replay/replay_stream.hpp"

namespace rtfuse::hal::replay {

class ReplayCanBus final : public CanBus {
 public:
  // Before its first call the bus reports the state recorded with this
  // device's first event: the state before a call was not recorded, and the
  // one after the first call is the closest the log has.
  ReplayCanBus(ReplayStream& stream, std::uint8_t device) noexcept;

  HalStatus send(const CanFrame& frame) noexcept override;
  // Caps max at kBusEventMaxFrames, as the recording decorator did.
  int receive(CanFrame* out, int max, TimeNs timeout_ns, HalStatus* status) noexcept override;
  CanBusState state() const noexcept override { return state_; }
  // The recorded status's text, or the divergence report.
  const char* last_error() const noexcept override;

  std::uint8_t device() const noexcept { return device_; }

 private:
  ReplayStream& stream_;
  std::uint8_t device_;
  CanBusState state_ = CanBusState::kUnknown;
  HalStatus last_status_ = HalStatus::kOk;
};

}  // namespace rtfuse::hal::replay
