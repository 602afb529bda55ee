#include "hal/replay/replay_serial_port.hpp"

#include <algorithm>
#include <cstring>

namespace rtfuse::hal::replay {

int ReplaySerialPort::read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp,
                           HalStatus* status) noexcept {
  BusEvent call;
  call.kind = BusEventKind::kSerialRead;
  call.device = device_;
  call.length = std::clamp(max, 0, kBusEventMaxBytes);
  call.timeout_ns = timeout_ns;
  const BusEvent* rec = stream_.take(call);
  if (stamp != nullptr) *stamp = 0;
  if (rec == nullptr) {
    last_status_ = HalStatus::kClosed;
    if (status != nullptr) *status = last_status_;
    return 0;
  }
  last_status_ = rec->status;
  if (status != nullptr) *status = rec->status;
  const int n = std::min<int>(rec->count, call.length);
  if (n <= 0) return 0;
  std::memcpy(out, rec->data, static_cast<std::size_t>(n));
  if (stamp != nullptr) *stamp = rec->edge_stamp;
  return n;
}

HalStatus ReplaySerialPort::write(const std::uint8_t* data, int size) noexcept {
  for (int done = 0; done < size; done += kBusEventMaxBytes) {
    BusEvent call;
    call.kind = BusEventKind::kSerialWrite;
    call.device = device_;
    call.length = std::min(kBusEventMaxBytes, size - done);
    std::memcpy(call.data, data + done, static_cast<std::size_t>(call.length));
    const BusEvent* rec = stream_.take(call);
    last_status_ = rec == nullptr ? HalStatus::kClosed : rec->status;
    if (last_status_ != HalStatus::kOk) return last_status_;
  }
  return HalStatus::kOk;
}

bool ReplaySerialPort::reopen() noexcept {
  BusEvent call;
  call.kind = BusEventKind::kSerialReopen;
  call.device = device_;
  const BusEvent* rec = stream_.take(call);
  last_status_ = rec == nullptr ? HalStatus::kClosed : rec->status;
  return last_status_ == HalStatus::kOk;
}

const char* ReplaySerialPort::last_error() const noexcept {
  return stream_.diverged() ? stream_.divergence() : to_string(last_status_);
}

}  // namespace rtfuse::hal::replay
