// The EKF's update (a rank-N downdate P - V'V on one triangle, in lane pairs)
// against a straightforward Joseph-form update computed in long double, on
// random states and covariances from well conditioned to condition number
// 1e12, for every fusion-vector size from 1 to 15.
#include <algorithm>
#include <limits>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "estimation/ekf.hpp"
#include "geometry/angles.hpp"
#include "support/random_fusion_subset.hpp"

namespace rtfuse::est {
namespace ekf_update_reference_test {

using MatL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
using VecL = Eigen::Matrix<long double, Eigen::Dynamic, 1>;

// A random orthogonal basis times log-spaced eigenvalues from `scale` down to
// scale / cond: a covariance with exactly that condition number.
StateMatrix covariance_with_condition(std::mt19937& rng, double cond, double scale) {
  std::normal_distribution<double> n(0.0, 1.0);
  StateMatrix g;
  for (int i = 0; i < kStateSize; ++i)
    for (int j = 0; j < kStateSize; ++j) g(i, j) = n(rng);
  const StateMatrix q = Eigen::HouseholderQR<StateMatrix>(g).householderQ();
  StateVector lambda;
  for (int i = 0; i < kStateSize; ++i)
    lambda(i) = scale * std::pow(cond, -static_cast<double>(i) / (kStateSize - 1));
  StateMatrix p = q * lambda.asDiagonal() * q.transpose();
  return (0.5 * (p + p.transpose())).eval();
}

struct Reference {
  VecL x;
  MatL p;
  long double mahalanobis2;
};

// Textbook: K = P H' S^-1, x += K innovation, P = (I-KH) P (I-KH)' + K R K'.
Reference joseph_reference(const StateVector& x, const StateMatrix& p, const Measurement& m,
                           const std::vector<int>& idx) {
  const int n = static_cast<int>(idx.size());
  const MatL pl = p.cast<long double>();
  MatL h = MatL::Zero(n, kStateSize);
  MatL r(n, n);
  VecL innov(n);
  for (int a = 0; a < n; ++a) {
    h(a, idx[a]) = 1.0L;
    // Angle innovations are wrapped, as the filter does (exact in double).
    double d = m.z(idx[a]) - x(idx[a]);
    if (is_angle_index(idx[a])) d = geometry::wrap_angle(d);
    innov(a) = d;
    for (int b = 0; b < n; ++b) r(a, b) = m.covariance(idx[a], idx[b]);
  }
  const MatL s = h * pl * h.transpose() + r;
  const Eigen::LDLT<MatL> ldlt(s);
  const MatL k = ldlt.solve(h * pl).transpose();
  const MatL ikh = MatL::Identity(kStateSize, kStateSize) - k * h;
  Reference ref;
  ref.x = x.cast<long double>() + k * innov;
  ref.p = ikh * pl * ikh.transpose() + k * r * k.transpose();
  ref.mahalanobis2 = innov.dot(ldlt.solve(innov));
  return ref;
}

TEST(EkfUpdateReference, DowndateMatchesLongDoubleJosephAtEverySizeAndConditioning) {
  std::mt19937 rng(2026);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double conds[] = {1.0, 1e3, 1e6, 1e9, 1e12};
  int cases = 0;
  for (double cond : conds) {
    for (int size = 1; size <= kStateSize; ++size) {
      for (int trial = 0; trial < 4; ++trial) {
        const double scale = std::pow(10.0, 4.0 * u(rng) - 2.0);  // 1e-2 .. 1e2
        const StateMatrix p = covariance_with_condition(rng, cond, scale);
        StateVector x;
        for (int i = 0; i < kStateSize; ++i) x(i) = 0.1 * n(rng);

        const std::vector<int> idx = test::random_fusion_subset(rng, size);
        Measurement m;
        for (int i : idx) m.mask |= mask_bit(i);
        for (int i = 0; i < kStateSize; ++i) m.z(i) = x(i) + std::sqrt(p(i, i)) * 0.5 * n(rng);
        // Measurement noise from far below the prior to above it, itself
        // ill-conditioned in half the cases.
        m.covariance = covariance_with_condition(rng, trial % 2 ? cond : 10.0,
                                                 scale * std::pow(10.0, 6.0 * u(rng) - 4.0));

        Ekf ekf;
        ekf.set_state(x);
        ekf.set_covariance(p);
        ekf.set_max_variance(1e30);
        const CorrectResult res = ekf.correct(m);
        ASSERT_EQ(res.outcome, CorrectOutcome::kFused) << "cond " << cond << " size " << size;
        const Reference ref = joseph_reference(x, p, m, idx);

        // Relative to the prior's largest variance, the scale of every entry.
        // The covariance agrees to a few units of round-off at every
        // conditioning (observed at most 1.3e-14). The state moves by the
        // gain times the innovation, and the gain's own sensitivity grows
        // with the conditioning: its bound grows as sqrt(cond) (observed
        // 5e-16 at cond 1, 2e-9 at cond 1e12).
        const long double bound = 5e-14L;
        const long double x_bound = 1e-14L * std::sqrt(static_cast<long double>(cond));
        const long double p_scale = p.diagonal().maxCoeff();
        const MatL got_p = ekf.covariance().cast<long double>();
        const long double p_err = (got_p - ref.p).cwiseAbs().maxCoeff() / p_scale;
        EXPECT_LT(p_err, bound) << "covariance, cond " << cond << " size " << size << " trial " << trial;
        long double x_err = 0.0L;
        for (int i = 0; i < kStateSize; ++i) {
          long double e = ekf.state()(i) - ref.x(i);
          // The filter wraps the angles it returns.
          if (is_angle_index(i)) e = std::remainder(e, 2.0L * 3.14159265358979323846264338327950288L);
          x_err = std::max(x_err, std::abs(e));
        }
        x_err /= std::sqrt(p_scale);
        EXPECT_LT(x_err, x_bound) << "state, cond " << cond << " size " << size << " trial " << trial;
        EXPECT_LT(std::abs(res.squared_mahalanobis - ref.mahalanobis2),
                  1e-9L * std::max(1.0L, ref.mahalanobis2))
            << "cond " << cond << " size " << size;

        // The estimator's guarantees: exactly symmetric, no negative
        // variance, and positive semi-definite up to round-off.
        const StateMatrix got = ekf.covariance();
        EXPECT_EQ(got, got.transpose());
        EXPECT_GE(got.diagonal().minCoeff(), 0.0);
        const double min_eig = Eigen::SelfAdjointEigenSolver<StateMatrix>(got).eigenvalues().minCoeff();
        EXPECT_GE(min_eig, -1e-14 * p_scale) << "cond " << cond << " size " << size;
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 5 * kStateSize * 4);
}

// A variance the downdate would drive below zero is a counted numeric
// rejection that leaves the estimate as it was, never a negative variance in
// P. Round-off after many updates can leave P a few units in the last place
// outside the positive semi-definite cone; here x and y are correlated a
// little more than perfectly (|c| = sqrt(a b) (1 + 4 eps)), so measuring x
// alone would leave y a variance of about -2e-15 b. With c a little under
// sqrt(a b) the same update is fused. (a is large enough that the floored
// R = 1e-9 cannot make up the difference: R / a < 4 eps.)
TEST(EkfUpdateReference, UpdateThatWouldMakeAVarianceNegativeIsRejected) {
  const double eps = std::numeric_limits<double>::epsilon();
  for (double a : {5e7, 3e9, 2e10}) {
    for (double b : {1e-6, 7.0, 5e5}) {
      for (double sign : {1.0, -1.0}) {
        for (double excess : {4.0, -4.0}) {
          StateMatrix p = StateMatrix::Identity();
          p(kX, kX) = a;
          p(kY, kY) = b;
          p(kX, kY) = p(kY, kX) = sign * std::sqrt(a * b) * (1.0 + excess * eps);
          Ekf ekf;
          ekf.set_max_variance(1e30);
          ekf.set_covariance(p);
          Measurement m;
          m.mask = mask_bit(kX);
          m.z(kX) = 0.5 * std::sqrt(a);
          m.covariance = StateMatrix::Identity() * 1e-9;
          const CorrectResult r = ekf.correct(m);
          if (excess > 0.0) {
            EXPECT_EQ(r.outcome, CorrectOutcome::kRejectedNumeric) << "a " << a << " b " << b;
            EXPECT_EQ(ekf.covariance(), p);
            EXPECT_EQ(ekf.state(), StateVector::Zero());
          } else {
            EXPECT_EQ(r.outcome, CorrectOutcome::kFused) << "a " << a << " b " << b;
            EXPECT_GE(ekf.covariance().diagonal().minCoeff(), 0.0);
          }
        }
      }
    }
  }
}

}  // namespace ekf_update_reference_test
}  // namespace rtfuse::est
