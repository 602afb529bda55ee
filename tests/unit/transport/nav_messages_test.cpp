// The navigator's messages: goals and stops decoded with their checks
// (wrong type, truncation, non-finite values, empty frame, a reason with
// an embedded NUL), paths encoded as path_t with orientations along the
// segments, and neither allocating per message.
#include "transport/nav_messages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "rtfuse/nav_stop_t.hpp"
#include "rtfuse/path_t.hpp"
#include "rtfuse/pose_stamped_t.hpp"
#include "rtfuse/twist_stamped_t.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::transport {
namespace nav_messages_test {

template <class Msg>
std::vector<std::uint8_t> bytes_of(const Msg& m) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(b.data(), 0, static_cast<int>(b.size())), static_cast<int>(b.size()));
  return b;
}

rtfuse::pose_stamped_t goal_msg(double x, double y, double yaw) {
  rtfuse::pose_stamped_t m{};
  m.header.utime = 12'000'345;
  m.header.frame_id = "odom";
  m.pose.position.x = x;
  m.pose.position.y = y;
  m.pose.orientation.z = std::sin(0.5 * yaw);
  m.pose.orientation.w = std::cos(0.5 * yaw);
  return m;
}

TEST(NavInputDecoder, GoalPositionHeadingStampAndFrame) {
  NavInputDecoder d;
  const auto b = bytes_of(goal_msg(3.5, -2.25, 2.0));
  NavGoal g;
  ASSERT_EQ(d.decode_goal(b.data(), static_cast<int>(b.size()), &g), DecodeResult::kOk);
  EXPECT_EQ(g.stamp, 12'000'345'000);
  EXPECT_EQ(g.x, 3.5);
  EXPECT_EQ(g.y, -2.25);
  ASSERT_TRUE(g.has_yaw);
  EXPECT_NEAR(g.yaw, 2.0, 1e-12);
  EXPECT_EQ(d.goal_frame(), "odom");
}

TEST(NavInputDecoder, AllZeroOrientationIsAPositionOnlyGoal) {
  NavInputDecoder d;
  rtfuse::pose_stamped_t m = goal_msg(1.0, 1.0, 0.0);
  m.pose.orientation.w = 0.0;
  const auto b = bytes_of(m);
  NavGoal g;
  ASSERT_EQ(d.decode_goal(b.data(), static_cast<int>(b.size()), &g), DecodeResult::kOk);
  EXPECT_FALSE(g.has_yaw);
}

TEST(NavInputDecoder, UnscaledQuaternionGivesTheSameYaw) {
  NavInputDecoder d;
  rtfuse::pose_stamped_t m = goal_msg(0.0, 0.0, -2.5);
  m.pose.orientation.z *= 3.0;
  m.pose.orientation.w *= 3.0;
  const auto b = bytes_of(m);
  NavGoal g;
  ASSERT_EQ(d.decode_goal(b.data(), static_cast<int>(b.size()), &g), DecodeResult::kOk);
  EXPECT_NEAR(g.yaw, -2.5, 1e-12);
}

TEST(NavInputDecoder, BadGoalsAreRefusedWithTheirReason) {
  NavInputDecoder d;
  NavGoal g;
  g.x = 99.0;
  rtfuse::pose_stamped_t nan_goal = goal_msg(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
  auto b = bytes_of(nan_goal);
  EXPECT_EQ(d.decode_goal(b.data(), static_cast<int>(b.size()), &g), DecodeResult::kNonFinite);
  rtfuse::pose_stamped_t inf_q = goal_msg(0.0, 0.0, 0.0);
  inf_q.pose.orientation.x = std::numeric_limits<double>::infinity();
  b = bytes_of(inf_q);
  EXPECT_EQ(d.decode_goal(b.data(), static_cast<int>(b.size()), &g), DecodeResult::kNonFinite);
  rtfuse::pose_stamped_t no_frame = goal_msg(0.0, 0.0, 0.0);
  no_frame.header.frame_id.clear();
  b = bytes_of(no_frame);
  EXPECT_EQ(d.decode_goal(b.data(), static_cast<int>(b.size()), &g), DecodeResult::kUnknownFrame);
  b = bytes_of(goal_msg(1.0, 2.0, 0.0));
  EXPECT_EQ(d.decode_goal(b.data(), static_cast<int>(b.size()) - 1, &g), DecodeResult::kMalformed);
  EXPECT_EQ(d.decode_goal(b.data(), 7, &g), DecodeResult::kMalformed);
  EXPECT_EQ(d.decode_goal(nullptr, 100, &g), DecodeResult::kMalformed);
  rtfuse::twist_stamped_t other{};
  other.header.frame_id = "odom";
  b = bytes_of(other);
  EXPECT_EQ(d.decode_goal(b.data(), static_cast<int>(b.size()), &g), DecodeResult::kWrongType);
  // A string length past the end, as lcm-gen would trust it.
  b = bytes_of(goal_msg(1.0, 2.0, 0.0));
  b[20] = 0x7f;
  EXPECT_EQ(d.decode_goal(b.data(), static_cast<int>(b.size()), &g), DecodeResult::kMalformed);
  EXPECT_EQ(g.x, 99.0) << "a refused goal leaves the output alone";
}

TEST(NavInputDecoder, StopAndRelease) {
  NavInputDecoder d;
  rtfuse::nav_stop_t m{};
  m.header.utime = 5;
  m.header.frame_id = "base_link";
  m.stop = true;
  m.reason = "operator";
  auto b = bytes_of(m);
  NavStop s;
  ASSERT_EQ(d.decode_stop(b.data(), static_cast<int>(b.size()), &s), DecodeResult::kOk);
  EXPECT_TRUE(s.stop);
  EXPECT_EQ(s.stamp, 5'000);
  EXPECT_EQ(d.stop_reason(), "operator");
  m.stop = false;
  m.header.frame_id.clear();  // a stop needs no frame
  b = bytes_of(m);
  ASSERT_EQ(d.decode_stop(b.data(), static_cast<int>(b.size()), &s), DecodeResult::kOk);
  EXPECT_FALSE(s.stop);
  // A reason with an embedded NUL: lcm-gen would keep it, its encoder not.
  m.reason = "ab";
  b = bytes_of(m);
  b[b.size() - 2] = 0;
  EXPECT_EQ(d.decode_stop(b.data(), static_cast<int>(b.size()), &s), DecodeResult::kMalformed);
  EXPECT_EQ(d.decode_stop(b.data(), static_cast<int>(b.size()) - 3, &s), DecodeResult::kMalformed);
}

TEST(NavInputDecoder, DecodingAllocatesNothing) {
  NavInputDecoder d;
  const auto goal = bytes_of(goal_msg(1.0, 2.0, 0.5));
  rtfuse::nav_stop_t m{};
  m.header.frame_id = "base_link";
  m.stop = true;
  m.reason = "someone stepped in front";
  const auto stop = bytes_of(m);
  NavGoal g;
  NavStop s;
  test::AllocScope count;
  for (int i = 0; i < 100; ++i) {
    ASSERT_EQ(d.decode_goal(goal.data(), static_cast<int>(goal.size()), &g), DecodeResult::kOk);
    ASSERT_EQ(d.decode_stop(stop.data(), static_cast<int>(stop.size()), &s), DecodeResult::kOk);
  }
  EXPECT_EQ(count.count(), 0u);
}

TEST(PathEncoder, PointsLengthCostAndHeadings) {
  std::string error;
  auto enc = PathEncoder::create(1000, "odom", &error);
  ASSERT_TRUE(enc) << error;
  const PathPoint2 pts[3] = {{0.0, 0.0}, {1.0, 0.0}, {1.0, 2.0}};
  const EncodedMessage e = enc->encode(pts, 3, 4, 12.5, 3'000'000'000);
  ASSERT_TRUE(e.ok());
  rtfuse::path_t msg;
  ASSERT_EQ(msg.decode(e.data, 0, e.size), e.size);
  EXPECT_EQ(msg.header.frame_id, "odom");
  EXPECT_EQ(msg.header.utime, 3'000'000);
  EXPECT_EQ(msg.goal_seq, 4);
  EXPECT_EQ(msg.cost, 12.5);
  EXPECT_DOUBLE_EQ(msg.length_m, 3.0);
  ASSERT_EQ(msg.num_poses, 3);
  EXPECT_EQ(msg.poses[2].position.y, 2.0);
  // Along x, then up y for the segment and the last point.
  EXPECT_NEAR(msg.poses[0].orientation.w, 1.0, 1e-15);
  EXPECT_NEAR(2.0 * std::atan2(msg.poses[1].orientation.z, msg.poses[1].orientation.w), M_PI / 2, 1e-12);
  EXPECT_NEAR(2.0 * std::atan2(msg.poses[2].orientation.z, msg.poses[2].orientation.w), M_PI / 2, 1e-12);
  EXPECT_LT(e.size, 400) << "as long as its points, not as the largest path";
}

TEST(PathEncoder, AnEmptyPathSaysNoneWasFound) {
  auto enc = PathEncoder::create(10, "odom", nullptr);
  ASSERT_TRUE(enc);
  const EncodedMessage e = enc->encode(nullptr, 0, 2, 0.0, 0);
  ASSERT_TRUE(e.ok());
  rtfuse::path_t msg;
  ASSERT_EQ(msg.decode(e.data, 0, e.size), e.size);
  EXPECT_EQ(msg.num_poses, 0);
  EXPECT_EQ(msg.goal_seq, 2);
}

TEST(PathEncoder, RefusesWhatItCannotEncode) {
  std::string error;
  EXPECT_FALSE(PathEncoder::create(0, "odom", &error));
  EXPECT_NE(error.find("1 to"), std::string::npos) << error;
  auto enc = PathEncoder::create(2, "odom", nullptr);
  const PathPoint2 pts[3] = {{0.0, 0.0}, {std::numeric_limits<double>::quiet_NaN(), 0.0}, {1.0, 1.0}};
  EXPECT_FALSE(enc->encode(pts, 3, 1, 0.0, 0).ok());
  EXPECT_FALSE(enc->encode(pts, 2, 1, 0.0, 0).ok());
  EXPECT_FALSE(enc->encode(pts, 1, 1, std::numeric_limits<double>::infinity(), 0).ok());
  EXPECT_EQ(enc->encode_failures(), 3);
  EXPECT_TRUE(enc->encode(pts, 1, 1, 0.0, 0).ok());
}

TEST(PathEncoder, EncodingAllocatesNothing) {
  auto enc = PathEncoder::create(4000, "odom", nullptr);
  std::vector<PathPoint2> pts(4000);
  for (int i = 0; i < 4000; ++i) pts[static_cast<std::size_t>(i)] = {0.05 * i, 0.01 * i};
  test::AllocScope count;
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(enc->encode(pts.data(), 4000 - i, i, 1.0 * i, i).ok());
  EXPECT_EQ(count.count(), 0u);
}

}  // namespace nav_messages_test
}  // namespace rtfuse::transport
