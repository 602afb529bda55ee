// Filter time semantics and robot_localization's per-sensor preprocessing.
#include "estimation/filter.hpp"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "estimation/sensor_model.hpp"
#include "geometry/rotation.hpp"

namespace rtfuse::est {
namespace filter_test {

FilterParams params() {
  FilterParams p;
  p.process_noise = StateMatrix::Identity() * 0.01;
  p.initial_covariance = StateMatrix::Identity() * 1e-9;
  return p;
}

Measurement twist_measurement(TimeNs t, double vx, double vyaw) {
  Measurement m;
  m.stamp = t;
  m.part = MeasurementPart::kTwist;
  m.mask = mask_bit(kVx) | mask_bit(kVyaw);
  m.z(kVx) = vx;
  m.z(kVyaw) = vyaw;
  m.covariance(kVx, kVx) = 0.01;
  m.covariance(kVyaw, kVyaw) = 0.01;
  return m;
}

TEST(Filter, FirstMeasurementInitialisesOnlyItsVariables) {
  Filter f(params());
  EXPECT_FALSE(f.initialized());
  const ProcessResult r = f.process(twist_measurement(1'000'000'000, 1.5, 0.2));
  EXPECT_TRUE(r.initialized_filter);
  EXPECT_TRUE(f.initialized());
  EXPECT_EQ(f.state()(kVx), 1.5);
  EXPECT_EQ(f.state()(kVyaw), 0.2);
  EXPECT_EQ(f.state()(kX), 0.0);
  EXPECT_EQ(f.covariance()(kVx, kVx), 0.01);
  EXPECT_EQ(f.covariance()(kX, kX), 1e-9);
  EXPECT_EQ(f.last_measurement_time(), 1'000'000'000);
}

TEST(Filter, InitialStateStartsInitialised) {
  FilterParams p = params();
  p.has_initial_state = true;
  p.initial_state(kX) = 5.0;
  p.initial_state(kVx) = 1.0;
  Filter f(p);
  EXPECT_TRUE(f.initialized());
  f.process(twist_measurement(0, 1.0, 0.0));
  f.process(twist_measurement(1'000'000'000, 1.0, 0.0));
  EXPECT_NEAR(f.state()(kX), 6.0, 1e-6);  // moved 1 m from the initial 5 m
}

TEST(Filter, PredictsToEachMeasurementInTimeOrder) {
  Filter f(params());
  f.process(twist_measurement(0, 1.0, 0.0));
  f.process(twist_measurement(500'000'000, 1.0, 0.0));
  f.process(twist_measurement(1'000'000'000, 1.0, 0.0));
  EXPECT_NEAR(f.state()(kX), 1.0, 1e-3);
}

TEST(Filter, PredictOnlyAfterSensorTimeout) {
  Filter f(params());
  f.process(twist_measurement(0, 2.0, 0.0));
  EXPECT_FALSE(f.predict_if_timed_out(50'000'000));  // 50 ms < 100 ms
  EXPECT_TRUE(f.predict_if_timed_out(500'000'000));
  EXPECT_NEAR(f.state()(kX), 1.0, 1e-9);
  EXPECT_EQ(f.last_measurement_time(), 500'000'000);
}

TEST(Filter, LateMeasurementWithSmoothingEqualsInOrderProcessing) {
  FilterParams p = params();
  p.smooth_lagged_data = true;
  p.history_length_s = 2.0;
  std::vector<Measurement> ms;
  for (int i = 0; i < 20; ++i) ms.push_back(twist_measurement(i * 50'000'000LL, 1.0 + 0.05 * i, 0.1 * std::sin(i)));
  Filter in_order(p), lagged(p);
  for (const auto& m : ms) in_order.process(m);
  // Measurement 12 arrives after 17: history must rewind and re-apply.
  for (int i = 0; i < 20; ++i) {
    if (i == 12) continue;
    lagged.process(ms[i]);
    if (i == 17) {
      const ProcessResult r = lagged.process(ms[12]);
      EXPECT_EQ(r.replayed, 5);
    }
  }
  EXPECT_LT((in_order.state() - lagged.state()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((in_order.covariance() - lagged.covariance()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Filter, MeasurementOlderThanHistoryIsStale) {
  FilterParams p = params();
  p.smooth_lagged_data = true;
  p.history_length_s = 0.5;
  Filter f(p);
  for (int i = 0; i <= 20; ++i) f.process(twist_measurement(i * 100'000'000LL, 1.0, 0.0));
  const StateVector before = f.state();
  const ProcessResult r = f.process(twist_measurement(300'000'000, 9.0, 0.0));  // 1.7 s late
  EXPECT_TRUE(r.stale);
  EXPECT_EQ(f.state(), before);
}

TEST(Filter, SetPoseReplacesStateAndCovariance) {
  Filter f(params());
  f.process(twist_measurement(0, 1.0, 0.0));
  StateVector x = StateVector::Zero();
  x(kX) = 10.0;
  x(kYaw) = 1.0;
  const StateMatrix p = StateMatrix::Identity() * 0.5;
  f.set_pose(2'000'000'000, x, p);
  EXPECT_EQ(f.state(), x);
  EXPECT_EQ(f.covariance(), p);
  EXPECT_EQ(f.last_measurement_time(), 2'000'000'000);
}

// ---- sensor models -------------------------------------------------------

struct Frames {
  geometry::FrameTree tree;
  FusionFrames f;
  Frames(const geometry::RigidTransform& base_T_imu) {
    tree.intern("odom");
    tree.intern("base_link");
    std::string err;
    EXPECT_TRUE(tree.add("base_link", "imu_link", base_T_imu, &err)) << err;
    f.tree = &tree;
    f.world = tree.find("odom");
    f.base_link = tree.find("base_link");
  }
};

SensorParams imu_params() {
  SensorParams s;
  s.kind = SensorKind::kImu;
  s.update_mask = kOrientationMask | kAngularVelocityMask | kAccelerationMask;
  s.remove_gravitational_acceleration = true;
  return s;
}

TEST(SensorModel, RotatedImuGivesTheSameMeasurementsAsAlignedOne) {
  // Body attitude, rates and acceleration the robot really has.
  const Eigen::Quaterniond world_q_base = geometry::quaternion_from_rpy(0.1, -0.05, 0.7);
  const Eigen::Vector3d w_base(0.02, -0.01, 0.3);
  const Eigen::Vector3d a_base(0.5, 0.1, 0.0);
  const Eigen::Vector3d g_base = world_q_base.conjugate() * Eigen::Vector3d(0, 0, 9.80665);

  auto sample_from = [&](const geometry::RigidTransform& base_T_imu, int frame) {
    SensorSample s;
    s.kind = SensorKind::kImu;
    s.frame = static_cast<std::int16_t>(frame);
    const Eigen::Matrix3d imu_R_base = base_T_imu.rotation.conjugate().toRotationMatrix();
    s.imu.has_orientation = s.imu.has_angular_velocity = s.imu.has_linear_acceleration = true;
    s.imu.orientation = world_q_base * base_T_imu.rotation;
    s.imu.angular_velocity = imu_R_base * w_base;
    s.imu.linear_acceleration = imu_R_base * (a_base + g_base);
    s.imu.orientation_covariance = Matrix3::Identity() * 1e-3;
    s.imu.angular_velocity_covariance = Matrix3::Identity() * 1e-4;
    s.imu.linear_acceleration_covariance = Matrix3::Identity() * 1e-2;
    return s;
  };

  geometry::RigidTransform mounted;
  mounted.rotation = geometry::quaternion_from_rpy(M_PI, 0.0, M_PI / 2);  // upside down, turned 90 degrees
  mounted.translation = Eigen::Vector3d(0.1, 0.0, 0.2);
  Frames aligned_frames(geometry::RigidTransform::identity());
  Frames mounted_frames(mounted);

  SensorModel aligned(0, imu_params(), FilterParams()), rotated(0, imu_params(), FilterParams());
  MeasurementBatch a, b;
  const StateVector state = StateVector::Zero();
  ASSERT_EQ(aligned.convert(sample_from(geometry::RigidTransform::identity(), aligned_frames.tree.find("imu_link")),
                            state, aligned_frames.f, &a), SampleRejection::kNone);
  ASSERT_EQ(rotated.convert(sample_from(mounted, mounted_frames.tree.find("imu_link")), state, mounted_frames.f, &b),
            SampleRejection::kNone);
  ASSERT_EQ(a.count, 3);
  ASSERT_EQ(b.count, 3);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(a.items[k].mask, b.items[k].mask);
    EXPECT_LT((a.items[k].z - b.items[k].z).cwiseAbs().maxCoeff(), 1e-9) << "part " << k;
    EXPECT_LT((a.items[k].covariance - b.items[k].covariance).cwiseAbs().maxCoeff(), 1e-12) << "part " << k;
  }
  // And both are the truth, with gravity removed.
  EXPECT_LT((a.items[0].z.segment<3>(kRoll) - Eigen::Vector3d(0.1, -0.05, 0.7)).norm(), 1e-9);
  EXPECT_LT((a.items[1].z.segment<3>(kVroll) - w_base).norm(), 1e-12);
  EXPECT_LT((a.items[2].z.segment<3>(kAx) - a_base).norm(), 1e-9);
}

TEST(SensorModel, OdometryChildFrameOffsetIsCorrectedWithLeverArm) {
  geometry::FrameTree tree;
  tree.intern("odom");
  tree.intern("base_link");
  geometry::RigidTransform base_T_wheel;
  base_T_wheel.translation = Eigen::Vector3d(0.0, 0.5, 0.0);  // 0.5 m to the left
  std::string err;
  ASSERT_TRUE(tree.add("base_link", "wheel_center", base_T_wheel, &err));
  FusionFrames f{&tree, tree.find("odom"), tree.find("base_link")};
  SensorParams sp;
  sp.kind = SensorKind::kOdometry;
  sp.update_mask = mask_bit(kVx) | mask_bit(kVyaw);
  SensorModel model(0, sp, FilterParams());
  SensorSample s;
  s.kind = SensorKind::kOdometry;
  s.frame = static_cast<std::int16_t>(tree.find("odom"));
  s.child_frame = static_cast<std::int16_t>(tree.find("wheel_center"));
  // Turning in place at 1 rad/s, a point 0.5 m left of centre moves backwards at 0.5 m/s.
  s.twist.linear = Eigen::Vector3d(-0.5, 0, 0);
  s.twist.angular = Eigen::Vector3d(0, 0, 1.0);
  s.twist.covariance = Matrix6::Identity() * 0.01;
  StateVector state = StateVector::Zero();
  state(kVyaw) = 1.0;
  MeasurementBatch out;
  ASSERT_EQ(model.convert(s, state, f, &out), SampleRejection::kNone);
  ASSERT_EQ(out.count, 1);
  EXPECT_NEAR(out.items[0].z(kVx), 0.0, 1e-12);
  EXPECT_NEAR(out.items[0].z(kVyaw), 1.0, 1e-12);
}

TEST(SensorModel, UnknownTransformIsRejected) {
  Frames fr(geometry::RigidTransform::identity());
  const int orphan = fr.tree.intern("orphan");
  SensorModel model(0, imu_params(), FilterParams());
  SensorSample s;
  s.kind = SensorKind::kImu;
  s.frame = static_cast<std::int16_t>(orphan);
  s.imu.has_angular_velocity = true;
  MeasurementBatch out;
  EXPECT_EQ(model.convert(s, StateVector::Zero(), fr.f, &out), SampleRejection::kNoTransform);
}

SensorSample pose_sample(TimeNs t, double x, double yaw) {
  SensorSample s;
  s.stamp = t;
  s.kind = SensorKind::kPose;
  s.frame = 0;  // odom
  s.pose.position = Eigen::Vector3d(x, 0, 0);
  s.pose.orientation = geometry::quaternion_from_rpy(0, 0, yaw);
  s.pose.covariance = Matrix6::Identity() * 0.01;
  return s;
}

TEST(SensorModel, DifferentialPoseBecomesBodyVelocity) {
  Frames fr(geometry::RigidTransform::identity());
  SensorParams sp;
  sp.kind = SensorKind::kPose;
  sp.update_mask = mask_bit(kX) | mask_bit(kYaw);
  sp.differential = true;
  SensorModel model(0, sp, FilterParams());
  MeasurementBatch out;
  model.convert(pose_sample(0, 10.0, 0.5), StateVector::Zero(), fr.f, &out);
  EXPECT_EQ(out.count, 0);  // the first pose only sets the reference
  // 0.1 s later: moved 0.2 m along the heading of 0.5 rad, turned 0.05 rad.
  SensorSample s2 = pose_sample(100'000'000, 0, 0.55);
  s2.pose.position = Eigen::Vector3d(10.0 + 0.2 * std::cos(0.5), 0.2 * std::sin(0.5), 0);
  model.convert(s2, StateVector::Zero(), fr.f, &out);
  ASSERT_EQ(out.count, 1);
  EXPECT_EQ(out.items[0].mask, mask_bit(kVx) | mask_bit(kVyaw));
  EXPECT_NEAR(out.items[0].z(kVx), 2.0, 1e-9);
  EXPECT_NEAR(out.items[0].z(kVyaw), 0.5, 1e-9);
}

TEST(SensorModel, RelativePoseStartsAtZero) {
  Frames fr(geometry::RigidTransform::identity());
  SensorParams sp;
  sp.kind = SensorKind::kPose;
  sp.update_mask = mask_bit(kX) | mask_bit(kYaw);
  sp.relative = true;
  SensorModel model(0, sp, FilterParams());
  MeasurementBatch out;
  model.convert(pose_sample(0, 10.0, 1.0), StateVector::Zero(), fr.f, &out);
  ASSERT_EQ(out.count, 1);
  EXPECT_NEAR(out.items[0].z(kX), 0.0, 1e-12);
  EXPECT_NEAR(out.items[0].z(kYaw), 0.0, 1e-12);
  model.convert(pose_sample(1, 10.0, 1.2), StateVector::Zero(), fr.f, &out);
  EXPECT_NEAR(out.items[0].z(kYaw), 0.2, 1e-12);
}

TEST(SensorModel, TwoDModeForcesPlanarVariables) {
  Frames fr(geometry::RigidTransform::identity());
  FilterParams fp;
  fp.two_d_mode = true;
  SensorParams sp;
  sp.kind = SensorKind::kPose;
  sp.update_mask = kPoseMask;
  SensorModel model(0, sp, fp);
  SensorSample s = pose_sample(0, 1.0, 0.3);
  s.pose.position.z() = 4.0;
  s.pose.orientation = geometry::quaternion_from_rpy(0.2, 0.1, 0.3);
  MeasurementBatch out;
  model.convert(s, StateVector::Zero(), fr.f, &out);
  ASSERT_EQ(out.count, 1);
  EXPECT_EQ(out.items[0].z(kZ), 0.0);
  EXPECT_EQ(out.items[0].z(kRoll), 0.0);
  EXPECT_EQ(out.items[0].z(kPitch), 0.0);
  EXPECT_NEAR(out.items[0].z(kYaw), 0.3, 1e-9);
  EXPECT_EQ(out.items[0].covariance(kZ, kZ), 1e-9);
}

TEST(SensorModel, GravityRemovedWithFilterAttitudeWhenImuHasNoOrientation) {
  Frames fr(geometry::RigidTransform::identity());
  SensorModel model(0, imu_params(), FilterParams());
  SensorSample s;
  s.kind = SensorKind::kImu;
  s.frame = static_cast<std::int16_t>(fr.tree.find("imu_link"));
  s.imu.has_linear_acceleration = true;
  StateVector state = StateVector::Zero();
  state(kPitch) = 0.3;  // nose down 0.3 rad: gravity has a +x component in the body
  const Eigen::Vector3d g_body = geometry::quaternion_from_rpy(0, 0.3, 0).conjugate() * Eigen::Vector3d(0, 0, 9.80665);
  s.imu.linear_acceleration = g_body;  // standing still
  MeasurementBatch out;
  model.convert(s, state, fr.f, &out);
  ASSERT_EQ(out.count, 1);
  EXPECT_LT(out.items[0].z.segment<3>(kAx).norm(), 1e-9);
}

TEST(SensorModel, RejectionThresholdsFollowThePart) {
  Frames fr(geometry::RigidTransform::identity());
  SensorParams sp = imu_params();
  sp.pose_rejection_threshold = 1.0;
  sp.twist_rejection_threshold = 2.0;
  sp.linear_acceleration_rejection_threshold = 3.0;
  SensorModel model(0, sp, FilterParams());
  SensorSample s;
  s.kind = SensorKind::kImu;
  s.frame = static_cast<std::int16_t>(fr.tree.find("imu_link"));
  s.imu.has_orientation = s.imu.has_angular_velocity = s.imu.has_linear_acceleration = true;
  MeasurementBatch out;
  model.convert(s, StateVector::Zero(), fr.f, &out);
  ASSERT_EQ(out.count, 3);
  EXPECT_EQ(out.items[0].mahalanobis_threshold, 1.0);
  EXPECT_EQ(out.items[1].mahalanobis_threshold, 2.0);
  EXPECT_EQ(out.items[2].mahalanobis_threshold, 3.0);
}

}  // namespace filter_test
}  // namespace rtfuse::est
