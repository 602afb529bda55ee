#include "estimation/ekf.hpp"

#include <cmath>


#include "estimation/motion_model.hpp"
#include "geometry/angles.hpp"

namespace rtfuse::est {

using geometry::wrap_angle;

void wrap_state_angles(StateVector& x) noexcept {
  x(kRoll) = wrap_angle(x(kRoll));
  x(kPitch) = wrap_angle(x(kPitch));
  x(kYaw) = wrap_angle(x(kYaw));
}

namespace {

// a <- a F' for the motion Jacobian F, in place. F is identity except rows
// x..vz, so only columns x..vz of a change, each a combination of a few
// columns: column operations on a column-major matrix vectorise, and this is
// ~700 multiply-adds instead of 3375 for a dense product.
void right_multiply_jacobian_transpose(Ekf::PaddedMatrix& a, const MotionJacobian& j) noexcept {
  // Written as whole-column axpys: each column is 16 doubles (8 SSE2 / NEON
  // packets), which Eigen's small lazy products do not exploit as well.
  const Eigen::Matrix<double, kStateSize + 1, 3> rpy = a.middleCols<3>(kRoll);
  for (int c = 0; c < 3; ++c) {
    a.col(kX + c) += rpy.col(0) * j.pos_rpy(c, 0) + rpy.col(1) * j.pos_rpy(c, 1) + rpy.col(2) * j.pos_rpy(c, 2);
    a.col(kX + c) += a.col(kVx) * j.pos_vel(c, 0) + a.col(kVy) * j.pos_vel(c, 1) + a.col(kVz) * j.pos_vel(c, 2);
    a.col(kX + c) += a.col(kAx) * j.pos_acc(c, 0) + a.col(kAy) * j.pos_acc(c, 1) + a.col(kAz) * j.pos_acc(c, 2);
  }
  for (int c = 0; c < 3; ++c) {
    a.col(kRoll + c) = rpy.col(0) * j.rpy_rpy(c, 0) + rpy.col(1) * j.rpy_rpy(c, 1) + rpy.col(2) * j.rpy_rpy(c, 2) +
                       a.col(kVroll) * j.rpy_rate(c, 0) + a.col(kVpitch) * j.rpy_rate(c, 1) +
                       a.col(kVyaw) * j.rpy_rate(c, 2);
  }
  a.middleCols<3>(kVx) += j.vel_acc * a.middleCols<3>(kAx);
}

}  // namespace

void Ekf::predict(double dt) noexcept {
  if (!(dt > 0.0)) return;
  // The Jacobian is evaluated at the prior state, as robot_localization does.
  const MotionJacobian j = motion_model_step(x_, dt);
  wrap_state_angles(x_);

  // F P F' = (P F')' F' because P is symmetric: two passes of column
  // operations with a transpose between them.
  PaddedMatrix a = p_;
  right_multiply_jacobian_transpose(a, j);
  p_ = a.transpose();
  right_multiply_jacobian_transpose(p_, j);

  if (dynamic_process_noise_) {
    // robot_localization scales the pose block of Q by the norm of the full
    // twist (linear and angular together), on both sides.
    const double speed2 = x_.segment<6>(kVx).squaredNorm();
    p_.topLeftCorner<6, 6>() += process_noise_.topLeftCorner<6, 6>() * (speed2 * dt);
    p_.bottomRows<10>() += process_noise_.bottomRows<10>() * dt;
    p_.topRightCorner<6, 10>() += process_noise_.topRightCorner<6, 10>() * dt;
  } else if (process_noise_diagonal_) {
    p_.diagonal() += process_noise_.diagonal() * dt;
  } else {
    p_ += process_noise_ * dt;
  }
  condition_covariance();
}

void Ekf::condition_covariance() noexcept {
  // Round-off makes P drift from symmetric; mirror the upper triangle so it
  // stays exactly symmetric (a copy, no arithmetic).
  p_.triangularView<Eigen::StrictlyLower>() = p_.transpose();
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

namespace {

// Cholesky factor S = L L' of a symmetric positive-definite N x N matrix in
// plain fixed-size loops (Eigen's LLT dispatches to blocked kernels whose set-up
// dominates at these sizes). Stores 1/L(j,j) so later steps never divide.
// Returns false when s is not positive definite.
template <int N>
bool cholesky(const Eigen::Matrix<double, N, N>& s, double (&l)[N][N], double (&d_inv)[N]) noexcept {
  for (int j = 0; j < N; ++j) {
    double d = s(j, j);
    for (int k = 0; k < j; ++k) d -= l[j][k] * l[j][k];
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    l[j][j] = std::sqrt(d);
    d_inv[j] = 1.0 / l[j][j];
    for (int i = j + 1; i < N; ++i) {
      double v = s(i, j);
      for (int k = 0; k < j; ++k) v -= l[i][k] * l[j][k];
      l[i][j] = v * d_inv[j];
    }
  }
  return true;
}

}  // namespace

// H is a selection matrix (row a picks state idx[a]), so H P H' and P H' are
// gathers and no H is ever formed. Dispatching on the update size N keeps
// every matrix fixed-size (no Eigen::Dynamic, no allocation).
//
// With S = L L', everything is done on rows of 16 contiguous doubles (whole
// SSE2/NEON packets, independent lanes): U' (its rows are columns of the
// symmetric P), V' = L^-1 U', K' = L^-T V' = S^-1 U', and (K S)' = L V'.
// No inverse is formed, and the Mahalanobis distance is |L^-1 innovation|^2.
template <int N>
CorrectResult Ekf::correct_fixed(const Measurement& m, const int* idx) noexcept {
  using VecN = Eigen::Matrix<double, N, 1>;
  using MatN = Eigen::Matrix<double, N, N>;
  using RowsN = Eigen::Matrix<double, N, kStateSize + 1, Eigen::RowMajor>;

  VecN innovation;
  MatN s;
  RowsN ut;  // U' = H P
  for (int a = 0; a < N; ++a) {
    const int ia = idx[a];
    innovation(a) = m.z(ia) - x_(ia);
    if (is_angle_index(ia)) innovation(a) = wrap_angle(innovation(a));
    ut.row(a) = p_.col(ia).transpose();
    for (int b = 0; b < N; ++b) s(a, b) = m.covariance(ia, idx[b]) + p_(ia, idx[b]);
    // As robot_localization: negative variances are taken as their magnitude
    // and near-zero ones floored, so a "perfect" sensor cannot make S singular.
    const double r = m.covariance(ia, ia);
    s(a, a) += std::max(std::abs(r), 1e-9) - r;
  }

  CorrectResult result;
  double l[N][N] = {};
  double d_inv[N];
  if (!cholesky<N>(s, l, d_inv)) {
    result.outcome = CorrectOutcome::kRejectedNumeric;
    return result;
  }
  // y = L^-1 innovation; squared Mahalanobis distance = y'y.
  VecN y;
  for (int k = 0; k < N; ++k) {
    double v = innovation(k);
    for (int j = 0; j < k; ++j) v -= l[k][j] * y(j);
    y(k) = v * d_inv[k];
  }
  result.squared_mahalanobis = y.squaredNorm();
  if (!std::isfinite(result.squared_mahalanobis) ||
      result.squared_mahalanobis >= m.mahalanobis_threshold * m.mahalanobis_threshold) {
    result.outcome = std::isfinite(result.squared_mahalanobis)
                         ? CorrectOutcome::kRejectedMahalanobis
                         : CorrectOutcome::kRejectedNumeric;
    return result;
  }

  RowsN vt;  // V' = L^-1 U'
  for (int k = 0; k < N; ++k) {
    vt.row(k) = ut.row(k);
    for (int j = 0; j < k; ++j) vt.row(k) -= l[k][j] * vt.row(j);
    vt.row(k) *= d_inv[k];
  }
  RowsN kt;  // K' = L^-T V'
  for (int k = N - 1; k >= 0; --k) {
    kt.row(k) = vt.row(k);
    for (int j = k + 1; j < N; ++j) kt.row(k) -= l[j][k] * kt.row(j);
    kt.row(k) *= d_inv[k];
  }
  // x += K innovation = V y.
  const StateVector x_new = x_ + (vt.transpose() * y).template head<kStateSize>();

  // Joseph form (I-KH) P (I-KH)' + K R K', expanded for a selection H:
  //   P - K U' - U K' + K S K'  with U = P H', S = H P H' + R.
  // It equals the product form for any gain K (no optimality assumed) and is
  // symmetric by construction as P + B + B' with B = W K', W = K S / 2 - U;
  // here W' = (L V') / 2 - U'.
  RowsN wt;
  for (int k = 0; k < N; ++k) {
    wt.row(k) = -ut.row(k);
    for (int j = 0; j <= k; ++j) wt.row(k) += (0.5 * l[k][j]) * vt.row(j);
  }
  const PaddedMatrix b = wt.transpose().lazyProduct(kt);
  const PaddedMatrix p_new = p_ + b + b.transpose();

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
