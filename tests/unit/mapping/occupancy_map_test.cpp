// OctoMap's update rules on scans small enough to follow by hand, and the
// fixed pool: what a full one does, and that nothing is allocated.
#include "mapping/occupancy_map.hpp"
#include "mapping/map_digest.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "support/alloc_counter.hpp"

namespace occupancy_map_test {

using namespace rtfuse::mapping;

OccupancyParams params(double resolution = 0.1) {
  OccupancyParams p;
  p.resolution = resolution;
  return p;
}

VoxelKey key_at(const OccupancyMap& map, float x, float y, float z) {
  VoxelKey k;
  EXPECT_TRUE(map.grid().key_of(MapPoint{x, y, z}, k));
  return k;
}

float value_at(const OccupancyMap& map, float x, float y, float z) {
  float v = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(map.log_odds(key_at(map, x, y, z), v)) << x << " " << y << " " << z;
  return v;
}

bool known_at(const OccupancyMap& map, float x, float y, float z) {
  float v;
  return map.log_odds(key_at(map, x, y, z), v);
}

TEST(OccupancyMap, ARayFreesItsVoxelsAndMarksItsEnd) {
  OccupancyMap map(params(), {64, 64});
  const MapPoint end{0.55f, 0.05f, 0.05f};
  const ScanResult r = map.insert_scan(&end, 1, {0.05f, 0.05f, 0.05f});
  EXPECT_EQ(r.hits, 1u);
  EXPECT_EQ(r.frees, 5u);
  EXPECT_EQ(map.known_voxels(), 6u);
  EXPECT_EQ(map.occupied_voxels(), 1u);
  EXPECT_EQ(value_at(map, 0.55f, 0.05f, 0.05f), map.log_odds().hit);
  EXPECT_EQ(value_at(map, 0.25f, 0.05f, 0.05f), map.log_odds().miss);
  EXPECT_FALSE(known_at(map, 0.65f, 0.05f, 0.05f));
}

TEST(OccupancyMap, AVoxelHitInAScanIsNotFreedByAnotherRayOfIt) {
  OccupancyMap map(params(), {64, 64});
  // The first ray ends at x = 0.35; the second passes through that voxel.
  const MapPoint scan[2] = {{0.35f, 0.05f, 0.05f}, {0.95f, 0.05f, 0.05f}};
  map.insert_scan(scan, 2, {0.05f, 0.05f, 0.05f});
  EXPECT_EQ(value_at(map, 0.35f, 0.05f, 0.05f), map.log_odds().hit);
  EXPECT_EQ(map.occupied_voxels(), 2u);
}

TEST(OccupancyMap, EachVoxelIsUpdatedOnceAScan) {
  OccupancyMap map(params(), {64, 64});
  const MapPoint scan[3] = {{0.51f, 0.05f, 0.05f}, {0.52f, 0.06f, 0.05f}, {0.53f, 0.07f, 0.08f}};
  const ScanResult r = map.insert_scan(scan, 3, {0.05f, 0.05f, 0.05f});
  EXPECT_EQ(r.hits, 1u);
  EXPECT_EQ(r.frees, 5u);
  EXPECT_EQ(value_at(map, 0.51f, 0.05f, 0.05f), map.log_odds().hit);
  EXPECT_EQ(value_at(map, 0.15f, 0.05f, 0.05f), map.log_odds().miss);
}

TEST(OccupancyMap, RepeatedScansSumAndClampAsFloats) {
  OccupancyMap map(params(), {64, 64});
  const MapPoint end{0.55f, 0.05f, 0.05f};
  float hit = 0.0f, miss = 0.0f;
  const LogOdds& lo = map.log_odds();
  for (int scan = 0; scan < 12; ++scan) {
    map.insert_scan(&end, 1, {0.05f, 0.05f, 0.05f});
    hit = std::min(hit + lo.hit, lo.clamp_max);
    miss = std::max(miss + lo.miss, lo.clamp_min);
    EXPECT_EQ(value_at(map, 0.55f, 0.05f, 0.05f), hit) << "scan " << scan;
    EXPECT_EQ(value_at(map, 0.15f, 0.05f, 0.05f), miss) << "scan " << scan;
  }
  EXPECT_EQ(hit, lo.clamp_max);
  EXPECT_EQ(miss, lo.clamp_min);
  // A free voxel turns occupied after enough hits, and the count follows.
  const MapPoint wall{0.15f, 0.05f, 0.05f};
  for (int scan = 0; scan < 3; ++scan) map.insert_scan(&wall, 1, {0.05f, 0.05f, 0.05f});
  EXPECT_EQ(map.occupied_voxels(), 2u);
}

TEST(OccupancyMap, RaysBeyondTheMaximumRangeFreeUpToItAndMarkNothing) {
  OccupancyMap map(params(), {64, 64});
  const MapPoint far{3.05f, 0.05f, 0.05f};
  const ScanResult r = map.insert_scan(&far, 1, {0.05f, 0.05f, 0.05f}, 1.0);
  EXPECT_EQ(r.beyond_range, 1u);
  EXPECT_EQ(r.hits, 0u);
  EXPECT_EQ(map.occupied_voxels(), 0u);
  EXPECT_EQ(r.frees, 10u);  // 0.05 .. 0.95; the voxel of 1.05 is the ray's end
  EXPECT_FALSE(known_at(map, 1.05f, 0.05f, 0.05f));
}

TEST(OccupancyMap, NonFinitePointsAreCountedAndSkipped) {
  OccupancyMap map(params(), {64, 64});
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const MapPoint scan[3] = {{nan, 0, 0}, {0.55f, inf, 0}, {0.55f, 0.05f, 0.05f}};
  const ScanResult r = map.insert_scan(scan, 3, {0.05f, 0.05f, 0.05f});
  EXPECT_EQ(r.rejected, 2u);
  EXPECT_EQ(r.hits, 1u);
  EXPECT_EQ(map.known_voxels(), 6u);
}

TEST(OccupancyMap, ANonFiniteOriginRefusesTheWholeScan) {
  OccupancyMap map(params(), {64, 64});
  const MapPoint end{0.55f, 0.05f, 0.05f};
  const ScanResult r = map.insert_scan(&end, 1, {std::numeric_limits<float>::quiet_NaN(), 0, 0});
  EXPECT_EQ(r.rejected, 1u);
  EXPECT_EQ(map.known_voxels(), 0u);
}

TEST(OccupancyMap, EndPointsOutsideTheMapAreCounted) {
  OccupancyMap map(params(0.001), {64, 64});  // +-32.768 m
  const MapPoint scan[1] = {{40.0f, 0, 0}};
  const ScanResult r = map.insert_scan(scan, 1, {0, 0, 0});
  EXPECT_EQ(r.outside, 1u);
  EXPECT_EQ(map.known_voxels(), 0u);
}

TEST(OccupancyMap, AFullPoolDropsUpdatesCountedAndStopsGrowing) {
  OccupancyMap map(params(0.05), {2, 3});  // two bricks, three dense blocks
  std::vector<MapPoint> scan;
  for (int i = 0; i < 50; ++i) scan.push_back({2.0f + 0.1f * i, 0.5f * i, -1.0f});
  const ScanResult r = map.insert_scan(scan.data(), scan.size(), {0, 0, 0});
  EXPECT_GT(r.dropped, 0u);
  EXPECT_EQ(map.dropped_updates(), r.dropped);
  EXPECT_EQ(map.store().bricks_used(), 2u);
  EXPECT_LE(map.known_voxels(), 3u * 64u);
  // Later scans still find only those two bricks.
  for (int k = 0; k < 3; ++k) map.insert_scan(scan.data(), scan.size(), {0.01f * k, 0, 0});
  EXPECT_EQ(map.store().bricks_used(), 2u);
  EXPECT_LE(map.known_voxels(), 2u * 512u);
  float v;
  map.for_each_voxel([&](const VoxelKey& k, float value) {
    ASSERT_TRUE(map.log_odds(k, v));
    EXPECT_EQ(v, value);
    EXPECT_FALSE(std::isnan(value));
  });
}

TEST(OccupancyMap, UniformSubBricksGiveTheirBlocksBack) {
  OccupancyMap map(params(0.1), {256, 4096});
  // Every voxel of the sub-brick [0.4, 0.8)^3 hit: one value, no block.
  std::vector<MapPoint> scan;
  for (int x = 0; x < 4; ++x)
    for (int y = 0; y < 4; ++y)
      for (int z = 0; z < 4; ++z) scan.push_back({0.45f + 0.1f * x, 0.45f + 0.1f * y, 0.45f + 0.1f * z});
  map.insert_scan(scan.data(), scan.size(), {-2.05f, -2.05f, -2.05f});
  const VoxelKey k = key_at(map, 0.45f, 0.45f, 0.45f);
  const std::uint32_t brick = map.store().find(brick_key_of(k));
  ASSERT_NE(brick, kNone);
  const std::uint32_t slot = map.store().brick(brick).sub[sub_of(k)];
  EXPECT_FALSE(is_dense(slot));
  EXPECT_EQ(OccupancyMap::float_of(slot), map.log_odds().hit);
  std::uint64_t voxels = 0;
  map.for_each_voxel([&](const VoxelKey&, float) { ++voxels; });
  EXPECT_EQ(voxels, map.known_voxels());
  EXPECT_EQ(map.occupied_voxels(), 64u);
}

TEST(OccupancyMap, InsertingAllocatesNothing) {
  OccupancyMap map(params(0.05), {4096, 16384});
  std::vector<MapPoint> scan;
  for (int i = 0; i < 500; ++i) scan.push_back({4.0f * std::cos(0.01f * i), 4.0f * std::sin(0.01f * i), 0.3f});
  map.insert_scan(scan.data(), scan.size(), {0, 0, 0});
  rtfuse::test::AllocScope scope;
  for (int k = 0; k < 3; ++k) map.insert_scan(scan.data(), scan.size(), {0.1f * k, 0, 0}, 3.0);
  map.clear();
  map.insert_scan(scan.data(), scan.size(), {0, 0, 0});
  EXPECT_EQ(scope.count(), 0u);
}

TEST(OccupancyMap, BadParametersAreRefusedWithTheirRange) {
  OccupancyParams p;
  p.prob_hit = 0.4;
  EXPECT_EQ(check(p), "prob_hit 0.4 must be in (0.5, 1)");
  p = OccupancyParams{};
  p.clamp_max = 0.3;
  EXPECT_EQ(check(p), "clamp_max 0.3 must be in (occupancy_threshold, 1)");
  p = OccupancyParams{};
  p.resolution = 0.0;
  EXPECT_THROW(OccupancyMap(p, {1, 1}), std::invalid_argument);
  EXPECT_THROW(OccupancyMap(OccupancyParams{}, {0, 1}), std::invalid_argument);
  EXPECT_EQ(check(OccupancyParams{}), "");
}

TEST(OccupancyMap, DefaultsAreOctomapsLogOdds) {
  const LogOdds lo = log_odds_of(OccupancyParams{});
  // logit(0.7), logit(0.4), logit(0.1192), logit(0.971), logit(0.5) as float32.
  EXPECT_EQ(lo.hit, 0.847297847f);
  EXPECT_EQ(lo.miss, -0.405465096f);
  EXPECT_EQ(lo.clamp_min, -2.00002789f);
  EXPECT_EQ(lo.clamp_max, 3.51103067f);
  EXPECT_EQ(lo.occupied, 0.0f);
}

}  // namespace occupancy_map_test

namespace occupancy_map_test {

// The same bits on every machine: a cloud made with integer hashing and
// float + - * / only, three scans from three origins with a range limit,
// and the map's digest and its .bt's size against the values this build
// gives on x86-64. The aarch64 stage (tools/test-cross.sh) runs this test
// under emulation: a different float rounding anywhere in the ray or the
// sums (a contracted multiply-add, a library's sqrt) changes the digest.
TEST(OccupancyMap, TheSameCloudGivesTheSameBitsOnEveryMachine) {
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  const auto next = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<float>(state >> 40) / static_cast<float>(1u << 24);  // [0, 1)
  };
  std::vector<MapPoint> cloud;
  for (int i = 0; i < 20000; ++i) {
    // Points on the walls and floor of a 10 x 8 x 3 m room, jittered.
    const float a = next(), b = next(), c = next();
    switch (i % 5) {
      case 0: cloud.push_back({-5.0f + 10.0f * a, -4.0f + 0.02f * c, 3.0f * b}); break;
      case 1: cloud.push_back({-5.0f + 10.0f * a, 4.0f - 0.02f * c, 3.0f * b}); break;
      case 2: cloud.push_back({5.0f - 0.02f * c, -4.0f + 8.0f * a, 3.0f * b}); break;
      case 3: cloud.push_back({-5.0f + 0.02f * c, -4.0f + 8.0f * a, 3.0f * b}); break;
      default: cloud.push_back({-5.0f + 10.0f * a, -4.0f + 8.0f * b, 0.01f * c}); break;
    }
  }
  OccupancyMap map(params(0.05), {8192, 65536});
  map.insert_scan(cloud.data(), cloud.size(), {0.013f, -0.021f, 1.2f}, -1.0);
  map.insert_scan(cloud.data(), cloud.size() / 2, {1.51f, 0.77f, 1.0f}, 4.0);
  map.insert_scan(cloud.data() + 1000, cloud.size() - 1000, {-2.2f, 1.3f, 0.5f}, 6.5);
  EXPECT_EQ(map.known_voxels(), 1317585u);
  EXPECT_EQ(map.occupied_voxels(), 17032u);
  EXPECT_EQ(map_digest(map), 0xa72f5d04ed728da1ull);
}

}  // namespace occupancy_map_test
