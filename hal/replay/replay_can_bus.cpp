#include "hal/replay/replay_can_bus.hpp"

#include <algorithm>

namespace rtfuse::hal::replay {

ReplayCanBus::ReplayCanBus(ReplayStream& stream, std::uint8_t device) noexcept
    : stream_(stream), device_(device) {
  for (std::size_t i = 0; i < stream.size(); ++i) {
    const BusEvent ev = stream.event(i);
    if (ev.device == device && (ev.kind == BusEventKind::kCanSend || ev.kind == BusEventKind::kCanReceive)) {
      state_ = ev.bus_state;
      break;
    }
  }
}

HalStatus ReplayCanBus::send(const CanFrame& frame) noexcept {
  BusEvent call;
  call.kind = BusEventKind::kCanSend;
  call.device = device_;
  call.count = 1;
  call.frames[0] = frame;
  const BusEvent* rec = stream_.take(call);
  if (rec == nullptr) {
    last_status_ = HalStatus::kClosed;
    return last_status_;
  }
  state_ = rec->bus_state;
  last_status_ = rec->status;
  return last_status_;
}

int ReplayCanBus::receive(CanFrame* out, int max, TimeNs timeout_ns, HalStatus* status) noexcept {
  BusEvent call;
  call.kind = BusEventKind::kCanReceive;
  call.device = device_;
  call.length = std::min(max, kBusEventMaxFrames);
  call.timeout_ns = timeout_ns;
  const BusEvent* rec = stream_.take(call);
  if (rec == nullptr) {
    last_status_ = HalStatus::kClosed;
    if (status != nullptr) *status = last_status_;
    return 0;
  }
  state_ = rec->bus_state;
  last_status_ = rec->status;
  if (status != nullptr) *status = rec->status;
  // The recording kept at most `max` frames (same cap, same max: checked).
  const int n = out == nullptr ? 0 : std::min<int>(rec->count, std::max(call.length, 0));
  for (int i = 0; i < n; ++i) out[i] = rec->frames[i];
  return n;
}

const char* ReplayCanBus::last_error() const noexcept {
  return stream_.diverged() ? stream_.divergence() : to_string(last_status_);
}

}  // namespace rtfuse::hal::replay
