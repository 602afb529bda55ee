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
  kRejectedNumeric,       // innovation covariance not positive definite, a non-finite
                          // result, or a variance the update would make negative
};

struct CorrectResult {
  CorrectOutcome outcome = CorrectOutcome::kNothingToFuse;
  int fused_variables = 0;
  bool yaw_conflict = false;  // yaw dropped by the yaw conflict gate
  double squared_mahalanobis = 0.0;
};

class Ekf {
 public:
  // P is kept padded to 16 x 16 with a zero last row and column: columns of
  // 16 doubles are whole SSE2/NEON packets, which makes the covariance
  // products ~1.5x faster than with 15 rows. The padding stays exactly zero
  // through every operation, and nothing outside this class sees it.
  using PaddedMatrix = Eigen::Matrix<double, kStateSize + 1, kStateSize + 1>;

  // Process noise per second (Q·dt is added per prediction). Taken from the
  // upper triangle.
  void set_process_noise(const StateMatrix& q) noexcept;
  void set_dynamic_process_noise(bool on) noexcept { dynamic_process_noise_ = on; }
  void set_max_variance(double v) noexcept { max_variance_ = v; }

  void set_state(const StateVector& x) noexcept { x_ = x; }
  // Taken from the upper triangle: P is kept exactly symmetric.
  void set_covariance(const StateMatrix& p) noexcept;
  const StateVector& state() const noexcept { return x_; }
  StateMatrix covariance() const noexcept { return p_.topLeftCorner<kStateSize, kStateSize>(); }
  double variance(int i) const noexcept { return p_(i, i); }

  // x <- f(x, dt); P <- F P F' + Q dt, with P kept symmetric and capped.
  void predict(double dt) noexcept;
  // One update with the masked variables of m: the optimal gain, and the
  // covariance as a rank-N downdate that is checked never to leave a
  // negative variance (see ekf.cpp).
  CorrectResult correct(const Measurement& m) noexcept;

 private:
  template <int N>
  CorrectResult correct_fixed(const Measurement& m, const int* idx) noexcept;
  // The update's epilogue: mirror, then cap.
  void condition_covariance() noexcept;
  void mirror_upper_triangle() noexcept;
  void cap_variances() noexcept;

  StateVector x_ = StateVector::Zero();
  PaddedMatrix p_ = identity_covariance();
  PaddedMatrix process_noise_ = PaddedMatrix::Zero();

  static PaddedMatrix identity_covariance() {
    PaddedMatrix p = PaddedMatrix::Identity() * 1e-9;
    p(kStateSize, kStateSize) = 0.0;
    return p;
  }
  bool dynamic_process_noise_ = false;
  bool process_noise_diagonal_ = true;
  double max_variance_ = 1e6;
};

// Wraps roll, pitch and yaw of x into [-pi, pi).
void wrap_state_angles(StateVector& x) noexcept;

}  // namespace rtfuse::est
