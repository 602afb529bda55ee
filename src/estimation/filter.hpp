#pragma once
// The EKF plus robot_localization's time semantics: initialisation from the
// first measurement, predict-then-correct in time order, predict-only after
// a sensor timeout, and re-filtering from history for late measurements.
#include <memory>

#include "estimation/ekf.hpp"
#include "estimation/filter_params.hpp"
#include "estimation/measurement.hpp"

namespace rtfuse::est {

struct ProcessResult {
  CorrectResult correct;
  bool initialized_filter = false;  // this measurement initialised the filter
  bool stale = false;               // older than the history: not fused
  int replayed = 0;                 // measurements re-applied from history
};

class Filter {
 public:
  // Allocates the history once; nothing allocates afterwards.
  explicit Filter(const FilterParams& params);
  ~Filter();
  Filter(const Filter&) = delete;
  Filter& operator=(const Filter&) = delete;

  // Back to the configured start: uninitialised, or at initial_state.
  void reset() noexcept;
  bool initialized() const noexcept { return initialized_; }
  bool has_time() const noexcept { return has_time_; }
  TimeNs last_measurement_time() const noexcept { return last_time_; }
  const StateVector& state() const noexcept { return ekf_.state(); }
  // The estimate as it stood at t, for preparing a measurement stamped t
  // (lever arms, gravity): a late one re-fused from history must be
  // prepared with the state it is fused into, not today's. The newest
  // history entry at or before t; the current state when t is not in the
  // past or there is no such entry.
  const StateVector& state_at(TimeNs t) const noexcept;
  StateMatrix covariance() const noexcept { return ekf_.covariance(); }
  const FilterParams& params() const noexcept { return params_; }

  ProcessResult process(const Measurement& m) noexcept;
  // Predict-only to t when nothing arrived for sensor_timeout (robot_localization
  // keeps the estimate moving this way). Returns true if it predicted.
  bool predict_if_timed_out(TimeNs t) noexcept;
  // The set_pose command: state and covariance replaced, history forgotten.
  void set_pose(TimeNs t, const StateVector& x, const StateMatrix& p) noexcept;

 private:
  struct HistoryEntry;
  ProcessResult process_in_order(const Measurement& m) noexcept;
  ProcessResult process_late(const Measurement& m) noexcept;
  void remember(const Measurement& m) noexcept;
  void prune_history() noexcept;
  HistoryEntry& entry(int i) noexcept;  // 0 = oldest

  FilterParams params_;
  Ekf ekf_;
  bool initialized_ = false;
  bool has_time_ = false;
  TimeNs last_time_ = 0;

  std::unique_ptr<HistoryEntry[]> history_;
  std::unique_ptr<Measurement[]> replay_scratch_;
  int capacity_ = 0;
  int head_ = 0;   // index of the oldest entry
  int count_ = 0;
};

}  // namespace rtfuse::est
