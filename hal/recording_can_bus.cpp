#include "hal/recording_can_bus.hpp"

#include <algorithm>

namespace rtfuse::hal {

HalStatus RecordingCanBus::send(const CanFrame& frame) noexcept {
  BusEvent ev;
  ev.kind = BusEventKind::kCanSend;
  ev.time_ns = clock_ != nullptr ? clock_->now() : 0;
  ev.status = inner_.send(frame);
  ev.bus_state = inner_.state();
  ev.count = 1;
  ev.frames[0] = frame;
  tap_.push(ev);
  return ev.status;
}

int RecordingCanBus::receive(CanFrame* out, int max, TimeNs timeout_ns, HalStatus* status) noexcept {
  BusEvent ev;
  ev.kind = BusEventKind::kCanReceive;
  ev.time_ns = clock_ != nullptr ? clock_->now() : 0;
  ev.timeout_ns = timeout_ns;
  const int capped = std::min(max, kBusEventMaxFrames);
  ev.length = capped;
  HalStatus st = HalStatus::kOk;
  const int n = inner_.receive(out, capped, timeout_ns, &st);
  if (status != nullptr) *status = st;
  ev.status = st;
  ev.bus_state = inner_.state();
  // A backend returning more than asked (or a negative count) would be a bug
  // there; the record keeps only what fits the call's contract.
  const int kept = out == nullptr ? 0 : std::clamp(n, 0, std::max(capped, 0));
  ev.count = static_cast<std::uint8_t>(kept);
  for (int i = 0; i < kept; ++i) ev.frames[i] = out[i];
  tap_.push(ev);
  return n;
}

}  // namespace rtfuse::hal
