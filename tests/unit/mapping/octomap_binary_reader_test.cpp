// Reading .bt files back: what the writer wrote, loaded as OctoMap loads
// it, and every way a file can be wrong refused with where and why.
#include "mapping/octomap_binary_reader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "mapping/octomap_binary.hpp"

namespace octomap_binary_reader_test {

using namespace rtfuse::mapping;

OccupancyParams res(double r) {
  OccupancyParams p;
  p.resolution = r;
  return p;
}

std::vector<std::uint8_t> bt_of(const OccupancyMap& map) {
  OctomapBinaryWriter writer(map.store().capacity().bricks);
  std::vector<std::uint8_t> out;
  writer.write(map, out);
  return out;
}

std::vector<std::uint8_t> bytes(const std::string& s) { return std::vector<std::uint8_t>(s.begin(), s.end()); }

TEST(OctomapBinaryReader, WhatTheWriterWroteLoadsAsOctomapLoadsIt) {
  OccupancyMap map(res(0.1), {1024, 8192});
  std::vector<MapPoint> scan;
  for (int i = 0; i < 400; ++i) scan.push_back({3.0f * std::cos(0.0157f * i), 3.0f * std::sin(0.0157f * i), 0.4f});
  map.insert_scan(scan.data(), scan.size(), {0.05f, 0.05f, 0.45f});
  map.insert_scan(scan.data(), 200, {0.55f, 0.25f, 0.45f});
  const std::vector<std::uint8_t> file = bt_of(map);

  OccupancyMap loaded(res(0.1), {1024, 8192});
  std::string error;
  ASSERT_TRUE(read_octomap_binary(file.data(), file.size(), "scan.bt", loaded, &error)) << error;
  EXPECT_EQ(loaded.known_voxels(), map.known_voxels());
  EXPECT_EQ(loaded.occupied_voxels(), map.occupied_voxels());
  // Every voxel at the clamp of its side, as OctoMap's readBinary sets them.
  map.for_each_voxel([&](const VoxelKey& k, float v) {
    float w;
    ASSERT_TRUE(loaded.log_odds(k, w));
    EXPECT_EQ(w, v >= map.log_odds().occupied ? map.log_odds().clamp_max : map.log_odds().clamp_min);
  });
  // And writing it again gives a file OctoMap would read into the same leaves.
  OccupancyMap again(res(0.1), {1024, 8192});
  const std::vector<std::uint8_t> second = bt_of(loaded);
  ASSERT_TRUE(read_octomap_binary(second.data(), second.size(), "again.bt", again, &error)) << error;
  EXPECT_EQ(again.known_voxels(), map.known_voxels());
}

TEST(OctomapBinaryReader, ACoarseLeafCostsItsBricksNotItsVoxels) {
  // Root, then inner nodes down to one free leaf at depth 10: 64^3 voxels.
  std::string file = "# Octomap OcTree binary file\nid OcTree\nsize 11\nres 0.1\ndata\n";
  file += std::string("\x00\xC0", 2);                                            // root: child 7 inner
  for (int d = 1; d < 9; ++d) file += std::string("\x03\x00", 2);                // child 0 inner
  file += std::string("\x01\x00", 2);                                            // depth 9: child 0 a free leaf
  OccupancyMap map(res(0.1), {1024, 16});
  std::string error;
  const std::vector<std::uint8_t> b = bytes(file);
  ASSERT_TRUE(read_octomap_binary(b.data(), b.size(), "coarse.bt", map, &error)) << error;
  EXPECT_EQ(map.known_voxels(), 64u * 64u * 64u);
  EXPECT_EQ(map.occupied_voxels(), 0u);
  EXPECT_EQ(map.store().bricks_used(), 512u);
  EXPECT_EQ(map.store().blocks_used(), 0u);
  float v;
  ASSERT_TRUE(map.log_odds(VoxelKey{{32768 + 63, 32768 + 5, 32768 + 40}}, v));
  EXPECT_EQ(v, map.log_odds().clamp_min);
  EXPECT_FALSE(map.log_odds(VoxelKey{{32768 + 64, 32768, 32768}}, v));
}

void expect_refused(const std::string& file, const char* words, BrickCapacity pool = {64, 64}) {
  OccupancyMap map(res(0.1), pool);
  std::string error;
  const std::vector<std::uint8_t> b = bytes(file);
  EXPECT_FALSE(read_octomap_binary(b.data(), b.size(), "bad.bt", map, &error)) << words;
  EXPECT_EQ(error.rfind("bad.bt", 0), 0u) << error;
  EXPECT_NE(error.find(words), std::string::npos) << error;
  map.for_each_voxel([](const VoxelKey&, float v) { EXPECT_FALSE(std::isnan(v)); });
}

TEST(OctomapBinaryReader, BrokenFilesAreRefusedWithWhereAndWhy) {
  const std::string head = "# Octomap OcTree binary file\nid OcTree\nsize 17\nres 0.1\ndata\n";
  std::string one_voxel = std::string("\x00\xC0", 2);
  for (int d = 1; d < 15; ++d) one_voxel += std::string("\x03\x00", 2);
  one_voxel += std::string("\x02\x00", 2);
  {
    OccupancyMap map(res(0.1), {64, 64});
    std::string error;
    const std::vector<std::uint8_t> b = bytes(head + one_voxel);
    ASSERT_TRUE(read_octomap_binary(b.data(), b.size(), "ok.bt", map, &error)) << error;
    EXPECT_EQ(map.occupied_voxels(), 1u);
  }
  expect_refused("P5\n3 2\n255\n", "not an OctoMap binary tree");
  expect_refused(head + one_voxel.substr(0, 17), "cut short at byte");
  expect_refused("# Octomap OcTree binary file\nid ColorOcTree\nsize 17\nres 0.1\ndata\n" + one_voxel,
                 "only OcTree");
  expect_refused("# Octomap OcTree binary file\nid OcTree\nsize 17\ndata\n" + one_voxel, "no \"res\"");
  expect_refused("# Octomap OcTree binary file\nid OcTree\nsize 17\nres 0.05\ndata\n" + one_voxel,
                 "the map's is");
  expect_refused("# Octomap OcTree binary file\nid OcTree\nsize 17\nres -3\ndata\n" + one_voxel, "bad.bt:4:");
  expect_refused("# Octomap OcTree binary file\nid OcTree\nsize 12\nres 0.1\ndata\n" + one_voxel,
                 "the header says 12 nodes, the tree holds 17");
  expect_refused(head + one_voxel + "xx", "2 bytes after the tree");
  expect_refused("# Octomap OcTree binary file\nid OcTree\nsize 1\nres 0.1\n", "no \"data\" line");
  std::string too_deep = one_voxel;
  too_deep[too_deep.size() - 2] = '\x03';  // the depth-15 node's child an inner node
  expect_refused(head + too_deep, "the tree ends at depth 16");
  // A root of eight free leaves: half the world, no pool holds it.
  expect_refused("# Octomap OcTree binary file\nid OcTree\nsize 9\nres 0.1\ndata\n" + std::string("\x55\x55", 2),
                 "cannot hold the file");
}

}  // namespace octomap_binary_reader_test
