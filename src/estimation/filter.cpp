#include "estimation/filter.hpp"

#include <algorithm>

namespace rtfuse::est {

// The filter right after a measurement was fused, and that measurement.
struct Filter::HistoryEntry {
  Measurement measurement;
  StateVector x;
  StateMatrix p;
  TimeNs last_time;
};

Filter::Filter(const FilterParams& params) : params_(params) {
  ekf_.set_process_noise(params.process_noise);
  ekf_.set_dynamic_process_noise(params.dynamic_process_noise);
  ekf_.set_max_variance(params.max_variance);
  if (params.smooth_lagged_data) {
    capacity_ = std::max(params.history_capacity, 1);
    history_ = std::make_unique<HistoryEntry[]>(capacity_);
    replay_scratch_ = std::make_unique<Measurement[]>(capacity_);
  }
  reset();
}

Filter::~Filter() = default;

void Filter::reset() noexcept {
  initialized_ = params_.has_initial_state;
  has_time_ = false;
  last_time_ = 0;
  ekf_.set_state(params_.has_initial_state ? params_.initial_state : StateVector::Zero());
  ekf_.set_covariance(params_.initial_covariance);
  head_ = 0;
  count_ = 0;
}

void Filter::set_pose(TimeNs t, const StateVector& x, const StateMatrix& p) noexcept {
  ekf_.set_state(x);
  ekf_.set_covariance(p);
  initialized_ = true;
  has_time_ = true;
  last_time_ = t;
  head_ = 0;
  count_ = 0;
}

Filter::HistoryEntry& Filter::entry(int i) noexcept { return history_[(head_ + i) % capacity_]; }

ProcessResult Filter::process(const Measurement& m) noexcept {
  if (params_.smooth_lagged_data && has_time_ && m.stamp < last_time_) return process_late(m);
  return process_in_order(m);
}

ProcessResult Filter::process_in_order(const Measurement& m) noexcept {
  ProcessResult r;
  if (!initialized_) {
    // As robot_localization: the first measurement sets the variables it
    // carries (state and their covariance block) without a Kalman update.
    StateVector x = ekf_.state();
    StateMatrix p = ekf_.covariance();
    for (int i = 0; i < kStateSize; ++i) {
      if (!mask_has(m.mask, i) || !std::isfinite(m.z(i))) continue;
      x(i) = m.z(i);
      for (int j = 0; j < kStateSize; ++j) {
        if (mask_has(m.mask, j) && std::isfinite(m.z(j))) p(i, j) = m.covariance(i, j);
      }
    }
    wrap_state_angles(x);
    ekf_.set_state(x);
    ekf_.set_covariance(p);
    initialized_ = true;
    has_time_ = true;
    last_time_ = m.stamp;
    r.initialized_filter = true;
    r.correct.outcome = CorrectOutcome::kFused;
    remember(m);
    return r;
  }
  if (!has_time_) {
    has_time_ = true;
    last_time_ = m.stamp;
  }
  const TimeNs delta = m.stamp - last_time_;
  if (delta > 0) ekf_.predict(ns_to_sec(delta));
  r.correct = ekf_.correct(m);
  // A late measurement without smoothing is fused at the current time and
  // does not move the clock back (robot_localization's behaviour).
  if (delta >= 0) last_time_ = m.stamp;
  remember(m);
  return r;
}

const StateVector& Filter::state_at(TimeNs t) const noexcept {
  if (!params_.smooth_lagged_data || !has_time_ || t >= last_time_) return ekf_.state();
  for (int i = count_ - 1; i >= 0; --i) {
    const HistoryEntry& e = history_[static_cast<std::size_t>((head_ + i) % capacity_)];
    if (e.measurement.stamp <= t) return e.x;
  }
  return ekf_.state();
}

ProcessResult Filter::process_late(const Measurement& m) noexcept {
  // Newest entry at or before the late stamp: the filter as it was then.
  int keep = -1;
  for (int i = count_ - 1; i >= 0; --i) {
    if (entry(i).measurement.stamp <= m.stamp) {
      keep = i;
      break;
    }
  }
  ProcessResult r;
  if (keep < 0 || last_time_ - m.stamp > sec_to_ns(params_.history_length_s)) {
    r.stale = true;
    return r;
  }
  const int n_replay = count_ - keep - 1;
  for (int i = 0; i < n_replay; ++i) replay_scratch_[i] = entry(keep + 1 + i).measurement;
  const HistoryEntry& base = entry(keep);
  ekf_.set_state(base.x);
  ekf_.set_covariance(base.p);
  last_time_ = base.last_time;
  count_ = keep + 1;

  // The late one goes first: everything in the scratch is newer than it.
  r = process_in_order(m);
  for (int i = 0; i < n_replay; ++i) process_in_order(replay_scratch_[i]);
  r.replayed = n_replay;
  return r;
}

void Filter::remember(const Measurement& m) noexcept {
  if (capacity_ == 0) return;
  if (count_ == capacity_) {
    head_ = (head_ + 1) % capacity_;
    --count_;
  }
  HistoryEntry& e = entry(count_);
  e.measurement = m;
  e.x = ekf_.state();
  e.p = ekf_.covariance();
  e.last_time = last_time_;
  ++count_;
  prune_history();
}

void Filter::prune_history() noexcept {
  const TimeNs horizon = last_time_ - sec_to_ns(params_.history_length_s);
  // Keep one entry at or before the horizon so a measurement exactly at the
  // horizon still finds a state to restart from.
  while (count_ > 1 && entry(1).measurement.stamp <= horizon) {
    head_ = (head_ + 1) % capacity_;
    --count_;
  }
}

bool Filter::predict_if_timed_out(TimeNs t) noexcept {
  if (!initialized_ || !has_time_) return false;
  const TimeNs delta = t - last_time_;
  if (delta < sec_to_ns(params_.sensor_timeout_s) || delta <= 0) return false;
  ekf_.predict(ns_to_sec(delta));
  last_time_ = t;
  return true;
}

}  // namespace rtfuse::est
