#pragma once
// A SerialPort that answers from a recording: each read is checked against
// the next recorded call of its ReplayStream (max after the recording's cap,
// timeout) and returns the recorded bytes, stamp and status; each write
// (split as the recording split it) must carry the recorded bytes. After a
// divergence every call fails with kClosed. Never blocks or allocates.
#include <cstdint>

#include "hal/replay/replay_stream.hpp"
#include "hal/serial_port.hpp"

namespace rtfuse::hal::replay {

class ReplaySerialPort final : public SerialPort {
 public:
  ReplaySerialPort(ReplayStream& stream, std::uint8_t device) noexcept : stream_(stream), device_(device) {}

  int read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp, HalStatus* status) noexcept override;
  HalStatus write(const std::uint8_t* data, int size) noexcept override;
  const char* last_error() const noexcept override;
  bool reopen() noexcept override;

  std::uint8_t device() const noexcept { return device_; }

 private:
  ReplayStream& stream_;
  std::uint8_t device_;
  HalStatus last_status_ = HalStatus::kOk;
};

}  // namespace rtfuse::hal::replay
