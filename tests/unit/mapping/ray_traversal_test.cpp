// The voxels of a ray: OctoMap's traversal rules on rays whose answer can
// be worked out by hand.
#include "mapping/ray_traversal.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace ray_traversal_test {

using rtfuse::mapping::MapPoint;
using rtfuse::mapping::traverse_ray;
using rtfuse::mapping::VoxelGrid;
using rtfuse::mapping::VoxelKey;

std::vector<VoxelKey> ray(const VoxelGrid& grid, MapPoint from, MapPoint to, bool* inside = nullptr) {
  std::vector<VoxelKey> keys;
  const bool ok = traverse_ray(grid, from, to, [&](const VoxelKey& k) { keys.push_back(k); });
  if (inside) *inside = ok;
  return keys;
}

TEST(RayTraversal, AlongAnAxisVisitsEveryVoxelButTheEndOne) {
  const VoxelGrid grid(0.1);
  const auto keys = ray(grid, {0.05f, 0.05f, 0.05f}, {0.55f, 0.05f, 0.05f});
  ASSERT_EQ(keys.size(), 5u);  // voxels 0..4 along x; voxel 5 holds the end point
  for (std::size_t i = 0; i < keys.size(); ++i) {
    EXPECT_EQ(keys[i].k[0], 32768 + i);
    EXPECT_EQ(keys[i].k[1], 32768);
    EXPECT_EQ(keys[i].k[2], 32768);
  }
}

TEST(RayTraversal, NegativeDirectionsStepDown) {
  const VoxelGrid grid(0.1);
  const auto keys = ray(grid, {0.05f, 0.05f, 0.05f}, {0.05f, -0.25f, 0.05f});
  ASSERT_EQ(keys.size(), 3u);
  EXPECT_EQ(keys[0].k[1], 32768);
  EXPECT_EQ(keys[1].k[1], 32767);
  EXPECT_EQ(keys[2].k[1], 32766);
}

TEST(RayTraversal, ADiagonalCrossesOneFaceAtATime) {
  const VoxelGrid grid(1.0);
  const auto keys = ray(grid, {0.5f, 0.2f, 0.5f}, {3.5f, 2.4f, 0.5f});
  ASSERT_FALSE(keys.empty());
  for (std::size_t i = 1; i < keys.size(); ++i) {
    const int dx = keys[i].k[0] - keys[i - 1].k[0], dy = keys[i].k[1] - keys[i - 1].k[1];
    EXPECT_EQ(dx + dy, 1) << "step " << i;  // a 6-connected walk, never a corner jump
    EXPECT_EQ(keys[i].k[2], keys[0].k[2]);
  }
  // It ends next to the end voxel (32771, 32770).
  const VoxelKey last = keys.back();
  EXPECT_EQ(std::abs(last.k[0] - 32771) + std::abs(last.k[1] - 32770), 1);
}

TEST(RayTraversal, ARayInsideOneVoxelVisitsNothing) {
  const VoxelGrid grid(0.1);
  bool inside = false;
  EXPECT_TRUE(ray(grid, {0.01f, 0.01f, 0.01f}, {0.09f, 0.02f, 0.03f}, &inside).empty());
  EXPECT_TRUE(inside);
}

TEST(RayTraversal, EndsOutsideTheMapAreRefused) {
  const VoxelGrid grid(0.01);  // the map spans +-327.68 m
  bool inside = true;
  EXPECT_TRUE(ray(grid, {0, 0, 0}, {400.0f, 0, 0}, &inside).empty());
  EXPECT_FALSE(inside);
  EXPECT_TRUE(ray(grid, {0, 0, 0}, {1.0f, std::numeric_limits<float>::quiet_NaN(), 0}, &inside).empty());
  EXPECT_FALSE(inside);
}

TEST(RayTraversal, AnOriginOnAVoxelBorderStillStartsInItsOwnVoxel) {
  // Exactly on the lower border going down: OctoMap's first distance is a
  // zero (or below, after rounding), the case the integer compares leave
  // to the plain loop.
  const VoxelGrid grid(0.25);
  const auto keys = ray(grid, {0.5f, 0.1f, 0.1f}, {-0.6f, 0.1f, 0.1f});
  ASSERT_EQ(keys.size(), 5u);
  EXPECT_EQ(keys[0].k[0], 32770);
  EXPECT_EQ(keys[4].k[0], 32766);
}

}  // namespace ray_traversal_test
