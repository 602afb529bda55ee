#pragma once
// The static-size EKF over robot_localization's 15 states. Pure math: time
// arrives as an argument, nothing allocates (every matrix is fixed-size).
#include "estimation/measurement.hpp"
#include "estimation/state.hpp"

namespace rtfuse::est {

enum class CorrectOutcome : std::uint8_t {
  kFused,                 // at least one variable fused
  kNothingToFuse,         // empty mask, or every masked value was NaN
  kRejectedMahalanobis,   // innovation beyond the measurement's threshold
  kRejectedNumeric,       // innovation covariance not positive definite, or non-finite result
};

struct CorrectResult {
  CorrectOutcome outcome = CorrectOutcome::kNothingToFuse;
  int fused_variables = 0;
  bool yaw_conflict = false;  // yaw dropped by the yaw conflict gate
  double squared_mahalanobis = 0.0;
};

class Ekf {
 public:
  // Process noise per second (Q·dt is added per prediction).
  void set_process_noise(const StateMatrix& q) noexcept { process_noise_ = q; }
  void set_dynamic_process_noise(bool on) noexcept { dynamic_process_noise_ = on; }
  void set_max_variance(double v) noexcept { max_variance_ = v; }

  void set_state(const StateVector& x) noexcept { x_ = x; }
  void set_covariance(const StateMatrix& p) noexcept { p_ = p; }
  const StateVector& state() const noexcept { return x_; }
  const StateMatrix& covariance() const noexcept { return p_; }

  // x <- f(x, dt); P <- F P F' + Q dt, with P kept symmetric and capped.
  void predict(double dt) noexcept;
  // Sequential update with the masked variables of m; Joseph-form covariance.
  CorrectResult correct(const Measurement& m) noexcept;

 private:
  template <int N>
  CorrectResult correct_fixed(const Measurement& m, const int* idx) noexcept;
  void condition_covariance() noexcept;

  StateVector x_ = StateVector::Zero();
  StateMatrix p_ = StateMatrix::Identity() * 1e-9;
  StateMatrix process_noise_ = StateMatrix::Zero();
  bool dynamic_process_noise_ = false;
  double max_variance_ = 1e6;
};

// Wraps roll, pitch and yaw of x into [-pi, pi).
void wrap_state_angles(StateVector& x) noexcept;

}  // namespace rtfuse::est
