#pragma once
// Scripted GPIO: a data-ready line whose edges a test or simulation queues
// ahead of time, and an output that records what the driver set.
// Allocation happens in the constructors only.
#include <cstdint>
#include <memory>

#include "hal/clock.hpp"
#include "hal/gpio.hpp"

namespace rtfuse::hal::mock {

class ScriptedEdgeSource final : public GpioEdgeSource {
 public:
  // Without a clock every queued edge is available at once (a test script).
  // With one, an edge stamped later than now + timeout is not there yet, so a
  // simulation can queue a whole run and the driver sees edges as time goes.
  explicit ScriptedEdgeSource(int capacity = 256, const Clock* clock = nullptr);
  ~ScriptedEdgeSource() override;
  ScriptedEdgeSource(const ScriptedEdgeSource&) = delete;
  ScriptedEdgeSource& operator=(const ScriptedEdgeSource&) = delete;

  // False (and counted) when the queue is full, as the kernel's event buffer
  // drops on overflow.
  bool push(const GpioEdge& edge) noexcept;
  bool push(TimeNs stamp, bool rising = true) noexcept { return push(GpioEdge{stamp, rising}); }
  int pending() const noexcept { return count_; }
  std::int64_t dropped() const noexcept { return dropped_; }
  std::int64_t delivered() const noexcept { return delivered_; }
  void clear() noexcept { head_ = count_ = 0; }
  // The next `count` waits fail with `status` (kClosed: chip removed; kIoError).
  void fail_next(HalStatus status, int count = 1) noexcept;

  // Edges come out in the order pushed; kTimeout when none is due. Never waits.
  HalStatus wait_edge(TimeNs timeout_ns, GpioEdge* out) noexcept override;
  const char* last_error() const noexcept override { return last_error_; }

 private:
  const Clock* clock_;
  std::unique_ptr<GpioEdge[]> edges_;
  int capacity_;
  int head_ = 0;
  int count_ = 0;
  std::int64_t dropped_ = 0;
  std::int64_t delivered_ = 0;
  HalStatus fail_status_ = HalStatus::kOk;
  int fail_count_ = 0;
  const char* last_error_ = "";
};

struct GpioLevelChange {
  bool high = false;
  TimeNs stamp = 0;  // clock time of the set(), 0 without a clock
};

class RecordingGpioOutput final : public GpioOutput {
 public:
  explicit RecordingGpioOutput(int capacity = 256, const Clock* clock = nullptr);
  ~RecordingGpioOutput() override;
  RecordingGpioOutput(const RecordingGpioOutput&) = delete;
  RecordingGpioOutput& operator=(const RecordingGpioOutput&) = delete;

  bool level() const noexcept { return level_; }
  // record(0) is the oldest kept; the log keeps the most recent `capacity`.
  const GpioLevelChange& record(int i) const noexcept;
  int record_count() const noexcept { return count_; }
  std::int64_t total_sets() const noexcept { return total_; }
  void clear() noexcept { head_ = count_ = 0; }
  // The next `count` sets fail with `status`; the level does not change.
  void fail_next(HalStatus status, int count = 1) noexcept;

  HalStatus set(bool high) noexcept override;
  const char* last_error() const noexcept override { return last_error_; }

 private:
  const Clock* clock_;
  std::unique_ptr<GpioLevelChange[]> log_;
  int capacity_;
  int head_ = 0;
  int count_ = 0;
  std::int64_t total_ = 0;
  bool level_ = false;
  HalStatus fail_status_ = HalStatus::kOk;
  int fail_count_ = 0;
  const char* last_error_ = "";
};

}  // namespace rtfuse::hal::mock
