// The mapper's grid as occupancy_grid_t, decoded back with the generated
// C++ type: nav_msgs/OccupancyGrid's fields, bad grids refused and counted,
// no allocation per encode.
#include "transport/occupancy_grid_message.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rtfuse/occupancy_grid_t.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::transport {
namespace occupancy_grid_message_test {

TEST(OccupancyGridEncoder, CellsAndLayoutAsNavMsgsHasThem) {
  std::string error;
  auto enc = OccupancyGridEncoder::create(400 * 400, "odom", 5'000'000'000, &error);
  ASSERT_TRUE(enc) << error;
  const std::int8_t cells[6] = {-1, 0, 100, 0, 0, 42};
  const OccupancyGridLayout layout{3, 2, 0.05, -1.5, 2.25};
  const EncodedMessage e = enc->encode(layout, cells, 7'000'123'000);
  ASSERT_TRUE(e.ok());
  rtfuse::occupancy_grid_t msg;
  ASSERT_EQ(msg.decode(e.data, 0, e.size), e.size);
  EXPECT_EQ(msg.header.frame_id, "odom");
  EXPECT_EQ(msg.header.utime, 7'000'123);
  EXPECT_EQ(msg.header.seq, 0);
  EXPECT_EQ(msg.map_load_utime, 5'000'000);
  EXPECT_FLOAT_EQ(msg.resolution, 0.05f);
  EXPECT_EQ(msg.width, 3);
  EXPECT_EQ(msg.height, 2);
  EXPECT_EQ(msg.origin.position.x, -1.5);
  EXPECT_EQ(msg.origin.position.y, 2.25);
  EXPECT_EQ(msg.origin.orientation.w, 1.0);
  ASSERT_EQ(msg.num_cells, 6);
  EXPECT_EQ(msg.data, std::vector<std::int8_t>(cells, cells + 6));
  // The message is as long as its cells, not as the largest grid.
  EXPECT_LT(e.size, 200);
  EXPECT_EQ(enc->encode(layout, cells, 0).ok(), true);
  rtfuse::occupancy_grid_t second;
  ASSERT_GT(second.decode(enc->encode(layout, cells, 0).data, 0, e.size), 0);
  EXPECT_EQ(second.header.seq, 2);
}

TEST(OccupancyGridEncoder, GridsItCannotCarryAreCountedNotSent) {
  std::string error;
  EXPECT_FALSE(OccupancyGridEncoder::create(0, "odom", 0, &error));
  EXPECT_NE(error.find("0 cells"), std::string::npos) << error;
  auto enc = OccupancyGridEncoder::create(4, "odom", 0, &error);
  ASSERT_TRUE(enc);
  const std::int8_t cells[6] = {0, 0, 0, 0, 0, 0};
  EXPECT_FALSE(enc->encode({3, 2, 0.05, 0, 0}, cells, 0).ok());  // 6 cells > 4
  const std::int8_t bad[4] = {0, 101, 0, 0};
  EXPECT_FALSE(enc->encode({2, 2, 0.05, 0, 0}, bad, 0).ok());
  EXPECT_FALSE(enc->encode({2, 2, std::nan(""), 0, 0}, cells, 0).ok());
  EXPECT_EQ(enc->encode_failures(), 3);
  EXPECT_TRUE(enc->encode({2, 2, 0.05, 0, 0}, cells, 0).ok());
}

TEST(OccupancyGridEncoder, EncodingAllocatesNothing) {
  std::string error;
  auto enc = OccupancyGridEncoder::create(200 * 200, "odom", 0, &error);
  ASSERT_TRUE(enc);
  std::vector<std::int8_t> cells(200 * 200, 0);
  rtfuse::test::AllocScope scope;
  for (int k = 0; k < 5; ++k) EXPECT_TRUE(enc->encode({200, 200, 0.05, 0, 0}, cells.data(), k).ok());
  EXPECT_EQ(enc->encode({100, 50, 0.1, 1, 2}, cells.data(), 9).ok(), true);
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace occupancy_grid_message_test
}  // namespace rtfuse::transport
