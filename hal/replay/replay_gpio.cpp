#include "hal/replay/replay_gpio.hpp"

namespace rtfuse::hal::replay {

HalStatus ReplayEdgeSource::wait_edge(TimeNs timeout_ns, GpioEdge* out) noexcept {
  BusEvent call;
  call.kind = BusEventKind::kGpioWaitEdge;
  call.device = device_;
  call.timeout_ns = timeout_ns;
  const BusEvent* rec = stream_.take(call);
  if (rec == nullptr) {
    last_status_ = HalStatus::kClosed;
    return last_status_;
  }
  last_status_ = rec->status;
  if (rec->status == HalStatus::kOk && out != nullptr) *out = GpioEdge{rec->edge_stamp, rec->level != 0};
  return rec->status;
}

const char* ReplayEdgeSource::last_error() const noexcept {
  return stream_.diverged() ? stream_.divergence() : to_string(last_status_);
}

HalStatus ReplayGpioOutput::set(bool high) noexcept {
  BusEvent call;
  call.kind = BusEventKind::kGpioSet;
  call.device = device_;
  call.level = high ? 1 : 0;
  const BusEvent* rec = stream_.take(call);
  if (rec == nullptr) {
    last_status_ = HalStatus::kClosed;
    return last_status_;
  }
  last_status_ = rec->status;
  if (rec->status == HalStatus::kOk) level_ = high;
  return rec->status;
}

const char* ReplayGpioOutput::last_error() const noexcept {
  return stream_.diverged() ? stream_.divergence() : to_string(last_status_);
}

}  // namespace rtfuse::hal::replay
