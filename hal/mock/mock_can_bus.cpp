#include "hal/mock/mock_can_bus.hpp"

#include <algorithm>

namespace rtfuse::hal::mock {

namespace {
// A zero-capacity ring would need a special case on every path.
int at_least_one(int n) { return n < 1 ? 1 : n; }
}  // namespace

MockCanBus::MockCanBus(MockCanBusCapacity capacity, const Clock* clock)
    : clock_(clock),
      rx_(new CanFrame[static_cast<std::size_t>(at_least_one(capacity.rx_frames))]),
      rx_capacity_(at_least_one(capacity.rx_frames)),
      sent_(new CanFrame[static_cast<std::size_t>(at_least_one(capacity.sent_frames))]),
      sent_capacity_(at_least_one(capacity.sent_frames)),
      nodes_(new CanNode*[static_cast<std::size_t>(at_least_one(capacity.nodes))]),
      node_capacity_(at_least_one(capacity.nodes)) {}

MockCanBus::~MockCanBus() = default;

TimeNs MockCanBus::now() const noexcept { return clock_ != nullptr ? clock_->now() : manual_now_; }

void MockCanBus::set_time(TimeNs t) noexcept {
  manual_now_ = t;
  advance_nodes_to(now());
}

void MockCanBus::advance_nodes_to(TimeNs t) noexcept {
  for (int i = 0; i < node_count_; ++i) nodes_[i]->advance(t, *this);
}

bool MockCanBus::attach(CanNode& node) noexcept {
  for (int i = 0; i < node_count_; ++i) {
    if (nodes_[i] == &node) return false;
  }
  if (node_count_ == node_capacity_) return false;
  nodes_[node_count_++] = &node;
  node.advance(now(), *this);
  return true;
}

void MockCanBus::detach(CanNode& node) noexcept {
  for (int i = 0; i < node_count_; ++i) {
    if (nodes_[i] == &node) {
      // Keep attach order: nodes answering the same frame answer in that order.
      for (int j = i + 1; j < node_count_; ++j) nodes_[j - 1] = nodes_[j];
      --node_count_;
      return;
    }
  }
}

bool MockCanBus::inject_at(const CanFrame& frame, TimeNs stamp) noexcept {
  if (rx_count_ == rx_capacity_) {
    ++rx_dropped_;
    return false;
  }
  CanFrame& slot = rx_[(rx_head_ + rx_count_) % rx_capacity_];
  slot = frame;
  slot.stamp = stamp;
  ++rx_count_;
  return true;
}

const CanFrame& MockCanBus::sent(int i) const noexcept {
  static const CanFrame kNone{};
  if (i < 0 || i >= sent_count_) return kNone;
  return sent_[(sent_head_ + i) % sent_capacity_];
}

void MockCanBus::clear_sent() noexcept {
  sent_head_ = 0;
  sent_count_ = 0;
}

void MockCanBus::fail_next_send(HalStatus status, int count) noexcept {
  fail_status_ = status;
  fail_count_ = status == HalStatus::kOk ? 0 : std::max(count, 0);
}

HalStatus MockCanBus::send(const CanFrame& frame) noexcept {
  const TimeNs t = now();
  advance_nodes_to(t);
  if (fail_count_ > 0) {
    --fail_count_;
    last_error_ = "mock: injected send failure";
    return fail_status_;
  }
  if (state_ == CanBusState::kBusOff) {
    last_error_ = "mock: bus-off";
    return HalStatus::kBusError;
  }
  if (frame.dlc > 8) {
    // SocketCAN refuses a classic frame longer than 8 bytes with EINVAL.
    last_error_ = "mock: dlc > 8";
    return HalStatus::kIoError;
  }
  CanFrame& slot = sent_[(sent_head_ + sent_count_) % sent_capacity_];
  slot = frame;
  slot.stamp = t;
  if (sent_count_ < sent_capacity_) {
    ++sent_count_;
  } else {
    sent_head_ = (sent_head_ + 1) % sent_capacity_;
  }
  ++total_sent_;
  const CanFrame on_wire = slot;  // a node may send, which can overwrite the slot
  for (int i = 0; i < node_count_; ++i) nodes_[i]->on_frame(on_wire, t, *this);
  return HalStatus::kOk;
}

int MockCanBus::drain(CanFrame* out, int max) noexcept {
  const int n = std::min(max, rx_count_);
  for (int i = 0; i < n; ++i) {
    out[i] = rx_[rx_head_];
    rx_head_ = (rx_head_ + 1) % rx_capacity_;
  }
  rx_count_ -= n;
  return n;
}

int MockCanBus::receive(CanFrame* out, int max, TimeNs timeout_ns, HalStatus* status) noexcept {
  HalStatus ignored = HalStatus::kOk;
  HalStatus& st = status != nullptr ? *status : ignored;
  if (out == nullptr || max <= 0) {
    st = HalStatus::kOk;
    return 0;
  }
  advance_nodes_to(now());
  if (rx_count_ == 0 && timeout_ns > 0 && clock_ == nullptr) {
    const TimeNs deadline = manual_now_ + timeout_ns;
    advance_nodes_to(deadline);
    TimeNs latest = manual_now_;
    for (int i = 0; i < rx_count_; ++i) latest = std::max(latest, rx_[(rx_head_ + i) % rx_capacity_].stamp);
    manual_now_ = rx_count_ > 0 ? std::min(latest, deadline) : deadline;
  }
  if (rx_count_ == 0) {
    st = timeout_ns > 0 ? HalStatus::kTimeout : HalStatus::kWouldBlock;
    return 0;
  }
  st = HalStatus::kOk;
  return drain(out, max);
}

}  // namespace rtfuse::hal::mock
