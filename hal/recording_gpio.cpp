#include "hal/recording_gpio.hpp"

namespace rtfuse::hal {

HalStatus RecordingEdgeSource::wait_edge(TimeNs timeout_ns, GpioEdge* out) noexcept {
  BusEvent ev;
  ev.kind = BusEventKind::kGpioWaitEdge;
  ev.time_ns = clock_ != nullptr ? clock_->now() : 0;
  ev.timeout_ns = timeout_ns;
  ev.status = inner_.wait_edge(timeout_ns, out);
  if (ev.status == HalStatus::kOk && out != nullptr) {
    ev.edge_stamp = out->stamp;
    ev.level = out->rising ? 1 : 0;
  }
  tap_.push(ev);
  return ev.status;
}

HalStatus RecordingOutputLine::set(bool high) noexcept {
  BusEvent ev;
  ev.kind = BusEventKind::kGpioSet;
  ev.time_ns = clock_ != nullptr ? clock_->now() : 0;
  ev.level = high ? 1 : 0;
  ev.status = inner_.set(high);
  tap_.push(ev);
  return ev.status;
}

}  // namespace rtfuse::hal
