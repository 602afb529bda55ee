#pragma once
// Lockstep replay of an LCM event log through the same FusionCore and
// Publisher as the daemon: the log's event times drive a simulated clock, the
// loop ticks at its configured rate on that clock, and inputs are delivered
// through the same InputRouter. Same log + same config => same bytes out.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "runtime/fusion/fusion_core.hpp"
#include "runtime/pipeline/publisher.hpp"
#include "transport/event_log.hpp"

namespace rtfuse {

struct ReplayProgress {
  std::int64_t events = 0;
  TimeNs log_time = 0;     // since the first event
  std::int64_t bytes_read = 0;
};

struct ReplayResult {
  bool ok = false;
  std::string error;
  std::int64_t events = 0;
  std::int64_t ticks = 0;
  std::int64_t published = 0;
  Snapshot final;
};

class Replay {
 public:
  static std::unique_ptr<Replay> create(const RuntimeConfig& cfg, std::string* error);
  // out may be null (no output log). progress is called every ~1000 events.
  ReplayResult run(transport::EventLogReader& in, transport::EventLogWriter* out,
                   const std::function<void(const ReplayProgress&)>& progress);
  const FusionCore& core() const { return *core_; }

 private:
  Replay() = default;
  std::unique_ptr<FusionCore> core_;
  std::unique_ptr<Publisher> publisher_;
};

}  // namespace rtfuse
