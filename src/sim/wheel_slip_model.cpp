#include "sim/wheel_slip_model.hpp"

#include <algorithm>
#include <cmath>

#include "sim/counter_rng.hpp"

namespace rtfuse::sim {

namespace {
// Slip changes over tenths of a second; 10 ms knots resolve that, and a
// long run widens the step rather than grow the tables without bound.
constexpr double kSlipKnotStep = 0.01;
constexpr std::size_t kMaxSlipKnots = std::size_t{1} << 18;  // 44 min at 10 ms
}  // namespace

WheelSlipModel::WheelSlipModel(const DriveScenario& sc, double end_s) : end_(end_s) {
  wheel_count_ = std::clamp(sc.robot.wheel_count, 0, kMaxSimWheels);
  for (int w = 0; w < wheel_count_; ++w) wheel_left_[w] = sc.robot.wheels[static_cast<std::size_t>(w)].left;

  const double sigma = sc.slip.noise_fraction;
  const double tau = sc.slip.correlation_time_s;
  if (sigma > 0.0 && std::isfinite(sigma) && tau > 0.0 && end_s > 0.0 && wheel_count_ > 0) {
    noise_step_ = std::max(kSlipKnotStep, end_s / static_cast<double>(kMaxSlipKnots - 2));
    const auto n = static_cast<std::size_t>(std::ceil(end_s / noise_step_)) + 2;
    // First-order Gauss-Markov, started in its stationary distribution.
    const double a = std::exp(-noise_step_ / tau);
    const double b = sigma * std::sqrt(1.0 - a * a);
    for (int w = 0; w < wheel_count_; ++w) {
      const std::uint64_t stream = stream::kWheelSlip + static_cast<std::uint64_t>(w);
      std::vector<double>& noise = noise_[w];
      noise.resize(n);
      for (std::size_t k = 0; k < n; ++k) {
        const double white = counter_normal(sc.seed, stream, k);
        noise[k] = k == 0 ? sigma * white : a * noise[k - 1] + b * white;
      }
    }
  }

  episode_count_ = std::clamp(sc.slip.episode_count, 0, kMaxSlipEpisodes);
  for (int i = 0; i < episode_count_; ++i) {
    const SlipEpisode& in = sc.slip.episodes[static_cast<std::size_t>(i)];
    episodes_[i] = Episode{in.start_s, in.start_s + in.duration_s, in.fraction, in.wheel_mask};
  }
}

void WheelSlipModel::locate(double t, std::size_t* k, double* dt) const noexcept {
  const double tc = t > 0.0 ? std::min(t, end_) : 0.0;  // NaN: the start
  *k = std::min(static_cast<std::size_t>(tc / noise_step_), noise_[0].size() - 2);
  *dt = tc - static_cast<double>(*k) * noise_step_;
}

double WheelSlipModel::noise_fraction(int wheel, double t) const noexcept {
  if (!has_noise()) return 0.0;
  std::size_t k = 0;
  double dt = 0.0;
  locate(t, &k, &dt);
  return noise_at(wheel, k, dt);
}

double WheelSlipModel::episode_fraction(int wheel, double t) const noexcept {
  double f = 0.0;
  for (int i = 0; i < episode_count_; ++i) {
    const Episode& e = episodes_[i];
    if ((e.wheel_mask & (1u << wheel)) != 0 && t > e.start && t < e.end) f += e.fraction;
  }
  return f;
}

}  // namespace rtfuse::sim
