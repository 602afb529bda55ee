#include "transport/lcm_node.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace rtfuse::transport {
namespace lcm_node_test {

// memq:// only: unit tests never touch the network.
struct Received {
  std::string channel;
  std::vector<std::uint8_t> bytes;
  std::int64_t recv_utime = 0;
  int calls = 0;
};

void on_message(const char* channel, const std::uint8_t* data, int size, std::int64_t recv_utime,
                void* user) {
  auto* r = static_cast<Received*>(user);
  r->channel = channel;
  r->bytes.assign(data, data + size);
  r->recv_utime = recv_utime;
  ++r->calls;
}

TEST(LcmNode, MemqPublishIsHandedToTheSubscriber) {
  std::string err;
  auto node = LcmNode::create("memq://", &err);
  ASSERT_NE(node, nullptr) << err;
  Received got;
  ASSERT_TRUE(node->subscribe("RTFUSE_TEST", &on_message, &got));
  const std::uint8_t bytes[] = {1, 2, 3, 250, 0, 7};
  ASSERT_TRUE(node->publish("RTFUSE_TEST", bytes, sizeof bytes));
  EXPECT_GT(node->handle_timeout(1000), 0);
  EXPECT_EQ(got.calls, 1);
  EXPECT_EQ(got.channel, "RTFUSE_TEST");
  EXPECT_EQ(got.bytes, std::vector<std::uint8_t>(std::begin(bytes), std::end(bytes)));
  EXPECT_GT(got.recv_utime, 0);
}

TEST(LcmNode, ChannelIsARegexAndOthersAreNotDelivered) {
  std::string err;
  auto node = LcmNode::create("memq://", &err);
  ASSERT_NE(node, nullptr) << err;
  Received imu, all;
  ASSERT_TRUE(node->subscribe("IMU", &on_message, &imu));
  ASSERT_TRUE(node->subscribe("IMU|ODOM", &on_message, &all));
  const std::uint8_t one = 1;
  ASSERT_TRUE(node->publish("ODOM", &one, 1));
  ASSERT_GT(node->handle_timeout(1000), 0);
  EXPECT_EQ(imu.calls, 0);
  EXPECT_EQ(all.calls, 1);
  EXPECT_EQ(all.channel, "ODOM");
  // Nothing left: handle_timeout times out rather than blocking.
  EXPECT_EQ(node->handle_timeout(10), 0);
}

TEST(LcmNode, EmptyMessageAndBadArguments) {
  std::string err;
  auto node = LcmNode::create("memq://", &err);
  ASSERT_NE(node, nullptr) << err;
  Received got;
  ASSERT_TRUE(node->subscribe("EMPTY", &on_message, &got));
  EXPECT_TRUE(node->publish("EMPTY", nullptr, 0));
  EXPECT_GT(node->handle_timeout(1000), 0);
  EXPECT_EQ(got.calls, 1);
  EXPECT_TRUE(got.bytes.empty());
  EXPECT_FALSE(node->publish("EMPTY", nullptr, 4));
  EXPECT_FALSE(node->publish("EMPTY", "x", -1));
  EXPECT_FALSE(node->subscribe("EMPTY", nullptr, nullptr));
}

TEST(LcmNode, BadUrlIsAnErrorNotACrash) {
  std::string err;
  auto node = LcmNode::create("nosuchprovider://nowhere", &err);
  EXPECT_EQ(node, nullptr);
  EXPECT_NE(err.find("'nosuchprovider://nowhere'"), std::string::npos) << err;
  EXPECT_NE(err.find("memq://"), std::string::npos) << err;
}

}  // namespace lcm_node_test
}  // namespace rtfuse::transport
