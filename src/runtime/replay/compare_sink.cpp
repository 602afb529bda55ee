#include "runtime/replay/compare_sink.hpp"

#include <algorithm>
#include <iterator>

namespace rtfuse {

CompareSink::CompareSink(const HalRecording& rec, const RuntimeConfig& cfg, transport::EventLogWriter* out)
    : diagnostics_(cfg.publish.diagnostics_channel.view()), out_(out) {
  const std::string estimate[] = {std::string(cfg.publish.odometry_channel.view()),
                                  std::string(cfg.publish.pose_channel.view()),
                                  std::string(cfg.publish.tf_channel.view()),
                                  std::string(cfg.publish.state_channel.view()),
                                  std::string(cfg.hardware.wheel_odometry.raw_channel.view())};
  for (const RecordedOutput& o : rec.outputs) {
    if (std::find(std::begin(estimate), std::end(estimate), o.channel) != std::end(estimate)) {
      recorded_[o.channel].push_back(&o);
    }
  }
}

bool CompareSink::publish(const char* channel, const std::uint8_t* data, int size, TimeNs now) {
  ++published;
  if (out_ != nullptr && !out_->write(ns_to_utime(now), channel, data, static_cast<std::size_t>(size), &error)) {
    return false;
  }
  if (diagnostics_ == channel) return true;
  auto it = recorded_.find(channel);
  std::size_t& next = next_[channel];
  if (it == recorded_.end() || next >= it->second.size()) return true;  // beyond the recording
  const RecordedOutput& r = *it->second[next++];
  ++compared;
  if (r.bytes.size() == static_cast<std::size_t>(size) && std::equal(r.bytes.begin(), r.bytes.end(), data)) {
    ++identical;
  } else if (first_mismatch.empty()) {
    first_mismatch = "'" + std::string(channel) + "' message " + std::to_string(next - 1) + " (log event " +
                     std::to_string(r.event_number) + "): " + std::to_string(r.bytes.size()) +
                     " bytes recorded, the replay's " + std::to_string(size) + " bytes differ";
  }
  return true;
}

std::int64_t CompareSink::not_reproduced() const {
  std::int64_t n = 0;
  for (const auto& [channel, list] : recorded_) {
    auto it = next_.find(channel);
    const std::size_t used = it == next_.end() ? 0 : it->second;
    n += static_cast<std::int64_t>(list.size() - used);
  }
  return n;
}

}  // namespace rtfuse
