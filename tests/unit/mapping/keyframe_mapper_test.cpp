// One stereo pair into the map: a textured wall at a known depth becomes
// occupied voxels at that depth with free space before it; beyond the
// maximum range it frees and marks nothing; a camera or memory that cannot
// work is refused at creation with what to change.
#include "mapping/keyframe_mapper.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "mapping/voxel_key.hpp"

namespace keyframe_mapper_test {
using namespace rtfuse;  // NOLINT

constexpr int kW = 320, kH = 240, kShift = 16;  // a wall 16 px of disparity away
constexpr double kF = 320.0, kB = 0.12;          // Z = f B / d = 2.4 m

struct Pair {
  std::vector<std::uint8_t> left, right;
};

// Random texture; the right eye sees it kShift px to the left (u_r = u_l - d).
Pair wall() {
  Pair p;
  p.left.resize(kW * kH);
  p.right.resize(kW * kH);
  std::uint32_t s = 12345;
  std::vector<std::uint8_t> tex((kW + kShift) * kH);
  for (auto& v : tex) {
    s = s * 1664525u + 1013904223u;
    v = static_cast<std::uint8_t>(s >> 24);
  }
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      p.left[y * kW + x] = tex[y * (kW + kShift) + x];
      p.right[y * kW + x] = tex[y * (kW + kShift) + x + kShift];
    }
  }
  return p;
}

mapping::KeyframeMapperParams params() {
  mapping::KeyframeMapperParams p;
  p.disparity.disparities = 64;
  p.disparity.downscale = 2;
  p.occupancy.resolution = 0.05;
  p.max_range_m = 6.0;
  p.pool_bytes = std::size_t{32} << 20;
  return p;
}

float log_odds_at(const mapping::OccupancyMap& map, double x, double y, double z, bool* known) {
  mapping::VoxelKey key;
  *known = false;
  if (!map.grid().key_of(x, key.k[0]) || !map.grid().key_of(y, key.k[1]) || !map.grid().key_of(z, key.k[2])) {
    return 0.0f;
  }
  float v = 0.0f;
  *known = map.log_odds(key, v);
  return v;
}

TEST(KeyframeMapper, AWallAtAKnownDepthIsOccupiedThereAndFreeBefore) {
  const vision::StereoCameraModel camera{kF, kW / 2.0, kH / 2.0, kB};
  std::string error;
  auto mapper = mapping::KeyframeMapper::create(kW, kH, camera, params(), &error);
  ASSERT_TRUE(mapper) << error;
  const Pair p = wall();
  // The camera at the map's origin looking along +z (its optical frame).
  const mapping::KeyframePoints pts = mapper->points_of({p.left.data(), kW, kH, kW}, {p.right.data(), kW, kH, kW},
                                                        geometry::RigidTransform::identity());
  ASSERT_TRUE(pts.ok);
  // Most of the half-resolution image matches (the left margin cannot).
  EXPECT_GT(pts.counts.points, 160u * 120u * 3 / 4);
  const mapping::ScanResult r = mapper->insert();
  EXPECT_EQ(r.points, pts.counts.points);
  EXPECT_GT(r.hits, 100u);
  EXPECT_EQ(r.dropped, 0u);
  const mapping::OccupancyMap& map = mapper->map();
  bool known = false;
  const double depth = kF * kB / kShift;
  EXPECT_TRUE(map.is_occupied(log_odds_at(map, 0.01, 0.01, depth, &known)));
  EXPECT_TRUE(known);
  EXPECT_FALSE(map.is_occupied(log_odds_at(map, 0.01, 0.01, depth / 2, &known)));
  EXPECT_TRUE(known);
  log_odds_at(map, 0.01, 0.01, depth + 0.3, &known);
  EXPECT_FALSE(known);  // behind the wall: never seen
}

TEST(KeyframeMapper, BeyondTheMaximumRangeItFreesAndMarksNothing) {
  const vision::StereoCameraModel camera{kF, kW / 2.0, kH / 2.0, kB};
  mapping::KeyframeMapperParams p = params();
  p.max_range_m = 1.5;  // the wall is at 2.4 m
  std::string error;
  auto mapper = mapping::KeyframeMapper::create(kW, kH, camera, p, &error);
  ASSERT_TRUE(mapper) << error;
  const Pair pair = wall();
  ASSERT_TRUE(mapper->points_of({pair.left.data(), kW, kH, kW}, {pair.right.data(), kW, kH, kW},
                                geometry::RigidTransform::identity())
                  .ok);
  const mapping::ScanResult r = mapper->insert();
  EXPECT_EQ(r.hits, 0u);
  EXPECT_EQ(r.beyond_range, r.points);
  EXPECT_GT(r.frees, 0u);
  EXPECT_EQ(mapper->map().occupied_voxels(), 0u);
}

TEST(KeyframeMapper, RefusesACameraWithoutBaselineAndAPoolTooSmallForOneKeyframe) {
  std::string error;
  EXPECT_FALSE(mapping::KeyframeMapper::create(kW, kH, {kF, kW / 2.0, kH / 2.0, 0.0}, params(), &error));
  EXPECT_NE(error.find("baseline 0"), std::string::npos) << error;
  mapping::KeyframeMapperParams small = params();
  small.pool_bytes = 1 << 20;
  small.max_range_m = 20.0;
  EXPECT_FALSE(mapping::KeyframeMapper::create(kW, kH, {kF, kW / 2.0, kH / 2.0, kB}, small, &error));
  EXPECT_NE(error.find("lower max_range"), std::string::npos) << error;
  mapping::KeyframeMapperParams wide = params();
  wide.disparity.disparities = 512;  // not narrower than the half-size image
  EXPECT_FALSE(mapping::KeyframeMapper::create(kW, kH, {kF, kW / 2.0, kH / 2.0, kB}, wide, &error));
  EXPECT_NE(error.find("disparit"), std::string::npos) << error;
}

}  // namespace keyframe_mapper_test
