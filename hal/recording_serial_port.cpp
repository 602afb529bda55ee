#include "hal/recording_serial_port.hpp"

#include <algorithm>
#include <cstring>

namespace rtfuse::hal {

int RecordingSerialPort::read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp,
                              HalStatus* status) noexcept {
  BusEvent ev;
  ev.kind = BusEventKind::kSerialRead;
  ev.time_ns = clock_ != nullptr ? clock_->now() : 0;
  ev.length = std::clamp(max, 0, kBusEventMaxBytes);
  ev.timeout_ns = timeout_ns;
  TimeNs seen = 0;
  HalStatus st = HalStatus::kOk;
  const int n = inner_.read(out, ev.length, timeout_ns, &seen, &st);
  ev.status = st;
  if (n > 0) {
    // A port returning more than it was asked for would be a backend bug;
    // the event keeps what fits and the caller gets what the event says.
    const int kept = std::min(n, ev.length);
    ev.count = static_cast<std::uint8_t>(kept);
    ev.edge_stamp = seen;
    std::memcpy(ev.data, out, static_cast<std::size_t>(kept));
  }
  tap_.push(ev);
  if (stamp != nullptr) *stamp = ev.edge_stamp;
  if (status != nullptr) *status = ev.status;
  return ev.count;
}

HalStatus RecordingSerialPort::write(const std::uint8_t* data, int size) noexcept {
  HalStatus result = HalStatus::kOk;
  for (int done = 0; done < size && result == HalStatus::kOk; done += kBusEventMaxBytes) {
    BusEvent ev;
    ev.kind = BusEventKind::kSerialWrite;
    ev.time_ns = clock_ != nullptr ? clock_->now() : 0;
    ev.length = std::min(kBusEventMaxBytes, size - done);
    std::memcpy(ev.data, data + done, static_cast<std::size_t>(ev.length));
    ev.status = inner_.write(ev.data, ev.length);
    result = ev.status;
    tap_.push(ev);
  }
  return result;
}

bool RecordingSerialPort::reopen() noexcept {
  BusEvent ev;
  ev.kind = BusEventKind::kSerialReopen;
  ev.time_ns = clock_ != nullptr ? clock_->now() : 0;
  const bool back = inner_.reopen();
  ev.status = back ? HalStatus::kOk : HalStatus::kClosed;
  tap_.push(ev);
  return back;
}

}  // namespace rtfuse::hal
