// Egomotion from synthetic matches whose motion is known: points in front of
// a KITTI-like stereo camera, projected before and after a motion, with
// pixel noise and a share of wrong matches.
#include "vision/stereo_egomotion.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "support/alloc_counter.hpp"

namespace rtfuse::vision {
namespace stereo_egomotion_test {

using Vec6 = Eigen::Matrix<double, 6, 1>;

const StereoCameraModel kCam{707.0912, 601.8873, 183.1104, 0.5372};

struct Synthetic {
  std::vector<StereoObservation> obs;
  std::vector<bool> good;
};

Synthetic make(const Vec6& motion, int n, double noise_px, double outliers, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-15, 15), uy(-3, 2), uz(4, 40), upx(0, 1226), uvx(0, 370);
  std::normal_distribution<double> nz(0.0, noise_px);
  const Eigen::Matrix4d t = egomotion_transform(motion);
  Synthetic s;
  while (static_cast<int>(s.obs.size()) < n) {
    const Eigen::Vector4d p(ux(rng), uy(rng), uz(rng), 1.0);
    const Eigen::Vector4d q = t * p;
    auto project = [](const Eigen::Vector4d& x, double* ul, double* v, double* ur) {
      *ul = kCam.f * x.x() / x.z() + kCam.cu;
      *v = kCam.f * x.y() / x.z() + kCam.cv;
      *ur = kCam.f * (x.x() - kCam.baseline) / x.z() + kCam.cu;
    };
    StereoObservation o;
    double vr = 0;
    project(p, &o.u_lp, &o.v_lp, &o.u_rp);
    project(q, &o.u_lc, &o.v_lc, &o.u_rc);
    vr = o.v_lc;
    if (o.u_lp < 0 || o.u_lp > 1226 || o.u_lc < 0 || o.u_lc > 1226 || o.u_rc < 0 || q.z() < 1) continue;
    o.u_lp += nz(rng), o.v_lp += nz(rng), o.u_rp += nz(rng);
    o.u_lc += nz(rng), o.v_lc += nz(rng), o.u_rc += nz(rng);
    o.v_rc = vr + nz(rng);
    const bool bad = std::uniform_real_distribution<double>(0, 1)(rng) < outliers;
    if (bad) {  // a wrong match: the current pair somewhere else
      o.u_lc = upx(rng), o.v_lc = uvx(rng);
      o.u_rc = o.u_lc - (o.u_lp - o.u_rp), o.v_rc = o.v_lc;
    }
    s.obs.push_back(o);
    s.good.push_back(!bad);
  }
  return s;
}

Vec6 motion(double rx, double ry, double rz, double tx, double ty, double tz) {
  Vec6 m;
  m << rx, ry, rz, tx, ty, tz;
  return m;
}

TEST(StereoEgomotion, RecoversTheMotionThroughNoiseAndWrongMatches) {
  // A car's frame at 10 Hz: 1 m forward, a slight turn and pitch.
  const Vec6 truth = motion(0.004, -0.02, 0.001, 0.03, -0.01, -1.0);
  const Synthetic s = make(truth, 400, 0.3, 0.3, 1);
  StereoEgomotion ego(1000);
  const Egomotion e = ego.estimate(kCam, s.obs.data(), 400, EgomotionParams{}, 7);
  ASSERT_TRUE(e.ok);
  EXPECT_LT((e.params.head<3>() - truth.head<3>()).cwiseAbs().maxCoeff(), 5e-4);   // rad
  EXPECT_LT((e.params.tail<3>() - truth.tail<3>()).cwiseAbs().maxCoeff(), 0.02);   // m
  // The wrong matches are the ones left out.
  int good_in = 0, bad_in = 0;
  for (int i = 0; i < 400; ++i) {
    if (ego.inlier(i)) ++(s.good[static_cast<std::size_t>(i)] ? good_in : bad_in);
  }
  EXPECT_EQ(bad_in, 0);
  EXPECT_GT(good_in, 250);
  EXPECT_EQ(e.inliers, good_in);
  EXPECT_LT(e.residual_rms_px, 1.0);
  // The covariance is symmetric, positive definite, and its spread covers
  // the error it has.
  EXPECT_TRUE(e.covariance.isApprox(e.covariance.transpose(), 1e-9));
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(e.covariance);
  EXPECT_GT(es.eigenvalues().minCoeff(), 0.0);
  for (int k = 0; k < 6; ++k) EXPECT_LT(std::abs(e.params[k] - truth[k]), 6.0 * std::sqrt(e.covariance(k, k))) << k;
}

// The adaptive stop draws far fewer samples when most matches agree, never
// fewer than the minimum, and finds the motion as well as the full count.
TEST(StereoEgomotion, StopsSamplingWhenAnotherSampleWouldNotHelp) {
  const Vec6 truth = motion(0.004, -0.02, 0.001, 0.03, -0.01, -1.0);
  const Synthetic s = make(truth, 300, 0.3, 0.1, 8);
  StereoEgomotion ego(1000);
  EgomotionParams full;
  full.ransac_confidence = 0.0;
  const Egomotion a = ego.estimate(kCam, s.obs.data(), 300, full, 3);
  const Egomotion b = ego.estimate(kCam, s.obs.data(), 300, EgomotionParams{}, 3);
  ASSERT_TRUE(a.ok);
  ASSERT_TRUE(b.ok);
  EXPECT_EQ(a.iterations, full.ransac_iterations);
  EXPECT_GE(b.iterations, EgomotionParams{}.ransac_min_iterations);
  EXPECT_LT(b.iterations, 60);
  // The refinement starts from another best sample: a borderline match
  // may go either way, the motion stays as close to the truth.
  EXPECT_NEAR(a.inliers, b.inliers, 3);
  EXPECT_LT((b.params.head<3>() - truth.head<3>()).cwiseAbs().maxCoeff(), 5e-4);
  EXPECT_LT((b.params.tail<3>() - truth.tail<3>()).cwiseAbs().maxCoeff(), 0.02);
  EXPECT_LT((a.params - b.params).cwiseAbs().maxCoeff(), 1e-3);
  // Half wrong: more samples are needed.
  const Synthetic worse = make(truth, 300, 0.3, 0.5, 9);
  const Egomotion c = ego.estimate(kCam, worse.obs.data(), 300, EgomotionParams{}, 3);
  ASSERT_TRUE(c.ok);
  EXPECT_GT(c.iterations, b.iterations);
  EXPECT_LT((c.params.head<3>() - truth.head<3>()).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(StereoEgomotion, SameInputSameBitsAndNoAllocation) {
  const Synthetic s = make(motion(0.0, 0.05, 0.0, 0.0, 0.0, -0.5), 300, 0.5, 0.2, 2);
  StereoEgomotion ego(1000);
  const Egomotion a = ego.estimate(kCam, s.obs.data(), 300, EgomotionParams{}, 42);
  Egomotion b;
  {
    test::AllocScope scope;
    b = ego.estimate(kCam, s.obs.data(), 300, EgomotionParams{}, 42);
    EXPECT_EQ(scope.count(), 0u);
  }
  ASSERT_TRUE(a.ok);
  EXPECT_EQ(std::memcmp(a.params.data(), b.params.data(), sizeof(double) * 6), 0);
  EXPECT_EQ(std::memcmp(a.covariance.data(), b.covariance.data(), sizeof(double) * 36), 0);
  EXPECT_EQ(a.inliers, b.inliers);
}

TEST(StereoEgomotion, TooFewOrDegenerateMatchesGiveNoMotion) {
  StereoEgomotion ego(100);
  const Synthetic s = make(motion(0, 0, 0, 0, 0, -1), 5, 0.0, 0.0, 3);
  EXPECT_FALSE(ego.estimate(kCam, s.obs.data(), 5, EgomotionParams{}, 1).ok);
  // Zero or negative disparities cannot be triangulated.
  Synthetic flat = make(motion(0, 0, 0, 0, 0, -1), 50, 0.0, 0.0, 4);
  for (StereoObservation& o : flat.obs) o.u_rp = o.u_lp + 1.0;
  EXPECT_FALSE(ego.estimate(kCam, flat.obs.data(), 50, EgomotionParams{}, 1).ok);
  // NaN in a match is skipped, never spread into the motion.
  Synthetic nan = make(motion(0, 0.01, 0, 0, 0, -1), 100, 0.2, 0.0, 5);
  nan.obs[3].u_lc = std::nan("");
  const Egomotion e = ego.estimate(kCam, nan.obs.data(), 100, EgomotionParams{}, 1);
  ASSERT_TRUE(e.ok);
  EXPECT_TRUE(e.params.allFinite());
  EXPECT_FALSE(ego.inlier(3));
  // All wrong: no consensus worth the name.
  Synthetic junk = make(motion(0, 0, 0, 0, 0, -1), 100, 0.0, 1.0, 6);
  const Egomotion j = ego.estimate(kCam, junk.obs.data(), 100, EgomotionParams{}, 1);
  EXPECT_TRUE(!j.ok || j.inliers < 15) << j.inliers;
}

}  // namespace stereo_egomotion_test
}  // namespace rtfuse::vision
