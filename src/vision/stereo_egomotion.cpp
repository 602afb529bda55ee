#include "vision/stereo_egomotion.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <pcg_random.hpp>

namespace rtfuse::vision {
namespace {

using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// A point must be at least this far in front of the cameras to be used
// (a disparity below 0.1 px triangulates beyond any useful range).
constexpr double kMinDisparityPx = 0.1;

struct Rotation {
  Mat3 r, drx, dry, drz;
};

Rotation rotation_and_derivatives(const Vec6& t) noexcept {
  const double ca = std::cos(t[0]), sa = std::sin(t[0]);
  const double cb = std::cos(t[1]), sb = std::sin(t[1]);
  const double cc = std::cos(t[2]), sc = std::sin(t[2]);
  Mat3 rx, ry, rz, drx, dry, drz;
  rx << 1, 0, 0, 0, ca, -sa, 0, sa, ca;
  ry << cb, 0, sb, 0, 1, 0, -sb, 0, cb;
  rz << cc, -sc, 0, sc, cc, 0, 0, 0, 1;
  drx << 0, 0, 0, 0, -sa, -ca, 0, ca, -sa;
  dry << -sb, 0, cb, 0, 0, 0, -cb, 0, -sb;
  drz << -sc, -cc, 0, cc, -sc, 0, 0, 0, 0;
  Rotation out;
  out.r = rx * ry * rz;
  out.drx = drx * ry * rz;
  out.dry = rx * dry * rz;
  out.drz = rx * ry * drz;
  return out;
}

double weight(const StereoCameraModel& cam, const StereoObservation& o, bool reweighting) noexcept {
  return reweighting ? 1.0 / (std::abs(o.u_lc - cam.cu) / std::abs(cam.cu) + 0.05) : 1.0;
}

}  // namespace

Eigen::Matrix4d egomotion_transform(const Vec6& params) noexcept {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t.topLeftCorner<3, 3>() = rotation_and_derivatives(params).r;
  t.topRightCorner<3, 1>() = params.tail<3>();
  return t;
}

StereoEgomotion::StereoEgomotion(int max_matches)
    : capacity_(max_matches),
      points_(new Eigen::Vector3d[static_cast<std::size_t>(std::max(1, max_matches))]),
      candidates_(new int[static_cast<std::size_t>(std::max(1, max_matches))]()),
      current_(new int[static_cast<std::size_t>(std::max(1, max_matches))]()),
      best_(new int[static_cast<std::size_t>(std::max(1, max_matches))]()),
      flags_(new std::uint8_t[static_cast<std::size_t>(std::max(1, max_matches))]()),
      inlier_(new std::uint8_t[static_cast<std::size_t>(std::max(1, max_matches))]()) {}

bool StereoEgomotion::gauss_newton(const StereoCameraModel& cam, const StereoObservation* obs, const int* idx, int n,
                                   Vec6* theta, int max_steps, double eps, bool weighted, Mat6* normal,
                                   double* weighted_sq) noexcept {
  for (int step = 0; step < max_steps; ++step) {
    const Rotation rot = rotation_and_derivatives(*theta);
    const Eigen::Vector3d t = theta->tail<3>();
    Mat6 a = Mat6::Zero();
    Vec6 g = Vec6::Zero();
    double sq = 0.0;
    for (int k = 0; k < n; ++k) {
      const int i = idx[k];
      const StereoObservation& o = obs[i];
      const Eigen::Vector3d& p = points_[static_cast<std::size_t>(i)];
      const Eigen::Vector3d q = rot.r * p + t;
      if (q.z() < 1e-6) return false;  // behind the camera: not a motion this point allows
      const double iz = 1.0 / q.z();
      // Derivatives of q by the six parameters.
      Eigen::Matrix<double, 3, 6> dq;
      dq.col(0) = rot.drx * p;
      dq.col(1) = rot.dry * p;
      dq.col(2) = rot.drz * p;
      dq.rightCols<3>().setIdentity();
      Eigen::Matrix<double, 4, 6> j;
      Eigen::Vector4d r;
      const double ul = cam.f * q.x() * iz + cam.cu, vl = cam.f * q.y() * iz + cam.cv;
      const double ur = cam.f * (q.x() - cam.baseline) * iz + cam.cu;
      for (int c = 0; c < 6; ++c) {
        const double dz = dq(2, c);
        j(0, c) = cam.f * (dq(0, c) * q.z() - q.x() * dz) * iz * iz;
        j(1, c) = cam.f * (dq(1, c) * q.z() - q.y() * dz) * iz * iz;
        j(2, c) = cam.f * (dq(0, c) * q.z() - (q.x() - cam.baseline) * dz) * iz * iz;
        j(3, c) = j(1, c);
      }
      r << o.u_lc - ul, o.v_lc - vl, o.u_rc - ur, o.v_rc - vl;
      const double w = weighted ? weight(cam, o, true) : 1.0;
      const double w2 = w * w;
      a.noalias() += w2 * (j.transpose() * j);
      g.noalias() += w2 * (j.transpose() * r);
      sq += w2 * r.squaredNorm();
    }
    const Eigen::LDLT<Mat6> ldlt(a);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
    const Vec6 delta = ldlt.solve(g);
    if (!delta.allFinite()) return false;
    *theta += delta;
    if (normal != nullptr) *normal = a;
    if (weighted_sq != nullptr) *weighted_sq = sq;
    if (delta.cwiseAbs().maxCoeff() < eps) return true;
  }
  return false;
}

int StereoEgomotion::count_inliers(const StereoCameraModel& cam, const StereoObservation* obs, int n,
                                   const Vec6& theta, double threshold_sq, std::uint8_t* flags, int* list) noexcept {
  const Mat3 r = rotation_and_derivatives(theta).r;
  const Eigen::Vector3d t = theta.tail<3>();
  int count = 0;
  for (int k = 0; k < n; ++k) {
    const int i = candidates_[k];
    const StereoObservation& o = obs[i];
    const Eigen::Vector3d q = r * points_[static_cast<std::size_t>(i)] + t;
    bool in = false;
    if (q.z() > 1e-6) {
      const double iz = 1.0 / q.z();
      const double ul = cam.f * q.x() * iz + cam.cu, vl = cam.f * q.y() * iz + cam.cv;
      const double ur = cam.f * (q.x() - cam.baseline) * iz + cam.cu;
      const double sq = (o.u_lc - ul) * (o.u_lc - ul) + (o.v_lc - vl) * (o.v_lc - vl) +
                        (o.u_rc - ur) * (o.u_rc - ur) + (o.v_rc - vl) * (o.v_rc - vl);
      in = sq < threshold_sq;
    }
    if (flags != nullptr) flags[i] = in ? 1 : 0;
    if (in) list[count++] = i;
  }
  return count;
}

Egomotion StereoEgomotion::estimate(const StereoCameraModel& cam, const StereoObservation* obs, int n_in,
                                    const EgomotionParams& p, std::uint64_t seed) noexcept {
  Egomotion out;
  const int n = std::min(n_in, capacity_);
  out.matches = n;
  std::fill(inlier_.get(), inlier_.get() + std::max(0, n), std::uint8_t{0});
  // Triangulate from the previous pair.
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const StereoObservation& o = obs[i];
    const double d = o.u_lp - o.u_rp;
    if (!(d >= kMinDisparityPx) || !std::isfinite(o.u_lc) || !std::isfinite(o.v_lc) || !std::isfinite(o.u_rc) ||
        !std::isfinite(o.v_rc)) {
      continue;
    }
    const double z = cam.f * cam.baseline / d;
    points_[static_cast<std::size_t>(i)] = {(o.u_lp - cam.cu) * cam.baseline / d, (o.v_lp - cam.cv) * cam.baseline / d, z};
    candidates_[m++] = i;
  }
  if (m < std::max(3, p.min_inliers)) return out;

  const double threshold_sq = p.inlier_threshold_px * p.inlier_threshold_px;
  pcg32 rng(seed, 0x5eed);  // stream fixed: the seed alone picks the sequence
  int best_count = 0;
  Vec6 best = Vec6::Zero();
  int sample[3];
  // Stop once a better set than the best is unlikely to exist: after k
  // samples the chance that none was all inliers is (1 - w^3)^k, w the best
  // set's share of the candidates. With 180 of 250 matches agreeing this
  // is some 30 samples instead of 200; the bound depends only on the counts
  // (plain IEEE products), so it is the same on every architecture.
  int needed = p.ransac_iterations;
  int it = 0;
  for (; it < needed; ++it) {
    // Three distinct candidates: a partial Fisher-Yates on the first three
    // positions, put back afterwards so the candidate order stays fixed.
    for (int s = 0; s < 3; ++s) {
      const int k = s + static_cast<int>(rng(static_cast<std::uint32_t>(m - s)));
      std::swap(candidates_[s], candidates_[k]);
      sample[s] = k;
    }
    int chosen[3] = {candidates_[0], candidates_[1], candidates_[2]};
    for (int s = 2; s >= 0; --s) std::swap(candidates_[s], candidates_[sample[s]]);
    Vec6 theta = Vec6::Zero();
    if (!gauss_newton(cam, obs, chosen, 3, &theta, p.max_gauss_newton_steps, 1e-6, p.reweighting, nullptr, nullptr)) {
      continue;
    }
    const int count = count_inliers(cam, obs, m, theta, threshold_sq, nullptr, current_.get());
    if (count > best_count) {
      best_count = count;
      best = theta;
      std::copy(current_.get(), current_.get() + count, best_.get());
      if (p.ransac_confidence > 0.0) {
        // Powers by multiplication rather than std::log: the same bits on
        // every libm.
        const double w = static_cast<double>(best_count) / m;
        const double miss = 1.0 - w * w * w;
        double chance = 1.0;
        int k = 0;
        while (k < p.ransac_iterations && chance > 1.0 - p.ransac_confidence) chance *= miss, ++k;
        needed = std::min(needed, std::max(p.ransac_min_iterations, k));
      }
    }
  }
  out.iterations = it;
  if (best_count < p.min_inliers) return out;
  // Refine on the inliers, take the inliers again with the better motion,
  // refine once more.
  Vec6 theta = best;
  Mat6 normal;
  double sq = 0.0;
  if (!gauss_newton(cam, obs, best_.get(), best_count, &theta, 100, 1e-9, p.reweighting, nullptr, nullptr)) return out;
  const int count = count_inliers(cam, obs, m, theta, threshold_sq, inlier_.get(), best_.get());
  if (count < p.min_inliers) {
    std::fill(inlier_.get(), inlier_.get() + n, std::uint8_t{0});
    return out;
  }
  if (!gauss_newton(cam, obs, best_.get(), count, &theta, 100, 1e-9, p.reweighting, &normal, &sq)) {
    std::fill(inlier_.get(), inlier_.get() + n, std::uint8_t{0});
    return out;
  }
  out.ok = true;
  out.params = theta;
  out.inliers = count;
  const int residuals = 4 * count;
  const double s2 = residuals > 6 ? sq / (residuals - 6) : sq;
  out.covariance = s2 * normal.ldlt().solve(Mat6::Identity());
  // The unweighted RMS, for diagnostics.
  const Mat3 r = rotation_and_derivatives(theta).r;
  double plain = 0.0;
  for (int k = 0; k < count; ++k) {
    const int i = best_[k];
    const StereoObservation& o = obs[i];
    const Eigen::Vector3d q = r * points_[static_cast<std::size_t>(i)] + theta.tail<3>();
    const double iz = 1.0 / q.z();
    const double ul = cam.f * q.x() * iz + cam.cu, vl = cam.f * q.y() * iz + cam.cv;
    const double ur = cam.f * (q.x() - cam.baseline) * iz + cam.cu;
    plain += (o.u_lc - ul) * (o.u_lc - ul) + (o.v_lc - vl) * (o.v_lc - vl) + (o.u_rc - ur) * (o.u_rc - ur) +
             (o.v_rc - vl) * (o.v_rc - vl);
  }
  out.residual_rms_px = std::sqrt(plain / residuals);
  return out;
}

}  // namespace rtfuse::vision
