#include "estimation/ekf.hpp"

#include <cmath>

#include <Eigen/Cholesky>

#include "estimation/motion_model.hpp"
#include "geometry/angles.hpp"

namespace rtfuse::est {

using geometry::wrap_angle;

void wrap_state_angles(StateVector& x) noexcept {
  x(kRoll) = wrap_angle(x(kRoll));
  x(kPitch) = wrap_angle(x(kPitch));
  x(kYaw) = wrap_angle(x(kYaw));
}

void Ekf::predict(double dt) noexcept {
  if (!(dt > 0.0)) return;
  // The Jacobian is evaluated at the prior state, as robot_localization does.
  const MotionJacobian j = motion_model_jacobian(x_, dt);
  motion_model_predict(x_, dt);
  wrap_state_angles(x_);

  // P <- F P F'. F is identity except rows x..vz, so only those rows (then
  // columns) are touched: ~1.4k multiply-adds instead of ~6.7k for a dense
  // 15x15 triple product.
  StateMatrix m = p_;
  m.middleRows<3>(kX).noalias() += j.pos_rpy * p_.middleRows<3>(kRoll);
  m.middleRows<3>(kX).noalias() += j.pos_vel * p_.middleRows<3>(kVx);
  m.middleRows<3>(kX).noalias() += j.pos_acc * p_.middleRows<3>(kAx);
  m.middleRows<3>(kRoll).noalias() = j.rpy_rpy * p_.middleRows<3>(kRoll);
  m.middleRows<3>(kRoll).noalias() += j.rpy_rate * p_.middleRows<3>(kVroll);
  m.middleRows<3>(kVx) += j.vel_acc * p_.middleRows<3>(kAx);

  p_ = m;
  p_.middleCols<3>(kX).noalias() += m.middleCols<3>(kRoll) * j.pos_rpy.transpose();
  p_.middleCols<3>(kX).noalias() += m.middleCols<3>(kVx) * j.pos_vel.transpose();
  p_.middleCols<3>(kX).noalias() += m.middleCols<3>(kAx) * j.pos_acc.transpose();
  p_.middleCols<3>(kRoll).noalias() = m.middleCols<3>(kRoll) * j.rpy_rpy.transpose();
  p_.middleCols<3>(kRoll).noalias() += m.middleCols<3>(kVroll) * j.rpy_rate.transpose();
  p_.middleCols<3>(kVx) += j.vel_acc * m.middleCols<3>(kAx);

  if (dynamic_process_noise_) {
    // robot_localization scales the pose block of Q by the norm of the full
    // twist (linear and angular together), on both sides.
    const double speed = x_.segment<6>(kVx).norm();
    StateMatrix q = process_noise_;
    q.topLeftCorner<6, 6>() *= speed * speed;
    p_.noalias() += q * dt;
  } else {
    p_.noalias() += process_noise_ * dt;
  }
  condition_covariance();
}

void Ekf::condition_covariance() noexcept {
  // Round-off makes F P F' drift from symmetric; keep it exactly symmetric.
  p_ = 0.5 * (p_ + p_.transpose()).eval();
  // Scaling row and column i by s is a congruence with diag(.., s, ..): it
  // keeps P positive semi-definite while bringing P(i,i) down to the cap.
  for (int i = 0; i < kStateSize; ++i) {
    const double var = p_(i, i);
    if (var > max_variance_) {
      const double s = std::sqrt(max_variance_ / var);
      p_.row(i) *= s;
      p_.col(i) *= s;
    }
  }
}

CorrectResult Ekf::correct(const Measurement& m) noexcept {
  int idx[kStateSize];
  int n = 0;
  bool yaw_conflict = false;
  for (int i = 0; i < kStateSize; ++i) {
    // robot_localization skips NaN values of a measurement and fuses the rest.
    if (!mask_has(m.mask, i) || !std::isfinite(m.z(i))) continue;
    if (i == kYaw && std::isfinite(m.yaw_gate_sigma)) {
      const double innov = wrap_angle(m.z(kYaw) - x_(kYaw));
      const double s = p_(kYaw, kYaw) + std::max(std::abs(m.covariance(kYaw, kYaw)), 1e-9);
      if (innov * innov > m.yaw_gate_sigma * m.yaw_gate_sigma * s) {
        yaw_conflict = true;
        continue;
      }
    }
    idx[n++] = i;
  }
  CorrectResult r;
  switch (n) {
    case 0: r.outcome = CorrectOutcome::kNothingToFuse; break;
    case 1: r = correct_fixed<1>(m, idx); break;
    case 2: r = correct_fixed<2>(m, idx); break;
    case 3: r = correct_fixed<3>(m, idx); break;
    case 4: r = correct_fixed<4>(m, idx); break;
    case 5: r = correct_fixed<5>(m, idx); break;
    case 6: r = correct_fixed<6>(m, idx); break;
    case 7: r = correct_fixed<7>(m, idx); break;
    case 8: r = correct_fixed<8>(m, idx); break;
    case 9: r = correct_fixed<9>(m, idx); break;
    case 10: r = correct_fixed<10>(m, idx); break;
    case 11: r = correct_fixed<11>(m, idx); break;
    case 12: r = correct_fixed<12>(m, idx); break;
    case 13: r = correct_fixed<13>(m, idx); break;
    case 14: r = correct_fixed<14>(m, idx); break;
    default: r = correct_fixed<15>(m, idx); break;
  }
  r.yaw_conflict = yaw_conflict;
  return r;
}

// H is a selection matrix (row a picks state idx[a]), so H P H' and P H' are
// gathers and no H is ever formed. Dispatching on the update size N keeps
// every matrix fixed-size (no Eigen::Dynamic, no allocation).
template <int N>
CorrectResult Ekf::correct_fixed(const Measurement& m, const int* idx) noexcept {
  using VecN = Eigen::Matrix<double, N, 1>;
  using MatN = Eigen::Matrix<double, N, N>;
  using MatXN = Eigen::Matrix<double, kStateSize, N>;

  VecN innovation;
  MatN s;
  MatXN u;  // P H'
  for (int a = 0; a < N; ++a) {
    const int ia = idx[a];
    innovation(a) = m.z(ia) - x_(ia);
    if (is_angle_index(ia)) innovation(a) = wrap_angle(innovation(a));
    u.col(a) = p_.col(ia);
    for (int b = 0; b < N; ++b) s(a, b) = m.covariance(ia, idx[b]);
    // As robot_localization: negative variances are taken as their magnitude
    // and near-zero ones floored, so a "perfect" sensor cannot make S singular.
    s(a, a) = std::max(std::abs(s(a, a)), 1e-9);
  }
  for (int a = 0; a < N; ++a) {
    for (int b = 0; b < N; ++b) s(a, b) += p_(idx[a], idx[b]);
  }

  CorrectResult result;
  const Eigen::LLT<MatN> llt(s);
  if (llt.info() != Eigen::Success) {
    result.outcome = CorrectOutcome::kRejectedNumeric;
    return result;
  }
  const VecN s_inv_innovation = llt.solve(innovation);
  result.squared_mahalanobis = innovation.dot(s_inv_innovation);
  if (!std::isfinite(result.squared_mahalanobis) ||
      result.squared_mahalanobis >= m.mahalanobis_threshold * m.mahalanobis_threshold) {
    result.outcome = std::isfinite(result.squared_mahalanobis)
                         ? CorrectOutcome::kRejectedMahalanobis
                         : CorrectOutcome::kRejectedNumeric;
    return result;
  }

  // K = P H' S^-1, from S K' = H P.
  const Eigen::Matrix<double, N, kStateSize> kt = llt.solve(u.transpose());
  const MatXN k = kt.transpose();

  const StateVector x_new = x_ + k * innovation;
  // Joseph form (I-KH) P (I-KH)' + K R K', expanded for a selection H:
  //   P - K U' - U K' + K S K'  with U = P H', S = H P H' + R.
  // It equals the product form for any gain K (no optimality assumed) and is
  // symmetric by construction as P + B + B' with B = (K S / 2 - U) K'.
  const MatXN w = 0.5 * (k * s) - u;
  const StateMatrix b = w * kt;
  StateMatrix p_new = p_ + b + b.transpose();

  if (!x_new.allFinite() || !p_new.allFinite()) {
    result.outcome = CorrectOutcome::kRejectedNumeric;
    return result;
  }
  x_ = x_new;
  wrap_state_angles(x_);
  p_ = p_new;
  condition_covariance();
  result.outcome = CorrectOutcome::kFused;
  result.fused_variables = N;
  return result;
}

}  // namespace rtfuse::est
