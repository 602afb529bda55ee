#include "estimation/ekf.hpp"

#include <cmath>

#include "estimation/lanes.hpp"
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

using lanes::D2;
using lanes::load;
using lanes::splat;
using lanes::store;

// A padded column of P: 16 doubles, 8 lane pairs.
constexpr int kRows = kStateSize + 1;
// Rows x..vz: the only rows of the motion Jacobian that are not identity.
constexpr int kMoving = 9;

// Row r < 9 of F applied to a column v of 16 doubles, the terms in a fixed
// order (no contraction, so both architectures round alike).
inline double jacobian_row_times(const MotionJacobian& j, int r, const double* v) noexcept {
  if (r < kRoll) {
    return v[r] + j.pos_rpy(r, 0) * v[kRoll] + j.pos_rpy(r, 1) * v[kPitch] + j.pos_rpy(r, 2) * v[kYaw] +
           j.pos_vel(r, 0) * v[kVx] + j.pos_vel(r, 1) * v[kVy] + j.pos_vel(r, 2) * v[kVz] +
           j.pos_acc(r, 0) * v[kAx] + j.pos_acc(r, 1) * v[kAy] + j.pos_acc(r, 2) * v[kAz];
  }
  if (r < kVx) {
    const int c = r - kRoll;
    return j.rpy_rpy(c, 0) * v[kRoll] + j.rpy_rpy(c, 1) * v[kPitch] + j.rpy_rpy(c, 2) * v[kYaw] +
           j.rpy_rate(c, 0) * v[kVroll] + j.rpy_rate(c, 1) * v[kVpitch] + j.rpy_rate(c, 2) * v[kVyaw];
  }
  return v[r] + j.vel_acc * v[kAx + (r - kVx)];
}

// P <- F P F' on the upper triangle (the caller mirrors it). With A = P F',
// F P F' = F A, and F's rows vroll..az are unit rows, so only two pieces
// of F A need arithmetic:
//  - A itself, of which only columns x..vz differ from P: each is row c of F
//    applied to P's columns, whole columns in lane pairs (~390 two-lane
//    multiply-adds);
//  - the 9 x 9 upper block of rows and columns x..vz, rows of F applied to
//    A's columns (~310 scalar multiply-adds).
// Column b >= vroll needs none: (F A)(a, b) = (F A)(b, a) = A(b, a) because
// row b of F is e_b, and the block vroll..az keeps P's values. Two full
// column passes with a transpose between them did ~860 two-lane
// multiply-adds and 256 strided copies.
void propagate_covariance(Ekf::PaddedMatrix& p, const MotionJacobian& j) noexcept {
  alignas(16) double a[kMoving][kRows];  // columns x..vz of A = P F'
  const double* pc = p.data();
  for (int q = 0; q < kRows; q += 2) {
    const auto at = [&](int col) { return load(pc + col * kRows + q); };
    const D2 rpy[3] = {at(kRoll), at(kPitch), at(kYaw)};
    const D2 vel[3] = {at(kVx), at(kVy), at(kVz)};
    const D2 rate[3] = {at(kVroll), at(kVpitch), at(kVyaw)};
    const D2 acc[3] = {at(kAx), at(kAy), at(kAz)};
    for (int c = 0; c < 3; ++c) {
      D2 s = at(kX + c);
      for (int k = 0; k < 3; ++k) s += splat(j.pos_rpy(c, k)) * rpy[k];
      for (int k = 0; k < 3; ++k) s += splat(j.pos_vel(c, k)) * vel[k];
      for (int k = 0; k < 3; ++k) s += splat(j.pos_acc(c, k)) * acc[k];
      store(a[kX + c] + q, s);
    }
    for (int c = 0; c < 3; ++c) {
      D2 s = splat(j.rpy_rpy(c, 0)) * rpy[0];
      for (int k = 1; k < 3; ++k) s += splat(j.rpy_rpy(c, k)) * rpy[k];
      for (int k = 0; k < 3; ++k) s += splat(j.rpy_rate(c, k)) * rate[k];
      store(a[kRoll + c] + q, s);
    }
    for (int c = 0; c < 3; ++c) store(a[kVx + c] + q, vel[c] + splat(j.vel_acc) * acc[c]);
  }
  double* pm = p.data();
  for (int b = kMoving; b < kStateSize; ++b) {
    for (int r = 0; r < kMoving; ++r) pm[b * kRows + r] = a[r][b];
  }
  for (int b = 0; b < kMoving; ++b) {
    for (int r = 0; r <= b; ++r) pm[b * kRows + r] = jacobian_row_times(j, r, a[b]);
  }
}

}  // namespace

void Ekf::predict(double dt) noexcept {
  if (!(dt > 0.0)) return;
  // The Jacobian is evaluated at the prior state, as robot_localization does.
  const MotionJacobian j = motion_model_step(x_, dt);
  wrap_state_angles(x_);
  propagate_covariance(p_, j);

  add_process_noise(dt);
  condition_covariance();
}

void Ekf::add_process_noise(double dt) noexcept {
  // robot_localization scales the pose block of Q by the squared norm of the
  // full twist (linear and angular together), on both sides.
  const double pose_dt = dynamic_process_noise_ ? x_.segment<6>(kVx).squaredNorm() * dt : dt;
  if (process_noise_diagonal_) {
    // robot_localization configs are nearly always diagonal.
    for (int i = 0; i < kStateSize; ++i) p_(i, i) += process_noise_(i, i) * (i < 6 ? pose_dt : dt);
    return;
  }
  // The upper triangle only; condition_covariance mirrors it. Lane pairs
  // never straddle the pose block's edge at row 6.
  double* pm = p_.data();
  const double* qm = process_noise_.data();
  for (int c = 0; c < kStateSize; ++c) {
    for (int r = 0; r <= c; r += 2) {
      const double f = (c < 6 && r < 6) ? pose_dt : dt;
      store(pm + c * kRows + r, load(pm + c * kRows + r) + load(qm + c * kRows + r) * splat(f));
    }
  }
}

void Ekf::condition_covariance() noexcept {
  // The predict and the update compute the upper triangle only; the mirror
  // makes P exactly symmetric (a copy, no arithmetic), as 2 x 2 blocks so
  // that every access is a lane pair.
  double* pm = p_.data();
  for (int c = 0; c < kRows; c += 2) {
    pm[c * kRows + c + 1] = pm[(c + 1) * kRows + c];
    for (int r = c + 2; r < kRows; r += 2) {
      // Upper block rows c, c+1 of columns r, r+1 -> lower block rows r, r+1
      // of columns c, c+1.
      const D2 u0 = load(pm + r * kRows + c);
      const D2 u1 = load(pm + (r + 1) * kRows + c);
      store(pm + c * kRows + r, D2{u0[0], u1[0]});
      store(pm + (c + 1) * kRows + r, D2{u0[1], u1[1]});
    }
  }
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

// S = L D L' with unit lower L, for a symmetric positive-definite N x N
// matrix, in plain fixed-size loops (Eigen's decompositions dispatch to
// blocked kernels whose set-up dominates at these sizes). LDL' rather than
// Cholesky: no square roots, whose latency would sit on the factorisation's
// serial chain, once per column. Stores 1/D so later steps never divide.
// Returns false when s is not positive definite.
template <int N>
bool factor_ldlt(const Eigen::Matrix<double, N, N>& s, double (&l)[N][N], double (&d_inv)[N]) noexcept {
  double ld[N][N];  // L D, below the diagonal
  for (int j = 0; j < N; ++j) {
    double d = s(j, j);
    for (int k = 0; k < j; ++k) d -= ld[j][k] * l[j][k];
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    d_inv[j] = 1.0 / d;
    for (int i = j + 1; i < N; ++i) {
      double v = s(i, j);
      for (int k = 0; k < j; ++k) v -= ld[i][k] * l[j][k];
      ld[i][j] = v;
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
// With S = L D L' and V = L^-1 H P (N rows of 16 contiguous doubles, since
// row k of H P is column idx[k] of the symmetric P) and W = D^-1 V: the gain
// is K = W' L^-1, the state moves by K innovation = W' z with z = L^-1
// innovation, and the covariance update (I - K H) P = P - W' V is a
// symmetric rank-N downdate, computed on the upper triangle only: ~N x 64
// two-lane multiply-adds, against ~4.8k scalar ones at N = 9 for the Joseph
// form this replaced. The Joseph form also holds for a suboptimal gain,
// which this filter never uses; what it bought, positive semi-definiteness
// under round-off, is checked instead: a variance the downdate would make
// negative (round-off can, when P has drifted an ulp outside the cone or a
// prior variance exceeds the measurement's by ~15 orders of magnitude)
// rejects the update as numeric, a counted outcome, rather than enter P.
template <int N>
CorrectResult Ekf::correct_fixed(const Measurement& m, const int* idx) noexcept {
  using VecN = Eigen::Matrix<double, N, 1>;
  using MatN = Eigen::Matrix<double, N, N>;
  constexpr int kPairs = kRows / 2;

  VecN innovation;
  MatN s;
  for (int a = 0; a < N; ++a) {
    const int ia = idx[a];
    innovation(a) = m.z(ia) - x_(ia);
    if (is_angle_index(ia)) innovation(a) = wrap_angle(innovation(a));
    for (int b = 0; b < N; ++b) s(a, b) = m.covariance(ia, idx[b]) + p_(ia, idx[b]);
    // As robot_localization: negative variances are taken as their magnitude
    // and near-zero ones floored, so a "perfect" sensor cannot make S singular.
    const double r = m.covariance(ia, ia);
    s(a, a) += std::max(std::abs(r), 1e-9) - r;
  }

  CorrectResult result;
  double l[N][N];
  double d_inv[N];
  if (!factor_ldlt<N>(s, l, d_inv)) {
    result.outcome = CorrectOutcome::kRejectedNumeric;
    return result;
  }
  // z = L^-1 innovation; squared Mahalanobis distance = z' D^-1 z.
  double z[N];
  double mahalanobis2 = 0.0;
  for (int k = 0; k < N; ++k) {
    double v = innovation(k);
    for (int j = 0; j < k; ++j) v -= l[k][j] * z[j];
    z[k] = v;
    mahalanobis2 += v * (v * d_inv[k]);
  }
  result.squared_mahalanobis = mahalanobis2;
  if (!std::isfinite(mahalanobis2) || mahalanobis2 >= m.mahalanobis_threshold * m.mahalanobis_threshold) {
    result.outcome = std::isfinite(mahalanobis2) ? CorrectOutcome::kRejectedMahalanobis
                                                 : CorrectOutcome::kRejectedNumeric;
    return result;
  }

  // V = L^-1 H P by forward substitution, a whole row (8 lane pairs, 8
  // independent chains) at a time; W = D^-1 V.
  alignas(16) double v[N][kRows];
  alignas(16) double w[N][kRows];
  double* pm = p_.data();
  for (int k = 0; k < N; ++k) {
    const double* hp = pm + idx[k] * kRows;
    D2 acc[kPairs];
    for (int q = 0; q < kPairs; ++q) acc[q] = load(hp + 2 * q);
    for (int j = 0; j < k; ++j) {
      const D2 f = splat(l[k][j]);
      for (int q = 0; q < kPairs; ++q) acc[q] -= f * load(v[j] + 2 * q);
    }
    const D2 scale = splat(d_inv[k]);
    for (int q = 0; q < kPairs; ++q) {
      store(v[k] + 2 * q, acc[q]);
      store(w[k] + 2 * q, acc[q] * scale);
    }
  }
  // x += W' z.
  alignas(16) double dx[kRows];
  {
    D2 acc[kPairs];
    for (int q = 0; q < kPairs; ++q) acc[q] = load(w[0] + 2 * q) * splat(z[0]);
    for (int k = 1; k < N; ++k) {
      const D2 f = splat(z[k]);
      for (int q = 0; q < kPairs; ++q) acc[q] += load(w[k] + 2 * q) * f;
    }
    for (int q = 0; q < kPairs; ++q) store(dx + 2 * q, acc[q]);
  }
  StateVector x_new;
  for (int i = 0; i < kStateSize; ++i) x_new(i) = x_(i) + dx[i];
  // The new variances, summed in the order the downdate below uses, so the
  // check sees exactly the values that will be stored. Finite sums also
  // bound every off-diagonal term (Cauchy-Schwarz): nothing else can
  // overflow. The padding's variance is 0 - 0 and always passes.
  {
    D2 var[kPairs];
    for (int q = 0; q < kPairs; ++q) var[q] = D2{pm[2 * q * (kRows + 1)], pm[(2 * q + 1) * (kRows + 1)]};
    for (int k = 0; k < N; ++k) {
      for (int q = 0; q < kPairs; ++q) var[q] -= load(w[k] + 2 * q) * load(v[k] + 2 * q);
    }
    bool ok = true;
    for (int q = 0; q < kPairs; ++q) {
      ok = ok && var[q][0] >= 0.0 && std::isfinite(var[q][0]) && var[q][1] >= 0.0 && std::isfinite(var[q][1]);
    }
    if (!ok) {
      result.outcome = CorrectOutcome::kRejectedNumeric;
      return result;
    }
  }
  if (!x_new.allFinite()) {
    result.outcome = CorrectOutcome::kRejectedNumeric;
    return result;
  }
  // P -= W' V on the upper triangle, column by column (a pair may reach one
  // row below the diagonal; the mirror overwrites it).
  for (int c = 0; c < kStateSize; ++c) {
    double* col = pm + c * kRows;
    for (int r = 0; r <= c; r += 2) {
      D2 acc = load(col + r);
      for (int k = 0; k < N; ++k) acc -= load(w[k] + r) * splat(v[k][c]);
      store(col + r, acc);
    }
  }
  x_ = x_new;
  wrap_state_angles(x_);
  condition_covariance();
  result.outcome = CorrectOutcome::kFused;
  result.fused_variables = N;
  return result;
}

}  // namespace rtfuse::est
