// EKF against hand-derived Kalman filter results and textbook forms.
#include "estimation/ekf.hpp"

#include <cmath>
#include <algorithm>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "estimation/motion_model.hpp"
#include "support/alloc_counter.hpp"
#include "support/random_fusion_subset.hpp"
#include "support/eigen_no_malloc.hpp"

namespace rtfuse::est {
namespace ekf_test {

Measurement measure(UpdateMask mask, const StateVector& z, double variance) {
  Measurement m;
  m.mask = mask;
  m.z = z;
  m.covariance = StateMatrix::Identity() * variance;
  return m;
}

TEST(Ekf, ScalarUpdateMatchesSeedEquations) {
  // K = P/(P+R) = 4/5; x = 0 + 0.8 * 5 = 4; P = (1-K) P = 0.8.
  Ekf ekf;
  StateMatrix p = StateMatrix::Identity();
  p(kX, kX) = 4.0;
  ekf.set_covariance(p);
  StateVector z = StateVector::Zero();
  z(kX) = 5.0;
  const CorrectResult r = ekf.correct(measure(mask_bit(kX), z, 1.0));
  ASSERT_EQ(r.outcome, CorrectOutcome::kFused);
  EXPECT_EQ(r.fused_variables, 1);
  EXPECT_NEAR(ekf.state()(kX), 4.0, 1e-12);
  EXPECT_NEAR(ekf.covariance()(kX, kX), 0.8, 1e-12);
  // Variables not measured and not correlated are untouched.
  EXPECT_NEAR(ekf.covariance()(kY, kY), 1.0, 1e-12);
  EXPECT_EQ(ekf.state()(kY), 0.0);
}

TEST(Ekf, CorrelatedVectorUpdateMovesUnmeasuredVariable) {
  // P = [[2,1],[1,3]] over (x, y), measure x = 3 with R = 1:
  // S = 3, K = [2/3, 1/3], x = [2, 1], P = P - K S K' = [[2/3,1/3],[1/3,8/3]].
  Ekf ekf;
  StateMatrix p = StateMatrix::Identity();
  p(kX, kX) = 2.0;
  p(kY, kY) = 3.0;
  p(kX, kY) = p(kY, kX) = 1.0;
  ekf.set_covariance(p);
  StateVector z = StateVector::Zero();
  z(kX) = 3.0;
  ASSERT_EQ(ekf.correct(measure(mask_bit(kX), z, 1.0)).outcome, CorrectOutcome::kFused);
  EXPECT_NEAR(ekf.state()(kX), 2.0, 1e-12);
  EXPECT_NEAR(ekf.state()(kY), 1.0, 1e-12);
  EXPECT_NEAR(ekf.covariance()(kX, kX), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(ekf.covariance()(kX, kY), 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(ekf.covariance()(kY, kX), 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(ekf.covariance()(kY, kY), 8.0 / 3.0, 1e-12);
}

StateMatrix random_spd(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  StateMatrix a;
  for (int i = 0; i < kStateSize; ++i)
    for (int j = 0; j < kStateSize; ++j) a(i, j) = n(rng);
  return a * a.transpose() * 0.1 + StateMatrix::Identity() * 0.05;
}

TEST(Ekf, CorrectMatchesTextbookJosephFormForEverySubsetSize) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int size = 1; size <= kStateSize; ++size) {
    Ekf ekf;
    const StateMatrix p = random_spd(rng);
    StateVector x;
    for (int i = 0; i < kStateSize; ++i) x(i) = 0.1 * n(rng);
    ekf.set_state(x);
    ekf.set_covariance(p);

    // A random subset of `size` variables, correlated measurement noise.
    const std::vector<int> idx = test::random_fusion_subset(rng, size);
    Measurement m;
    for (int i : idx) m.mask |= mask_bit(i);
    for (int i = 0; i < kStateSize; ++i) m.z(i) = x(i) + 0.2 * n(rng);
    m.covariance = random_spd(rng);

    // Textbook: H selection, K = P H' S^-1, P = (I-KH)P(I-KH)' + KRK'.
    Eigen::MatrixXd h = Eigen::MatrixXd::Zero(size, kStateSize);
    Eigen::MatrixXd r(size, size);
    Eigen::VectorXd innov(size);
    for (int a = 0; a < size; ++a) {
      h(a, idx[a]) = 1.0;
      innov(a) = m.z(idx[a]) - x(idx[a]);
      for (int b = 0; b < size; ++b) r(a, b) = m.covariance(idx[a], idx[b]);
    }
    const Eigen::MatrixXd s = h * p * h.transpose() + r;
    const Eigen::MatrixXd k = p * h.transpose() * s.inverse();
    const Eigen::MatrixXd ikh = Eigen::MatrixXd::Identity(kStateSize, kStateSize) - k * h;
    const Eigen::MatrixXd p_expected = ikh * p * ikh.transpose() + k * r * k.transpose();
    Eigen::VectorXd x_expected = x + k * innov;

    const CorrectResult res = ekf.correct(m);
    ASSERT_EQ(res.outcome, CorrectOutcome::kFused) << "size " << size;
    // Angles are wrapped after the update; the perturbations here stay small.
    EXPECT_LT((ekf.state() - x_expected).cwiseAbs().maxCoeff(), 1e-9) << "size " << size;
    EXPECT_LT((ekf.covariance() - p_expected).cwiseAbs().maxCoeff(), 1e-9) << "size " << size;
    EXPECT_EQ(ekf.covariance(), ekf.covariance().transpose()) << "symmetric, size " << size;
    EXPECT_NEAR(res.squared_mahalanobis, innov.dot(s.inverse() * innov), 1e-9);
  }
}

TEST(Ekf, JacobianMatchesNumericDifferentiation) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    StateVector x;
    for (int i = 0; i < kStateSize; ++i) x(i) = u(rng);
    x(kPitch) *= 1.2;  // stay away from the ±pi/2 singularity
    const double dt = 0.05;
    const StateMatrix analytic = motion_model_jacobian_dense(x, dt);
    StateMatrix numeric;
    const double h = 1e-6;
    for (int j = 0; j < kStateSize; ++j) {
      StateVector xp = x, xm = x;
      xp(j) += h;
      xm(j) -= h;
      motion_model_predict(xp, dt);
      motion_model_predict(xm, dt);
      numeric.col(j) = (xp - xm) / (2 * h);
    }
    EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-7) << "trial " << trial;
  }
}

// The predict skips these entries (ekf.cpp); a model change that fills one
// must fail here, not bias the covariance by a skipped term.
TEST(Ekf, JacobianHasTheStructureThePredictSkips) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int trial = 0; trial < 200; ++trial) {
    StateVector x;
    for (int i = 0; i < kStateSize; ++i) x(i) = u(rng);
    x(kPitch) *= 0.45;
    const MotionJacobian j = motion_model_jacobian(x, 0.01 + 0.001 * trial);
    EXPECT_EQ(j.pos_rpy(2, 2), 0.0);
    EXPECT_EQ(j.rpy_rpy(0, 2), 0.0);
    EXPECT_EQ(j.rpy_rpy(1, 2), 0.0);
    EXPECT_EQ(j.rpy_rpy(1, 1), 1.0);
    EXPECT_EQ(j.rpy_rpy(2, 2), 1.0);
    EXPECT_EQ(j.rpy_rate(1, 0), 0.0);
    EXPECT_EQ(j.rpy_rate(2, 0), 0.0);
  }
}

TEST(Ekf, PredictCovarianceEqualsDenseTripleProduct) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  StateVector x;
  for (int i = 0; i < kStateSize; ++i) x(i) = u(rng);
  const StateMatrix p = random_spd(rng);
  StateMatrix q = StateMatrix::Zero();
  for (int i = 0; i < kStateSize; ++i) q(i, i) = 0.01 * (i + 1);
  const double dt = 0.02;

  Ekf ekf;
  ekf.set_state(x);
  ekf.set_covariance(p);
  ekf.set_process_noise(q);
  ekf.predict(dt);

  const StateMatrix f = motion_model_jacobian_dense(x, dt);
  const StateMatrix expected = f * p * f.transpose() + q * dt;
  EXPECT_LT((ekf.covariance() - expected).cwiseAbs().maxCoeff(), 1e-12);
  StateVector x_expected = x;
  motion_model_predict(x_expected, dt);
  wrap_state_angles(x_expected);
  EXPECT_LT((ekf.state() - x_expected).cwiseAbs().maxCoeff(), 1e-15);
}

// The dense-Q path of the predict, with the dynamic scaling of the pose
// block: F P F' + Q dt, Q's pose block times |twist|^2, P exactly symmetric.
TEST(Ekf, PredictWithDenseDynamicNoiseEqualsDenseTripleProduct) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  StateVector x;
  for (int i = 0; i < kStateSize; ++i) x(i) = u(rng);
  const StateMatrix p = random_spd(rng);
  const StateMatrix q = random_spd(rng) * 0.1;
  const double dt = 0.02;

  Ekf ekf;
  ekf.set_state(x);
  ekf.set_covariance(p);
  ekf.set_process_noise(q);
  ekf.set_dynamic_process_noise(true);
  ekf.predict(dt);

  StateVector x_next = x;
  motion_model_predict(x_next, dt);
  const double speed2 = x_next.segment<6>(kVx).squaredNorm();
  StateMatrix scaled_q = q * dt;
  scaled_q.topLeftCorner<6, 6>() *= speed2;
  const StateMatrix f = motion_model_jacobian_dense(x, dt);
  const StateMatrix expected = f * p * f.transpose() + scaled_q;
  EXPECT_LT((ekf.covariance() - expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(ekf.covariance(), ekf.covariance().transpose());
}

// Outside covariances (set_pose, a first measurement, a config) may be
// asymmetric by rounding or by mistake; the filter takes the upper triangle.
TEST(Ekf, CovarianceAndNoiseAreTakenFromTheUpperTriangle) {
  std::mt19937 rng(29);
  StateMatrix p = random_spd(rng);
  StateMatrix q = random_spd(rng) * 0.1;
  const auto from_upper = [](const StateMatrix& m) {
    StateMatrix s = m;
    s.triangularView<Eigen::StrictlyLower>() = m.transpose();
    return s;
  };
  const StateMatrix p_upper = from_upper(p), q_upper = from_upper(q);
  p(7, 2) += 0.5;  // lower triangle only
  q(11, 0) -= 0.25;
  Ekf ekf;
  ekf.set_covariance(p);
  EXPECT_EQ(ekf.covariance(), p_upper);
  ekf.set_process_noise(q);
  ekf.set_covariance(StateMatrix::Zero());
  ekf.predict(1.0);  // F 0 F' = 0: P is Q dt
  EXPECT_EQ(ekf.covariance(), q_upper);
}

TEST(Ekf, ConstantVelocityMotionInTheBodyFrame) {
  // Heading 90 degrees, 1 m/s forward in the body frame: moves along +y.
  Ekf ekf;
  StateVector x = StateVector::Zero();
  x(kYaw) = M_PI / 2;
  x(kVx) = 1.0;
  ekf.set_state(x);
  for (int i = 0; i < 100; ++i) ekf.predict(0.01);
  EXPECT_NEAR(ekf.state()(kX), 0.0, 1e-12);
  EXPECT_NEAR(ekf.state()(kY), 1.0, 1e-12);
}

TEST(Ekf, DynamicProcessNoiseScalesPoseBlockBySpeedSquared) {
  StateMatrix q = StateMatrix::Identity();
  Ekf ekf;
  ekf.set_covariance(StateMatrix::Zero());
  ekf.set_process_noise(q);
  ekf.set_dynamic_process_noise(true);
  StateVector x = StateVector::Zero();
  x(kVx) = 3.0;
  x(kVyaw) = 4.0;  // |twist| = 5
  ekf.set_state(x);
  ekf.predict(0.1);
  EXPECT_NEAR(ekf.covariance()(kZ, kZ), 25.0 * 0.1, 1e-9);
  EXPECT_NEAR(ekf.covariance()(kVz, kVz), 0.1, 1e-12);  // twist block unscaled
}

TEST(Ekf, YawInnovationIsWrapped) {
  Ekf ekf;
  ekf.set_covariance(StateMatrix::Identity());
  StateVector x = StateVector::Zero();
  x(kYaw) = 3.1;
  ekf.set_state(x);
  StateVector z = StateVector::Zero();
  z(kYaw) = -3.1;  // 0.083 rad away across the cut, not 6.2
  ekf.correct(measure(mask_bit(kYaw), z, 1e-9));
  const double expected = -3.1;  // measurement nearly perfect, wrapped into range
  EXPECT_NEAR(ekf.state()(kYaw), expected, 1e-6);
  EXPECT_GE(ekf.state()(kYaw), -M_PI);
  EXPECT_LT(ekf.state()(kYaw), M_PI);
}

TEST(Ekf, MahalanobisGateRejectsOutlierAndKeepsState) {
  Ekf ekf;
  ekf.set_covariance(StateMatrix::Identity());
  StateVector z = StateVector::Zero();
  z(kX) = 10.0;  // S = 2, d^2 = 50
  Measurement m = measure(mask_bit(kX), z, 1.0);
  m.mahalanobis_threshold = 7.0;  // 49 < 50: reject
  CorrectResult r = ekf.correct(m);
  EXPECT_EQ(r.outcome, CorrectOutcome::kRejectedMahalanobis);
  EXPECT_NEAR(r.squared_mahalanobis, 50.0, 1e-12);
  EXPECT_EQ(ekf.state()(kX), 0.0);
  m.mahalanobis_threshold = 7.1;  // 50.41 > 50: accept
  EXPECT_EQ(ekf.correct(m).outcome, CorrectOutcome::kFused);
  EXPECT_NEAR(ekf.state()(kX), 5.0, 1e-12);
}

TEST(Ekf, NanValuesAreSkippedOthersFused) {
  Ekf ekf;
  ekf.set_covariance(StateMatrix::Identity());
  StateVector z = StateVector::Zero();
  z(kX) = std::nan("");
  z(kY) = 2.0;
  const CorrectResult r = ekf.correct(measure(mask_bit(kX) | mask_bit(kY), z, 1.0));
  EXPECT_EQ(r.outcome, CorrectOutcome::kFused);
  EXPECT_EQ(r.fused_variables, 1);
  EXPECT_EQ(ekf.state()(kX), 0.0);
  EXPECT_NEAR(ekf.state()(kY), 1.0, 1e-12);
  EXPECT_TRUE(ekf.state().allFinite());
}

TEST(Ekf, NegativeAndZeroVariancesAreRepairedLikeRobotLocalization) {
  Ekf ekf;
  ekf.set_covariance(StateMatrix::Identity());
  StateVector z = StateVector::Zero();
  z(kX) = 2.0;
  Measurement m = measure(mask_bit(kX), z, 0.0);
  m.covariance(kX, kX) = -1.0;  // taken as +1
  ekf.correct(m);
  EXPECT_NEAR(ekf.state()(kX), 1.0, 1e-12);
  Ekf perfect;
  perfect.set_covariance(StateMatrix::Zero());  // P = 0 and R = 0 would divide by zero
  ASSERT_EQ(perfect.correct(measure(mask_bit(kX), z, 0.0)).outcome, CorrectOutcome::kFused);
  EXPECT_TRUE(perfect.state().allFinite());
}

TEST(Ekf, VarianceIsCappedAndCovarianceStaysPsd) {
  Ekf ekf;
  ekf.set_max_variance(100.0);
  StateMatrix q = StateMatrix::Identity() * 50.0;
  ekf.set_process_noise(q);
  ekf.set_covariance(StateMatrix::Identity());
  for (int i = 0; i < 100; ++i) ekf.predict(1.0);  // would grow without bound
  for (int i = 0; i < kStateSize; ++i) EXPECT_LE(ekf.covariance()(i, i), 100.0 + 1e-9);
  Eigen::SelfAdjointEigenSolver<StateMatrix> es(ekf.covariance());
  EXPECT_GE(es.eigenvalues().minCoeff(), -1e-9);
}

TEST(Ekf, ConflictingYawIsGatedAndReported) {
  Ekf ekf;
  StateMatrix p = StateMatrix::Identity() * 0.01;
  ekf.set_covariance(p);
  StateVector z = StateVector::Zero();
  z(kYaw) = 1.0;  // 10 sigma away
  z(kRoll) = 0.01;
  Measurement m = measure(mask_bit(kYaw) | mask_bit(kRoll), z, 0.0001);
  m.yaw_gate_sigma = 5.0;
  const CorrectResult r = ekf.correct(m);
  EXPECT_TRUE(r.yaw_conflict);
  EXPECT_EQ(r.fused_variables, 1);  // roll fused, yaw dropped
  EXPECT_EQ(ekf.state()(kYaw), 0.0);
  EXPECT_GT(ekf.state()(kRoll), 0.0);
}

TEST(Ekf, PredictAndCorrectDoNotAllocate) {
  Ekf ekf;
  ekf.set_process_noise(StateMatrix::Identity() * 0.01);
  ekf.set_covariance(StateMatrix::Identity());
  StateVector z = StateVector::Constant(0.1);
  test::AllocScope scope;
  test::EigenMallocForbidden eigen_no_malloc;
  for (int size = 1; size <= kStateSize; ++size) {
    ekf.predict(0.01);
    ekf.correct(measure(static_cast<UpdateMask>((1u << size) - 1u), z, 0.5));
  }
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace ekf_test
}  // namespace rtfuse::est
