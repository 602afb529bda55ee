#include "transport/sample_decoder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "transport/encode_buffer.hpp"

namespace rtfuse::transport {
namespace sample_decoder_test {

using est::SensorKind;
using est::SensorSample;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

template <class Msg>
std::vector<std::uint8_t> bytes_of(const Msg& m) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(encode_into(m, out.data(), static_cast<int>(out.size())), static_cast<int>(out.size()));
  return out;
}

void set_header(rtfuse::header_t* h, const char* frame, std::int64_t utime = 1'234'567) {
  h->utime = utime;
  h->seq = 7;
  h->frame_id = frame;
}

// Row-major symmetric covariance with distinct entries, to catch transposes.
template <int N>
void fill_covariance(double (&c)[N * N], double scale) {
  for (int r = 0; r < N; ++r) {
    for (int k = 0; k < N; ++k)
      c[r * N + k] = (r == k) ? scale * (r + 1) : scale * 0.01 * (r + k + 1);
  }
}

rtfuse::odometry_t good_odometry() {
  rtfuse::odometry_t m{};
  set_header(&m.header, "odom");
  m.child_frame_id = "base_link";
  m.pose.pose.position = {1.0, 2.0, 3.0};
  m.pose.pose.orientation = {0.0, 0.0, std::sin(0.25), std::cos(0.25)};  // x y z w
  fill_covariance<6>(m.pose.covariance, 0.1);
  m.twist.twist.linear = {0.5, -0.1, 0.0};
  m.twist.twist.angular = {0.0, 0.0, 0.2};
  fill_covariance<6>(m.twist.covariance, 0.02);
  return m;
}

rtfuse::imu_t good_imu() {
  rtfuse::imu_t m{};
  set_header(&m.header, "imu_link");
  m.orientation = {0.0, 0.0, 0.0, 1.0};
  fill_covariance<3>(m.orientation_covariance, 0.01);
  m.angular_velocity = {0.01, 0.02, 0.03};
  fill_covariance<3>(m.angular_velocity_covariance, 0.001);
  m.linear_acceleration = {0.1, 0.2, 9.81};
  fill_covariance<3>(m.linear_acceleration_covariance, 0.05);
  return m;
}

rtfuse::pose_with_covariance_stamped_t good_pose() {
  rtfuse::pose_with_covariance_stamped_t m{};
  set_header(&m.header, "map");
  m.pose.pose.position = {10.0, -4.0, 0.5};
  m.pose.pose.orientation = {0.0, 0.0, 0.0, 1.0};
  fill_covariance<6>(m.pose.covariance, 0.3);
  return m;
}

rtfuse::twist_with_covariance_stamped_t good_twist() {
  rtfuse::twist_with_covariance_stamped_t m{};
  set_header(&m.header, "base_link");
  m.twist.twist.linear = {1.0, 0.0, 0.0};
  m.twist.twist.angular = {0.0, 0.0, -0.5};
  fill_covariance<6>(m.twist.covariance, 0.04);
  return m;
}

class SampleDecoderTest : public testing::Test {
 protected:
  SampleDecoderTest() {
    odom_ = frames_.intern("odom");
    base_ = frames_.intern("base_link");
    imu_ = frames_.intern("imu_link");
    map_ = frames_.intern("map");
  }

  template <class Msg>
  DecodeResult decode(SensorKind kind, const Msg& m) {
    const auto b = bytes_of(m);
    return decoder_.decode(kind, b.data(), static_cast<int>(b.size()), &out_);
  }

  geometry::FrameTree frames_;
  int odom_ = -1, base_ = -1, imu_ = -1, map_ = -1;
  SampleDecoder decoder_{frames_};
  SensorSample out_;
};

TEST_F(SampleDecoderTest, OdometryValuesAndCovariances) {
  const auto m = good_odometry();
  out_.sensor = 5;
  ASSERT_EQ(decode(SensorKind::kOdometry, m), DecodeResult::kOk);
  EXPECT_EQ(out_.sensor, 5);  // the caller's, untouched
  EXPECT_EQ(out_.kind, SensorKind::kOdometry);
  EXPECT_EQ(out_.stamp, 1'234'567'000);
  EXPECT_EQ(out_.frame, odom_);
  EXPECT_EQ(out_.child_frame, base_);
  EXPECT_EQ(out_.pose.position, Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_DOUBLE_EQ(out_.pose.orientation.w(), std::cos(0.25));
  EXPECT_DOUBLE_EQ(out_.pose.orientation.z(), std::sin(0.25));
  EXPECT_DOUBLE_EQ(out_.pose.orientation.x(), 0.0);
  for (int r = 0; r < 6; ++r) {
    for (int k = 0; k < 6; ++k) {
      EXPECT_EQ(out_.pose.covariance(r, k), m.pose.covariance[r * 6 + k]) << r << "," << k;
      EXPECT_EQ(out_.twist.covariance(r, k), m.twist.covariance[r * 6 + k]) << r << "," << k;
    }
  }
  EXPECT_EQ(out_.twist.linear, Eigen::Vector3d(0.5, -0.1, 0.0));
  EXPECT_EQ(out_.twist.angular, Eigen::Vector3d(0.0, 0.0, 0.2));
}

TEST_F(SampleDecoderTest, RowMajorCovarianceIsNotTransposed) {
  auto m = good_twist();
  m.twist.covariance[0 * 6 + 0] = 1.0;  // keep the matrix positive definite
  // Symmetric within tolerance but the two halves are told apart by their last digit.
  m.twist.covariance[0 * 6 + 5] = 0.123456789;
  m.twist.covariance[5 * 6 + 0] = 0.1234567891;
  ASSERT_EQ(decode(SensorKind::kTwist, m), DecodeResult::kOk);
  EXPECT_EQ(out_.twist.covariance(0, 5), 0.123456789);
  EXPECT_EQ(out_.twist.covariance(5, 0), 0.1234567891);
}

TEST_F(SampleDecoderTest, PoseAndTwist) {
  ASSERT_EQ(decode(SensorKind::kPose, good_pose()), DecodeResult::kOk);
  EXPECT_EQ(out_.kind, SensorKind::kPose);
  EXPECT_EQ(out_.frame, map_);
  EXPECT_EQ(out_.child_frame, -1);
  EXPECT_EQ(out_.pose.position, Eigen::Vector3d(10.0, -4.0, 0.5));
  EXPECT_DOUBLE_EQ(out_.pose.covariance(2, 2), 0.9);

  ASSERT_EQ(decode(SensorKind::kTwist, good_twist()), DecodeResult::kOk);
  EXPECT_EQ(out_.kind, SensorKind::kTwist);
  EXPECT_EQ(out_.frame, base_);
  EXPECT_EQ(out_.twist.angular.z(), -0.5);
  // The pose of the previous sample must not leak into a twist sample.
  EXPECT_EQ(out_.pose.position, Eigen::Vector3d::Zero());
}

TEST_F(SampleDecoderTest, ImuValues) {
  const auto m = good_imu();
  ASSERT_EQ(decode(SensorKind::kImu, m), DecodeResult::kOk);
  EXPECT_EQ(out_.frame, imu_);
  EXPECT_TRUE(out_.imu.has_orientation);
  EXPECT_TRUE(out_.imu.has_angular_velocity);
  EXPECT_TRUE(out_.imu.has_linear_acceleration);
  EXPECT_EQ(out_.imu.linear_acceleration, Eigen::Vector3d(0.1, 0.2, 9.81));
  EXPECT_EQ(out_.imu.angular_velocity, Eigen::Vector3d(0.01, 0.02, 0.03));
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(out_.imu.linear_acceleration_covariance(r, k),
                m.linear_acceleration_covariance[r * 3 + k]);
    }
  }
}

TEST_F(SampleDecoderTest, ImuMinusOneMeansNotProvidedAndIsNotChecked) {
  auto m = good_imu();
  m.orientation_covariance[0] = -1.0;
  m.orientation = {kNaN, 0.0, 0.0, 0.0};  // garbage in an absent part is fine
  m.linear_acceleration_covariance[0] = -1.0;
  m.linear_acceleration = {kInf, kInf, kInf};
  ASSERT_EQ(decode(SensorKind::kImu, m), DecodeResult::kOk);
  EXPECT_FALSE(out_.imu.has_orientation);
  EXPECT_TRUE(out_.imu.has_angular_velocity);
  EXPECT_FALSE(out_.imu.has_linear_acceleration);
  EXPECT_EQ(out_.imu.linear_acceleration, Eigen::Vector3d::Zero());
  EXPECT_TRUE(out_.imu.orientation.coeffs().allFinite());
}

TEST_F(SampleDecoderTest, ZeroAndHugeCovariancesAreValid) {
  auto m = good_imu();
  for (double& c : m.orientation_covariance) c = 0.0;  // "unknown": the filter floors it
  for (double& c : m.angular_velocity_covariance) c = 0.0;
  m.angular_velocity_covariance[0] = 1e6;
  ASSERT_EQ(decode(SensorKind::kImu, m), DecodeResult::kOk);
  EXPECT_EQ(out_.imu.orientation_covariance, Eigen::Matrix3d::Zero());
  EXPECT_EQ(out_.imu.angular_velocity_covariance(0, 0), 1e6);
}

TEST_F(SampleDecoderTest, NonFiniteValues) {
  auto t = good_twist();
  t.twist.twist.linear.y = kNaN;
  EXPECT_EQ(decode(SensorKind::kTwist, t), DecodeResult::kNonFinite);

  t = good_twist();
  t.twist.covariance[7] = kInf;
  EXPECT_EQ(decode(SensorKind::kTwist, t), DecodeResult::kNonFinite);

  auto o = good_odometry();
  o.pose.pose.orientation.w = kNaN;
  EXPECT_EQ(decode(SensorKind::kOdometry, o), DecodeResult::kNonFinite);

  auto i = good_imu();
  i.angular_velocity.z = -kInf;
  EXPECT_EQ(decode(SensorKind::kImu, i), DecodeResult::kNonFinite);
}

TEST_F(SampleDecoderTest, ZeroQuaternionIsRejectedAndOffNormIsNormalised) {
  auto p = good_pose();
  p.pose.pose.orientation = {0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(decode(SensorKind::kPose, p), DecodeResult::kNonFinite);

  p.pose.pose.orientation = {0.0, 0.0, 0.0, 2.0};
  ASSERT_EQ(decode(SensorKind::kPose, p), DecodeResult::kOk);
  EXPECT_DOUBLE_EQ(out_.pose.orientation.w(), 1.0);

  // Within 0.01 of unit norm: kept exactly as sent, as robot_localization does.
  p.pose.pose.orientation = {0.0, 0.0, 0.0, 1.005};
  ASSERT_EQ(decode(SensorKind::kPose, p), DecodeResult::kOk);
  EXPECT_EQ(out_.pose.orientation.w(), 1.005);
}

TEST_F(SampleDecoderTest, AQuaternionWhoseNormOverflowsIsRejectedNotZeroed) {
  // The fuzzer's finding: finite components whose squares overflow made a
  // norm of infinity, and normalising by it gave the zero quaternion.
  auto p = good_pose();
  p.pose.pose.orientation = {0.0, 0.0, 1e200, 1.0};
  EXPECT_EQ(decode(SensorKind::kPose, p), DecodeResult::kNonFinite);
  auto i = good_imu();
  i.orientation = {-1e160, 0.0, 0.0, 0.0};
  EXPECT_EQ(decode(SensorKind::kImu, i), DecodeResult::kNonFinite);
  // Large but representable: normalised.
  p.pose.pose.orientation = {0.0, 0.0, 0.0, 1e150};
  ASSERT_EQ(decode(SensorKind::kPose, p), DecodeResult::kOk);
  EXPECT_DOUBLE_EQ(out_.pose.orientation.w(), 1.0);
}

TEST_F(SampleDecoderTest, AFrameNameWithANulInsideIsMalformed) {
  // lcm-gen's decoder keeps what follows a NUL and its encoder drops it: such
  // a name is no string a sender meant, and no frame.
  auto b = bytes_of(good_twist());
  // header.frame_id ("base_link" or similar) starts after its 4-byte length at 24.
  b[25] = 0;
  EXPECT_EQ(decoder_.decode(SensorKind::kTwist, b.data(), static_cast<int>(b.size()), &out_),
            DecodeResult::kMalformed);
  b = bytes_of(good_twist());
  const std::int32_t len = (b[20] << 24) | (b[21] << 16) | (b[22] << 8) | b[23];
  b[24 + static_cast<std::size_t>(len) - 1] = 'x';  // the terminating NUL overwritten
  EXPECT_EQ(decoder_.decode(SensorKind::kTwist, b.data(), static_cast<int>(b.size()), &out_),
            DecodeResult::kMalformed);
}

TEST_F(SampleDecoderTest, BadCovariances) {
  auto p = good_pose();
  p.pose.covariance[1] += 0.5;  // (0,1) != (1,0)
  EXPECT_EQ(decode(SensorKind::kPose, p), DecodeResult::kBadCovariance);

  p = good_pose();
  p.pose.covariance[14] = -0.1;  // diagonal (2,2)
  EXPECT_EQ(decode(SensorKind::kPose, p), DecodeResult::kBadCovariance);

  auto i = good_imu();
  i.linear_acceleration_covariance[4] = -1.0;  // -1 only means "absent" in element 0
  EXPECT_EQ(decode(SensorKind::kImu, i), DecodeResult::kBadCovariance);

  // Relative tolerance: a 1e-9 mismatch on entries of 1e6 is rounding, not asymmetry.
  p = good_pose();
  p.pose.covariance[0] = 1e6;
  p.pose.covariance[14] = 1e6;
  p.pose.covariance[2] = 5e5;
  p.pose.covariance[12] = 5e5 + 1e-3;
  EXPECT_EQ(decode(SensorKind::kPose, p), DecodeResult::kOk);

  // Symmetric, non-negative diagonal, yet indefinite: a correlation above 1
  // between x and y (eigenvalues of [[1,2],[2,1]] are 3 and -1).
  p = good_pose();
  p.pose.covariance[0] = 1.0;
  p.pose.covariance[7] = 1.0;
  p.pose.covariance[1] = 2.0;
  p.pose.covariance[6] = 2.0;
  EXPECT_EQ(decode(SensorKind::kPose, p), DecodeResult::kBadCovariance);
}

TEST_F(SampleDecoderTest, UnknownOrEmptyFrames) {
  auto t = good_twist();
  t.header.frame_id = "laser";
  EXPECT_EQ(decode(SensorKind::kTwist, t), DecodeResult::kUnknownFrame);
  t.header.frame_id = "";
  EXPECT_EQ(decode(SensorKind::kTwist, t), DecodeResult::kUnknownFrame);

  auto o = good_odometry();
  o.child_frame_id = "wheel";
  EXPECT_EQ(decode(SensorKind::kOdometry, o), DecodeResult::kUnknownFrame);
}

TEST_F(SampleDecoderTest, WrongTypeIsToldFromMalformed) {
  EXPECT_EQ(decode(SensorKind::kOdometry, good_imu()), DecodeResult::kWrongType);
  EXPECT_EQ(decode(SensorKind::kPose, good_twist()), DecodeResult::kWrongType);
  EXPECT_EQ(decode(SensorKind::kImu, good_pose()), DecodeResult::kWrongType);
}

TEST_F(SampleDecoderTest, TruncatedBytesAreMalformed) {
  const auto b = bytes_of(good_odometry());
  for (int size = 0; size < static_cast<int>(b.size()); ++size) {
    EXPECT_EQ(decoder_.decode(SensorKind::kOdometry, b.data(), size, &out_),
              DecodeResult::kMalformed)
        << "size " << size;
  }
  EXPECT_EQ(decoder_.decode(SensorKind::kOdometry, nullptr, 0, &out_), DecodeResult::kMalformed);
}

TEST_F(SampleDecoderTest, CorruptStringLengthsAreMalformedNotAThrow) {
  auto b = bytes_of(good_twist());
  // header.frame_id length lives after the fingerprint, utime and seq.
  for (std::size_t i = 20; i < 24; ++i)
    b[i] = 0;  // length 0: lcm-gen would assign (size_t)-1 chars
  EXPECT_EQ(decoder_.decode(SensorKind::kTwist, b.data(), static_cast<int>(b.size()), &out_),
            DecodeResult::kMalformed);
  b[20] = 0xFF;  // negative length
  EXPECT_EQ(decoder_.decode(SensorKind::kTwist, b.data(), static_cast<int>(b.size()), &out_),
            DecodeResult::kMalformed);
}

TEST_F(SampleDecoderTest, FailureLeavesTheOutputUntouched) {
  ASSERT_EQ(decode(SensorKind::kPose, good_pose()), DecodeResult::kOk);
  const SensorSample before = out_;
  auto p = good_pose();
  p.pose.pose.position.x = kNaN;
  EXPECT_EQ(decode(SensorKind::kPose, p), DecodeResult::kNonFinite);
  EXPECT_EQ(out_.pose.position, before.pose.position);
  EXPECT_EQ(out_.stamp, before.stamp);
}

TEST_F(SampleDecoderTest, SetPose) {
  auto m = good_pose();
  m.header.utime = 42;
  const auto b = bytes_of(m);
  est::PoseSample pose;
  TimeNs stamp = 0;
  std::int16_t frame = -1;
  ASSERT_EQ(decoder_.decode_set_pose(b.data(), static_cast<int>(b.size()), &pose, &stamp, &frame),
            DecodeResult::kOk);
  EXPECT_EQ(stamp, 42'000);
  EXPECT_EQ(frame, map_);
  EXPECT_EQ(pose.position, Eigen::Vector3d(10.0, -4.0, 0.5));
  EXPECT_DOUBLE_EQ(pose.covariance(5, 5), 1.8);

  const auto wrong = bytes_of(good_twist());
  EXPECT_EQ(
      decoder_.decode_set_pose(wrong.data(), static_cast<int>(wrong.size()), &pose, &stamp, &frame),
      DecodeResult::kWrongType);
}

TEST(DecodeResult, HasNames) {
  EXPECT_STREQ(to_string(DecodeResult::kOk), "ok");
  EXPECT_STREQ(to_string(DecodeResult::kBadCovariance), "invalid covariance");
  EXPECT_STREQ(to_string(DecodeResult::kWrongType), "wrong message type");
}

TEST(EncodeBuffer, RefusesWhatDoesNotFit) {
  const auto m = good_odometry();
  EncodeBuffer<64> small;
  EXPECT_FALSE(small.encode(m));
  EXPECT_EQ(small.size(), 0);
  EncodeBuffer<4096> big;
  ASSERT_TRUE(big.encode(m));
  EXPECT_EQ(big.size(), m.getEncodedSize());
  rtfuse::odometry_t back;
  EXPECT_EQ(back.decode(big.data(), 0, big.size()), big.size());
  EXPECT_EQ(back.child_frame_id, "base_link");
  std::uint8_t raw[16];
  EXPECT_EQ(encode_into(m, raw, sizeof raw), -1);
}

}  // namespace sample_decoder_test
}  // namespace rtfuse::transport

namespace rtfuse::transport {
namespace sample_decoder_test {

TEST_F(SampleDecoderTest, NavSatFixKeepsItsValuesForTheNavsatTransformToJudge) {
  rtfuse::navsat_fix_t m{};
  m.header.utime = 1'234'567;
  m.header.frame_id = "base_link";
  m.status = rtfuse::navsat_fix_t::STATUS_SBAS_FIX;
  m.latitude = 47.3977;
  m.longitude = 8.5456;
  m.altitude = 488.25;
  for (int i = 0; i < 9; ++i) m.position_covariance[i] = 0.1 * (i + 1);  // row major, east north up
  m.position_covariance_type = rtfuse::navsat_fix_t::COVARIANCE_TYPE_KNOWN;
  out_.sensor = 3;
  ASSERT_EQ(decode(SensorKind::kNavSatFix, m), DecodeResult::kOk);
  EXPECT_EQ(out_.sensor, 3);
  EXPECT_EQ(out_.kind, SensorKind::kNavSatFix);
  EXPECT_EQ(out_.stamp, 1'234'567'000);
  EXPECT_EQ(out_.frame, base_);
  EXPECT_EQ(out_.navsat.status, 1);
  EXPECT_EQ(out_.navsat.covariance_type, 3);
  EXPECT_EQ(out_.navsat.position.latitude_deg, 47.3977);
  EXPECT_EQ(out_.navsat.position.longitude_deg, 8.5456);
  EXPECT_EQ(out_.navsat.position.altitude_m, 488.25);
  EXPECT_DOUBLE_EQ(out_.navsat.covariance(0, 1), 0.2);
  EXPECT_DOUBLE_EQ(out_.navsat.covariance(1, 0), 0.4);

  // A NaN latitude, no fix, an unknown frame: passed on (the transform
  // counts them by reason), not lost as a decode error.
  m.latitude = NAN;
  m.status = rtfuse::navsat_fix_t::STATUS_NO_FIX;
  m.header.frame_id = "gps_antenna";
  ASSERT_EQ(decode(SensorKind::kNavSatFix, m), DecodeResult::kOk);
  EXPECT_TRUE(std::isnan(out_.navsat.position.latitude_deg));
  EXPECT_EQ(out_.navsat.status, -1);
  EXPECT_EQ(out_.frame, -1);

  // Another type's bytes on a navsat channel.
  EXPECT_EQ(decode(SensorKind::kNavSatFix, good_odometry()), DecodeResult::kWrongType);
}

}  // namespace sample_decoder_test
}  // namespace rtfuse::transport
