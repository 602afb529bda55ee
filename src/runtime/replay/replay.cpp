#include "runtime/replay/replay.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace rtfuse {
namespace {

class LogSink final : public MessageSink {
 public:
  explicit LogSink(transport::EventLogWriter* out) : out_(out) {}
  bool publish(const char* channel, const std::uint8_t* data, int size, TimeNs now) override {
    ++published;
    if (out_ == nullptr) return true;
    std::string err;
    if (!out_->write(ns_to_utime(now), channel, data, static_cast<std::size_t>(size), &err)) {
      if (error.empty()) error = err;
      return false;
    }
    return true;
  }
  std::int64_t published = 0;
  std::string error;

 private:
  transport::EventLogWriter* out_;
};

}  // namespace

std::unique_ptr<Replay> Replay::create(const RuntimeConfig& cfg, std::string* error) {
  std::unique_ptr<Replay> r(new Replay());
  r->core_ = FusionCore::create(cfg, error);
  if (!r->core_) return nullptr;
  r->publisher_ = std::make_unique<Publisher>(r->core_->config());
  return r;
}

ReplayResult Replay::run(transport::EventLogReader& in, transport::EventLogWriter* out,
                         const std::function<void(const ReplayProgress&)>& progress) {
  ReplayResult result;
  LogSink sink(out);
  const TimeNs period = static_cast<TimeNs>(std::llround(1e9 / core_->config().rate_hz));
  LoopStats loop;
  loop.rate_hz = core_->config().rate_hz;
  loop.period_ns = period;
  Snapshot snap;
  TimeNs first = 0, next_tick = 0, last_event = 0;
  bool started = false;
  ReplayProgress prog;

  auto tick_to = [&](TimeNs t) {
    while (next_tick <= t) {
      ++loop.ticks;
      core_->tick(next_tick, loop);
      core_->snapshot().load(snap);
      publisher_->poll(snap, next_tick, sink);
      next_tick += period;
    }
  };

  transport::LogEvent ev;
  std::string err;
  for (;;) {
    const transport::ReadStatus st = in.next(&ev, &err);
    if (st == transport::ReadStatus::kEnd) break;
    if (st == transport::ReadStatus::kError) {
      result.error = err;
      result.events = prog.events;
      core_->snapshot().load(result.final);
      return result;
    }
    const TimeNs t = utime_to_ns(ev.timestamp_us);
    if (!started) {
      first = t;
      next_tick = t;  // the first tick coincides with the first event
      started = true;
    }
    if (t < last_event) {
      // lcm-logger writes in receive order; a log that goes back in time is
      // not one we can replay deterministically.
      result.error = "log event " + std::to_string(ev.event_number) + " on '" + std::string(ev.channel) +
                     "' goes back in time by " + std::to_string((last_event - t) / 1000) + " us";
      result.events = prog.events;
      return result;
    }
    last_event = t;
    // Ticks strictly before the event run first, as the live loop would have.
    tick_to(t - 1);
    char channel[256];
    const std::size_t n = std::min<std::size_t>(ev.channel.size(), sizeof(channel) - 1);
    std::memcpy(channel, ev.channel.data(), n);
    channel[n] = '\0';
    core_->input().on_message(channel, ev.data, static_cast<int>(ev.size), t);
    ++prog.events;
    prog.log_time = t - first;
    if (progress && prog.events % 1000 == 0) progress(prog);
  }
  // Let the loop see the last inputs, as it would one period later live.
  if (started) tick_to(last_event + period);
  if (progress) progress(prog);
  if (!sink.error.empty()) {
    result.error = "writing the output log: " + sink.error;
    return result;
  }
  result.ok = true;
  result.events = prog.events;
  result.ticks = loop.ticks;
  result.published = sink.published;
  core_->snapshot().load(result.final);
  return result;
}

}  // namespace rtfuse
