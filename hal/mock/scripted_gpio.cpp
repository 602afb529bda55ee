#include "hal/mock/scripted_gpio.hpp"

#include <algorithm>

namespace rtfuse::hal::mock {

ScriptedEdgeSource::ScriptedEdgeSource(int capacity, const Clock* clock)
    : clock_(clock),
      edges_(new GpioEdge[static_cast<std::size_t>(std::max(capacity, 1))]),
      capacity_(std::max(capacity, 1)) {}

ScriptedEdgeSource::~ScriptedEdgeSource() = default;

bool ScriptedEdgeSource::push(const GpioEdge& edge) noexcept {
  if (count_ == capacity_) {
    ++dropped_;
    return false;
  }
  edges_[(head_ + count_) % capacity_] = edge;
  ++count_;
  return true;
}

void ScriptedEdgeSource::fail_next(HalStatus status, int count) noexcept {
  fail_status_ = status;
  fail_count_ = status == HalStatus::kOk ? 0 : std::max(count, 0);
}

HalStatus ScriptedEdgeSource::wait_edge(TimeNs timeout_ns, GpioEdge* out) noexcept {
  if (fail_count_ > 0) {
    --fail_count_;
    last_error_ = "mock gpio: injected failure";
    return fail_status_;
  }
  if (count_ == 0) return HalStatus::kTimeout;
  const GpioEdge& next = edges_[head_];
  if (clock_ != nullptr && next.stamp > clock_->now() + std::max<TimeNs>(timeout_ns, 0)) return HalStatus::kTimeout;
  if (out != nullptr) *out = next;
  head_ = (head_ + 1) % capacity_;
  --count_;
  ++delivered_;
  return HalStatus::kOk;
}

RecordingGpioOutput::RecordingGpioOutput(int capacity, const Clock* clock)
    : clock_(clock),
      log_(new GpioLevelChange[static_cast<std::size_t>(std::max(capacity, 1))]),
      capacity_(std::max(capacity, 1)) {}

RecordingGpioOutput::~RecordingGpioOutput() = default;

const GpioLevelChange& RecordingGpioOutput::record(int i) const noexcept {
  static const GpioLevelChange kNone{};
  if (i < 0 || i >= count_) return kNone;
  return log_[(head_ + i) % capacity_];
}

void RecordingGpioOutput::fail_next(HalStatus status, int count) noexcept {
  fail_status_ = status;
  fail_count_ = status == HalStatus::kOk ? 0 : std::max(count, 0);
}

HalStatus RecordingGpioOutput::set(bool high) noexcept {
  if (fail_count_ > 0) {
    --fail_count_;
    last_error_ = "mock gpio: injected failure";
    return fail_status_;
  }
  level_ = high;
  log_[(head_ + count_) % capacity_] = GpioLevelChange{high, clock_ != nullptr ? clock_->now() : 0};
  if (count_ < capacity_) {
    ++count_;
  } else {
    head_ = (head_ + 1) % capacity_;
  }
  ++total_;
  return HalStatus::kOk;
}

}  // namespace rtfuse::hal::mock
