// The digest and the 2-D grid kept up to date scan by scan (MapDigest,
// ProjectedGrid) against the same computed from the whole map: they must
// never differ, whatever the scans free, hit, compact into whole
// sub-bricks, or fail to store for a full pool, refreshed after every scan
// or after several.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "mapping/grid_projection.hpp"
#include "mapping/map_digest.hpp"

namespace incremental_map_views_test {

using namespace rtfuse::mapping;

// Scans of a room with pillars from a sensor wandering through it: rays
// end on walls, on pillars, short of them (clutter) and beyond the range.
std::vector<MapPoint> scan_from(const MapPoint& o, std::mt19937& rng) {
  std::uniform_real_distribution<float> yaw(-3.14159f, 3.14159f), pitch(-0.6f, 0.6f), unit(0.0f, 1.0f);
  std::vector<MapPoint> points;
  for (int i = 0; i < 1500; ++i) {
    const float a = yaw(rng), e = pitch(rng);
    const float dx = std::cos(e) * std::cos(a), dy = std::cos(e) * std::sin(a), dz = std::sin(e);
    // Distance to the room's walls (x, y in [-4, 4]), floor 0 and ceiling 2.5.
    float t = 20.0f;
    if (dx != 0.0f) t = std::min(t, ((dx > 0 ? 4.0f : -4.0f) - o.x) / dx);
    if (dy != 0.0f) t = std::min(t, ((dy > 0 ? 4.0f : -4.0f) - o.y) / dy);
    if (dz != 0.0f) t = std::min(t, ((dz > 0 ? 2.5f : 0.0f) - o.z) / dz);
    if (unit(rng) < 0.2f) t *= unit(rng);  // clutter in the room
    points.push_back({o.x + t * dx, o.y + t * dy, o.z + t * dz});
  }
  return points;
}

// dropped: the updates the pool could not hold.
void check_scans(const OccupancyParams& params, BrickCapacity capacity, double max_range, std::uint64_t* dropped) {
  OccupancyMap map(params, capacity);
  MapDigest digest(map);
  const GridSpec spec = grid_around(map.grid(), 0.3, -0.2, 70, 90, 0.1, 1.5);  // smaller than the room
  ProjectedGrid grid(map, spec);
  std::vector<std::int8_t> whole(spec.cells());
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> place(-3.0f, 3.0f);
  for (int scan = 0; scan < 40; ++scan) {
    const MapPoint origin{place(rng), place(rng), 0.4f};
    const std::vector<MapPoint> points = scan_from(origin, rng);
    map.insert_scan(points.data(), points.size(), origin, max_range);
    digest.note_scan(map);
    grid.note_scan(map);
    if (scan % 3 == 1) continue;  // refreshed after one scan, or after three
    const std::int8_t* cells = grid.refresh(map);
    const std::vector<std::int8_t> kept(cells, cells + spec.cells());
    project_to_grid(map, spec, whole.data());
    ASSERT_EQ(digest.refresh(map), map_digest(map)) << "scan " << scan;
    ASSERT_EQ(kept, whole) << "scan " << scan;
  }
  EXPECT_GT(map.occupied_voxels(), 500u);
  *dropped = map.dropped_updates();
  map.clear();
  digest.rebuild(map);
  EXPECT_EQ(digest.refresh(map), map_digest(map));
}

TEST(IncrementalMapViews, MatchTheWholeMapAfterEveryScan) {
  OccupancyParams p;
  p.resolution = 0.1;
  std::uint64_t dropped = 1;
  check_scans(p, {4096, 16384}, 5.0, &dropped);
  EXPECT_EQ(dropped, 0u);
}

TEST(IncrementalMapViews, MatchAtFineResolutionWithoutRange) {
  OccupancyParams p;
  p.resolution = 0.05;
  std::uint64_t dropped = 1;
  check_scans(p, {16384, 65536}, -1.0, &dropped);
  EXPECT_EQ(dropped, 0u);
}

TEST(IncrementalMapViews, MatchWhenThePoolRunsOut) {
  OccupancyParams p;
  p.resolution = 0.05;
  std::uint64_t dropped = 0;
  check_scans(p, {300, 400}, -1.0, &dropped);
  EXPECT_GT(dropped, 0u);
}

}  // namespace incremental_map_views_test
