// The .bt writer on maps whose file can be written out by hand; the
// byte-for-byte comparison with OctoMap's own writeBinary on real scans is
// tests/reference/octomap_equality_test.cpp.
#include "mapping/octomap_binary.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "mapping/map_digest.hpp"

namespace octomap_binary_test {

using namespace rtfuse::mapping;

OccupancyParams tenth() {
  OccupancyParams p;
  p.resolution = 0.1;
  return p;
}

std::string header(std::size_t nodes, const char* res) {
  return std::string("# Octomap OcTree binary file\n"
                     "# (feel free to add / change comments, but leave the first line as it is!)\n"
                     "#\nid OcTree\nsize ") +
         std::to_string(nodes) + "\nres " + res + "\ndata\n";
}

std::vector<std::uint8_t> bytes(const std::string& head, std::vector<std::uint8_t> data) {
  std::vector<std::uint8_t> all(head.begin(), head.end());
  all.insert(all.end(), data.begin(), data.end());
  return all;
}

TEST(OctomapBinary, AnEmptyMapIsAHeaderOfSizeZero) {
  OccupancyMap map(tenth(), {8, 8});
  OctomapBinaryWriter writer(8);
  std::vector<std::uint8_t> out;
  EXPECT_EQ(writer.write(map, out), 0u);
  EXPECT_EQ(out, bytes(header(0, "0.1"), {}));
}

TEST(OctomapBinary, OneOccupiedVoxelIsAPathOfSixteenInnerNodes) {
  OccupancyMap map(tenth(), {8, 8});
  const MapPoint p{0.05f, 0.05f, 0.05f};
  map.insert_scan(&p, 1, {0.01f, 0.01f, 0.01f});  // sensor in the same voxel: no free space
  OctomapBinaryWriter writer(8);
  std::vector<std::uint8_t> out;
  EXPECT_EQ(writer.write(map, out), 17u);
  // Key 32768 on each axis: bit 15 set, so child 7 of the root, then child
  // 0 down to depth 15, whose child 0 is the occupied voxel (10 = 0x02).
  std::vector<std::uint8_t> data = {0x00, 0xC0};
  for (int depth = 1; depth < 15; ++depth) data.insert(data.end(), {0x03, 0x00});
  data.insert(data.end(), {0x02, 0x00});
  EXPECT_EQ(out, bytes(header(17, "0.1"), data));
}

TEST(OctomapBinary, ChildrenThatAgreeInOccupancyAreOneLeafInTheFile) {
  // Eight voxels of one depth-15 node, all occupied but not all with the
  // same log-odds: OctoMap's log-odds tree keeps them apart, its file
  // (after toMaxLikelihood and prune) has one occupied leaf at depth 15.
  OccupancyMap map(tenth(), {8, 8});
  std::vector<MapPoint> cube;
  for (int i = 0; i < 8; ++i) cube.push_back({0.05f + 0.1f * (i & 1), 0.05f + 0.1f * (i >> 1 & 1), 0.05f + 0.1f * (i >> 2)});
  map.insert_scan(cube.data(), cube.size(), {0.05f, 0.05f, 0.05f});
  map.insert_scan(cube.data(), 1, {0.05f, 0.05f, 0.05f});  // the first voxel again: 2 hits
  float a, b;
  ASSERT_TRUE(map.log_odds(VoxelKey{{32768, 32768, 32768}}, a));
  ASSERT_TRUE(map.log_odds(VoxelKey{{32769, 32768, 32768}}, b));
  ASSERT_NE(a, b);
  OctomapBinaryWriter writer(8);
  std::vector<std::uint8_t> out;
  EXPECT_EQ(writer.write(map, out), 16u);
  std::vector<std::uint8_t> data = {0x00, 0xC0};
  for (int depth = 1; depth < 14; ++depth) data.insert(data.end(), {0x03, 0x00});
  data.insert(data.end(), {0x02, 0x00});
  EXPECT_EQ(out, bytes(header(16, "0.1"), data));
}

TEST(OctomapBinary, AFreeVoxelIsCodedOneAndResolutionPrintsLikeAStream) {
  OccupancyParams p;
  p.resolution = 0.05;
  OccupancyMap map(p, {8, 8});
  const MapPoint end{0.075f, 0.025f, 0.025f};  // one free voxel (the sensor's), one occupied
  map.insert_scan(&end, 1, {0.025f, 0.025f, 0.025f});
  OctomapBinaryWriter writer(8);
  std::vector<std::uint8_t> out;
  EXPECT_EQ(writer.write(map, out), 18u);  // root, depths 1-15, two voxels
  std::vector<std::uint8_t> data = {0x00, 0xC0};
  for (int depth = 1; depth < 15; ++depth) data.insert(data.end(), {0x03, 0x00});
  data.insert(data.end(), {0x09, 0x00});  // child 0 free (01), child 1 occupied (10)
  EXPECT_EQ(out, bytes(header(18, "0.05"), data));
}

TEST(MapDigest, FollowsTheContentsNotTheHistory) {
  const MapPoint a{0.55f, 0.05f, 0.05f}, b{0.05f, 0.85f, 0.05f};
  OccupancyMap first(tenth(), {16, 16}), second(tenth(), {16, 16});
  const MapPoint ab[2] = {a, b}, ba[2] = {b, a};
  first.insert_scan(ab, 2, {0.05f, 0.05f, 0.05f});
  second.insert_scan(ba, 2, {0.05f, 0.05f, 0.05f});
  EXPECT_EQ(map_digest(first), map_digest(second));
  second.insert_scan(&a, 1, {0.05f, 0.05f, 0.05f});
  EXPECT_NE(map_digest(first), map_digest(second));
}

}  // namespace octomap_binary_test
