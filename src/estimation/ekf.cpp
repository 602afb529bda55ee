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

// P <- F P F' + Q on both triangles, P exactly symmetric on entry and on
// exit. With A = P F', F P F' = F A, and F's rows vroll..az are unit rows,
// so the arithmetic is in two pieces:
//  - A's columns x..vz (the others equal P's): rows of F applied to P's
//    columns, whole columns in lane pairs (~280 two-lane multiply-adds);
//  - the 9 x 9 upper block of rows and columns x..vz: rows of F applied to
//    A's columns, also in lane pairs (~130 two-lane multiply-adds), then
//    mirrored.
// Everything else is a copy: rows vroll..az of column b < 9 are A's
// (contiguous), and by symmetry so are row b's columns vroll..az; the block
// vroll..az keeps P's values. Q is added as each entry is written, so P is
// read and written once. kDenseNoise false: Q is diagonal (as
// robot_localization configs nearly always are) and only the diagonal is
// touched. `pose_f` scales Q's pose block, `f` the rest.
template <bool kDenseNoise>
void propagate_covariance(Ekf::PaddedMatrix& p, const MotionJacobian& j, const Ekf::PaddedMatrix& q,
                          double pose_f, double f) noexcept {
  alignas(16) double a[kMoving][kRows];  // columns x..vz of A = P F'
  const double* pc = p.data();
  const D2 half_dt = splat(0.5 * j.vel_acc);
  for (int r = 0; r < kRows; r += 2) {
    const auto at = [&](int col) { return load(pc + col * kRows + r); };
    const D2 rpy[3] = {at(kRoll), at(kPitch), at(kYaw)};
    const D2 rate[3] = {at(kVroll), at(kVpitch), at(kVyaw)};
    D2 vel[3], w[3];
    for (int k = 0; k < 3; ++k) {
      vel[k] = at(kVx + k);
      const D2 acc = at(kAx + k);
      w[k] = vel[k] + half_dt * acc;
      store(a[kVx + k] + r, vel[k] + splat(j.vel_acc) * acc);
    }
    for (int c = 0; c < 2; ++c) {
      store(a[kX + c] + r, at(kX + c) + splat(j.pos_rpy(c, 0)) * rpy[0] + splat(j.pos_rpy(c, 1)) * rpy[1] +
                               splat(j.pos_rpy(c, 2)) * rpy[2] + splat(j.pos_vel(c, 0)) * w[0] +
                               splat(j.pos_vel(c, 1)) * w[1] + splat(j.pos_vel(c, 2)) * w[2]);
    }
    store(a[kZ] + r, at(kZ) + splat(j.pos_rpy(2, 0)) * rpy[0] + splat(j.pos_rpy(2, 1)) * rpy[1] +
                         splat(j.pos_vel(2, 0)) * w[0] + splat(j.pos_vel(2, 1)) * w[1] +
                         splat(j.pos_vel(2, 2)) * w[2]);
    store(a[kRoll] + r, splat(j.rpy_rpy(0, 0)) * rpy[0] + splat(j.rpy_rpy(0, 1)) * rpy[1] +
                            splat(j.rpy_rate(0, 0)) * rate[0] + splat(j.rpy_rate(0, 1)) * rate[1] +
                            splat(j.rpy_rate(0, 2)) * rate[2]);
    store(a[kPitch] + r, rpy[1] + splat(j.rpy_rpy(1, 0)) * rpy[0] + splat(j.rpy_rate(1, 1)) * rate[1] +
                             splat(j.rpy_rate(1, 2)) * rate[2]);
    store(a[kYaw] + r, rpy[2] + splat(j.rpy_rpy(2, 0)) * rpy[0] + splat(j.rpy_rpy(2, 1)) * rpy[1] +
                           splat(j.rpy_rate(2, 1)) * rate[1] + splat(j.rpy_rate(2, 2)) * rate[2]);
  }

  double* pm = p.data();
  const double* qm = q.data();
  const D2 lane_f = splat(f);
  // Rows vroll..az (9..14) are three unaligned lane pairs; row 15 is padding.
  for (int b = kMoving; b < kStateSize; ++b) {
    double* col = pm + b * kRows;
    const double* qcol = qm + b * kRows;
    for (int r = 0; r < kMoving; ++r) col[r] = kDenseNoise ? a[r][b] + qcol[r] * f : a[r][b];
    if (kDenseNoise) {
      for (int r = kMoving; r < kStateSize; r += 2) store(col + r, load(col + r) + load(qcol + r) * lane_f);
    } else {
      col[b] += qcol[b] * f;
    }
  }
  // The 9 x 9 block: (F A)(r, b) for r <= b, column b of it as F's rows
  // applied to A's column b, two rows per lane pair (F's entries paired once
  // per prediction), then mirrored. F's position rows are
  // [I, dR/drpy s, R dt, 0, R dt^2/2]: with w = v[vel] + (dt/2) v[acc] their
  // velocity and acceleration terms are one product R dt w. The pairs skip the
  // Jacobian's structural zeros and ones (motion_model.hpp; a test pins them).
  const auto pair = [](double top, double bottom) { return D2{top, bottom}; };
  D2 xy_rpy[3], xy_w[3], z_w[3], roll_rate[3];
  for (int k = 0; k < 3; ++k) {
    xy_rpy[k] = pair(j.pos_rpy(0, k), j.pos_rpy(1, k));
    xy_w[k] = pair(j.pos_vel(0, k), j.pos_vel(1, k));
    z_w[k] = pair(j.pos_vel(2, k), 0.0);
    roll_rate[k] = pair(0.0, j.rpy_rate(0, k));
  }
  const D2 zr_roll = pair(j.pos_rpy(2, 0), j.rpy_rpy(0, 0));
  const D2 zr_pitch = pair(j.pos_rpy(2, 1), j.rpy_rpy(0, 1));
  const D2 py_roll = pair(j.rpy_rpy(1, 0), j.rpy_rpy(2, 0));
  const D2 py_pitch = pair(0.0, j.rpy_rpy(2, 1));
  const D2 py_vpitch = pair(j.rpy_rate(1, 1), j.rpy_rate(2, 1));
  const D2 py_vyaw = pair(j.rpy_rate(1, 2), j.rpy_rate(2, 2));
  const D2 lane_dt = splat(j.vel_acc);
  for (int b = 0; b < kMoving; ++b) {
    const double* v = a[b];
    double* col = pm + b * kRows;
    const double* qcol = qm + b * kRows;
    const D2 pose_lanes = splat(b < 6 ? pose_f : f);  // rows x..yaw: the pose block if b is in it
    const auto put = [&](int r, D2 e, D2 factor) {
      store(col + r, kDenseNoise ? e + load(qcol + r) * factor : e);
    };
    D2 w[3];
    for (int k = 0; k < 3; ++k) w[k] = splat(v[kVx + k] + 0.5 * j.vel_acc * v[kAx + k]);
    const D2 roll = splat(v[kRoll]);
    const D2 pitch = splat(v[kPitch]);
    put(kX, load(v + kX) + xy_rpy[0] * roll + xy_rpy[1] * pitch + xy_rpy[2] * splat(v[kYaw]) + xy_w[0] * w[0] +
                xy_w[1] * w[1] + xy_w[2] * w[2],
        pose_lanes);
    if (b >= kZ) {
      put(kZ, pair(v[kZ], 0.0) + zr_roll * roll + zr_pitch * pitch + z_w[0] * w[0] + z_w[1] * w[1] + z_w[2] * w[2] +
                  roll_rate[0] * splat(v[kVroll]) + roll_rate[1] * splat(v[kVpitch]) +
                  roll_rate[2] * splat(v[kVyaw]),
          pose_lanes);
    }
    if (b >= kPitch) {
      put(kPitch, load(v + kPitch) + py_roll * roll + py_pitch * pitch + py_vpitch * splat(v[kVpitch]) +
                      py_vyaw * splat(v[kVyaw]),
          pose_lanes);
    }
    // Row pair (vz, vroll) writes vroll too: the copy below overwrites it.
    if (b >= kVx) put(kVx, load(v + kVx) + lane_dt * load(v + kAx), lane_f);
    if (b >= kVz) put(kVz, load(v + kVz) + lane_dt * load(v + kAz), lane_f);
    if (!kDenseNoise) col[b] += qcol[b] * (b < 6 ? pose_f : f);
  }
  for (int b = 1; b < kMoving; ++b) {
    for (int r = 0; r < b; ++r) pm[r * kRows + b] = pm[b * kRows + r];
  }
  // Rows vroll..az of columns x..vz: A's, after the block (see above).
  for (int c = 0; c < kMoving; ++c) {
    double* col = pm + c * kRows;
    const double* qcol = qm + c * kRows;
    for (int r = kMoving; r < kStateSize; r += 2) {
      store(col + r, kDenseNoise ? load(a[c] + r) + load(qcol + r) * lane_f : load(a[c] + r));
    }
  }
}

}  // namespace

void Ekf::predict(double dt) noexcept {
  if (!(dt > 0.0)) return;
  // The Jacobian is evaluated at the prior state, as robot_localization does.
  const MotionJacobian j = motion_model_step(x_, dt);
  wrap_state_angles(x_);
  // robot_localization scales the pose block of Q by the squared norm of the
  // full twist (linear and angular together), taken after the motion step.
  const double pose_dt = dynamic_process_noise_ ? x_.segment<6>(kVx).squaredNorm() * dt : dt;
  if (process_noise_diagonal_) {
    propagate_covariance<false>(p_, j, process_noise_, pose_dt, dt);
  } else {
    propagate_covariance<true>(p_, j, process_noise_, pose_dt, dt);
  }
  cap_variances();
}

void Ekf::set_process_noise(const StateMatrix& q) noexcept {
  // From the upper triangle: the predict adds Q's (r, c) and (c, r) to the
  // two triangles of P, which stay equal only if Q is exactly symmetric.
  process_noise_.setZero();
  for (int c = 0; c < kStateSize; ++c) {
    for (int r = 0; r <= c; ++r) process_noise_(r, c) = process_noise_(c, r) = q(r, c);
  }
  process_noise_diagonal_ = q.isDiagonal(0.0);
}

void Ekf::set_covariance(const StateMatrix& p) noexcept {
  // Symmetric from the upper triangle, like every update of P: the predict
  // copies rather than recomputes the block vroll..az, so symmetry has to
  // hold on entry. A whole copy and the lane mirror: the history's restore
  // pays this, and a triangle loop cost it 8 ns more.
  p_.topLeftCorner<kStateSize, kStateSize>() = p;
  mirror_upper_triangle();
}

void Ekf::condition_covariance() noexcept {
  mirror_upper_triangle();
  cap_variances();
}

void Ekf::mirror_upper_triangle() noexcept {
  // A copy, no arithmetic, so P becomes exactly symmetric; in 2 x 2 blocks so
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
}

void Ekf::cap_variances() noexcept {
  // One pass of compares first: the cap nearly never bites, and a branch per
  // variance through Eigen's indexing cost 4 % of a prediction.
  const double* pm = p_.data();
  bool over = false;
  for (int i = 0; i < kStateSize; ++i) over |= pm[i * (kRows + 1)] > max_variance_;
  if (!over) return;
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
