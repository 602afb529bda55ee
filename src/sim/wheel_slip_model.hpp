#pragma once
// A scenario's [slip], shared by the scripted truth (TruthTrajectory) and
// the commanded one (CommandedTruth), so that both slip the same way: per
// wheel, a continuous Gauss-Markov fraction drawn once, at construction,
// from counter-based noise (knots every 10 ms, linear between them), plus
// the scenario's episodes. What the fraction does to the rolled distance
// depends on how the ground speed is known, so each truth integrates it
// itself.
//
// Immutable after construction: any number of threads may read one.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sim/drive_scenario.hpp"

namespace rtfuse::sim {

class WheelSlipModel {
 public:
  struct Episode {
    double start = 0.0, end = 0.0, fraction = 0.0;
    std::uint8_t wheel_mask = 0;
  };

  WheelSlipModel() = default;
  // The noise covers [0, end_s]; later the fraction keeps its value at end_s.
  WheelSlipModel(const DriveScenario& scenario, double end_s);

  int wheel_count() const noexcept { return wheel_count_; }
  bool wheel_left(int wheel) const noexcept { return wheel_left_[wheel]; }
  // False when the scenario has no continuous slip (the fraction is 0).
  bool has_noise() const noexcept { return noise_[0].size() >= 2; }
  double noise_step() const noexcept { return noise_step_; }
  std::size_t knot_count() const noexcept { return noise_[0].size(); }
  // The fraction of `wheel` at knot k (k * noise_step() s).
  double knot(int wheel, std::size_t k) const noexcept { return noise_[wheel][k]; }

  // The knot interval of t (clamped to [0, end]; NaN counts as the start):
  // t lies dt after knot *k, and k + 1 is a knot. has_noise() must be true.
  void locate(double t, std::size_t* k, double* dt) const noexcept;
  // The continuous fraction of `wheel` dt after knot k (linear between knots).
  double noise_at(int wheel, std::size_t k, double dt) const noexcept {
    const std::vector<double>& n = noise_[wheel];
    return n[k] + (n[k + 1] - n[k]) * (dt / noise_step_);
  }
  // The same at time t; 0 without continuous slip.
  double noise_fraction(int wheel, double t) const noexcept;

  int episode_count() const noexcept { return episode_count_; }
  const Episode& episode(int i) const noexcept { return episodes_[i]; }
  // The episodes' fraction of `wheel` at t: those with start < t < end.
  double episode_fraction(int wheel, double t) const noexcept;

 private:
  double end_ = 0.0;
  int wheel_count_ = 0;
  bool wheel_left_[kMaxSimWheels] = {};
  double noise_step_ = 0.01;
  std::vector<double> noise_[kMaxSimWheels];
  int episode_count_ = 0;
  Episode episodes_[kMaxSlipEpisodes];
};

}  // namespace rtfuse::sim
