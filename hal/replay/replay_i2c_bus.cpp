#include "hal/replay/replay_i2c_bus.hpp"

#include <cstring>

namespace rtfuse::hal::replay {

const BusEvent* ReplayI2cBus::take(const BusEvent& call) noexcept {
  const BusEvent* rec = stream_.take(call);
  if (rec == nullptr) {
    last_status_ = HalStatus::kClosed;
    return nullptr;
  }
  last_status_ = rec->status;
  retries_ = rec->retries;
  return rec;
}

HalStatus ReplayI2cBus::read_registers(std::uint8_t address, std::uint8_t reg, std::uint8_t* buf, int n) noexcept {
  BusEvent call;
  call.kind = BusEventKind::kI2cRead;
  call.device = device_;
  call.address = address;
  call.reg = reg;
  call.length = n;
  const BusEvent* rec = take(call);
  if (rec == nullptr) return last_status_;
  // As the real bus: buf is written only on kOk.
  if (rec->status == HalStatus::kOk && buf != nullptr && n > 0 && n <= kBusEventMaxBytes) {
    std::memcpy(buf, rec->data, static_cast<std::size_t>(n));
  }
  return rec->status;
}

HalStatus ReplayI2cBus::write_register(std::uint8_t address, std::uint8_t reg, std::uint8_t value) noexcept {
  BusEvent call;
  call.kind = BusEventKind::kI2cWrite;
  call.device = device_;
  call.address = address;
  call.reg = reg;
  call.length = 1;
  call.value = value;
  const BusEvent* rec = take(call);
  return rec == nullptr ? last_status_ : rec->status;
}

const char* ReplayI2cBus::last_error() const noexcept {
  return stream_.diverged() ? stream_.divergence() : to_string(last_status_);
}

}  // namespace rtfuse::hal::replay
