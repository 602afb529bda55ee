#pragma once
// A CAN bus: frames in and out, each received frame with its kernel receive
// time. No device knowledge (that is drivers/).
#include <cstdint>

#include "core/time.hpp"
#include "hal/status.hpp"

namespace rtfuse::hal {

struct CanFrame {
  std::uint32_t id = 0;     // 11-bit, or 29-bit when extended
  bool extended = false;
  bool rtr = false;         // remote transmission request
  bool error = false;       // an error frame: id holds the CAN_ERR_* class bits, data the details
  std::uint8_t dlc = 0;     // 0..8 (classic CAN)
  std::uint8_t data[8] = {};
  TimeNs stamp = 0;         // CLOCK_MONOTONIC ns of reception (kernel time where the backend has it)
};

enum class CanBusState : std::uint8_t { kUnknown, kErrorActive, kErrorWarning, kErrorPassive, kBusOff };

class CanBus {
 public:
  virtual ~CanBus() = default;
  virtual HalStatus send(const CanFrame& frame) noexcept = 0;
  // Up to max frames into out. timeout_ns 0: return at once (kWouldBlock if
  // none); > 0: wait at most that long for the first frame, then take what is
  // queued without waiting. Returns the number of frames; *status says why 0.
  virtual int receive(CanFrame* out, int max, TimeNs timeout_ns, HalStatus* status) noexcept = 0;
  // Error-active/passive/bus-off as the backend last learnt it (error frames).
  virtual CanBusState state() const noexcept = 0;
  // errno text of the last failure, for diagnostics (never allocates to read).
  virtual const char* last_error() const noexcept = 0;
};

}  // namespace rtfuse::hal
