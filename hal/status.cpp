#include "hal/status.hpp"

namespace rtfuse::hal {

const char* to_string(HalStatus s) noexcept {
  switch (s) {
    case HalStatus::kOk: return "ok";
    case HalStatus::kTimeout: return "timeout";
    case HalStatus::kWouldBlock: return "would block";
    case HalStatus::kNack: return "no acknowledge (NACK)";
    case HalStatus::kBusError: return "bus error";
    case HalStatus::kIoError: return "I/O error";
    case HalStatus::kClosed: return "device closed";
    case HalStatus::kMalformed: return "malformed record";
  }
  return "unknown";
}

}  // namespace rtfuse::hal
