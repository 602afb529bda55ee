// The voxels of a ray: OctoMap's traversal rules on rays whose answer can
// be worked out by hand.
#include "mapping/ray_traversal.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
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

// OctoMap 1.9.7's computeRayKeys as it is written (octomap/OcTreeBaseImpl.hxx),
// over this project's key conversions: the reference the fast walk, with
// its packed keys, integer compares and conditional moves, must equal.
bool octomap_ray(const VoxelGrid& grid, const MapPoint& origin, const MapPoint& end, std::vector<VoxelKey>& ray) {
  ray.clear();
  VoxelKey key_origin, key_end;
  if (!grid.key_of(origin, key_origin) || !grid.key_of(end, key_end)) return false;
  if (key_origin == key_end) return true;
  ray.push_back(key_origin);
  const float dx = end.x - origin.x, dy = end.y - origin.y, dz = end.z - origin.z;
  const double norm_sq = dx * dx + dy * dy + dz * dz;  // Vector3::norm_sq: a float sum, returned as double
  const float length = static_cast<float>(std::sqrt(norm_sq));
  const float direction[3] = {dx / length, dy / length, dz / length};
  const float o[3] = {origin.x, origin.y, origin.z};
  const double resolution = grid.resolution();
  int step[3];
  double t_max[3], t_delta[3];
  VoxelKey current = key_origin;
  for (unsigned i = 0; i < 3; ++i) {
    if (direction[i] > 0.0) {
      step[i] = 1;
    } else if (direction[i] < 0.0) {
      step[i] = -1;
    } else {
      step[i] = 0;
    }
    if (step[i] != 0) {
      double voxel_border = grid.centre(current.k[i]);
      voxel_border += static_cast<float>(step[i] * resolution * 0.5);
      t_max[i] = (voxel_border - o[i]) / direction[i];
      t_delta[i] = resolution / std::fabs(direction[i]);
    } else {
      t_max[i] = std::numeric_limits<double>::max();
      t_delta[i] = std::numeric_limits<double>::max();
    }
  }
  for (;;) {
    unsigned dim;
    if (t_max[0] < t_max[1]) {
      dim = t_max[0] < t_max[2] ? 0 : 2;
    } else {
      dim = t_max[1] < t_max[2] ? 1 : 2;
    }
    current.k[dim] = static_cast<std::uint16_t>(current.k[dim] + step[dim]);
    t_max[dim] += t_delta[dim];
    if (current == key_end) break;
    const double dist_from_origin = std::min(std::min(t_max[0], t_max[1]), t_max[2]);
    if (dist_from_origin > length) break;
    ray.push_back(current);
  }
  return true;
}

// Rays of every kind the fast walk treats apart: arbitrary, from and to
// voxel borders, along an axis, in a plane (a zero direction component),
// diagonal (ties between axes), at the map's edge.
MapPoint random_point(std::mt19937_64& rng, const VoxelGrid& grid, const MapPoint& near, float spread, int kind) {
  std::uniform_real_distribution<float> offset(-spread, spread);
  std::uniform_int_distribution<int> voxels(-40, 40);
  const auto border = [&](float c) {
    return static_cast<float>(std::floor(c / grid.resolution() + voxels(rng) % 3) * grid.resolution());
  };
  MapPoint p{near.x + offset(rng), near.y + offset(rng), near.z + offset(rng)};
  switch (kind) {
    case 1:  // on voxel borders
      p = {border(p.x), border(p.y), border(p.z)};
      break;
    case 2:  // along x
      p.y = near.y;
      p.z = near.z;
      break;
    case 3:  // in the x-y plane
      p.z = near.z;
      break;
    case 4: {  // a diagonal through the voxels' corners
      const float d = static_cast<float>(voxels(rng) * grid.resolution());
      p = {near.x + d, near.y + d, near.z - d};
      break;
    }
    default:
      break;
  }
  return p;
}

void expect_rays_like_octomap(double resolution, const MapPoint& centre, float spread, int rays, std::uint64_t seed) {
  const VoxelGrid grid(resolution);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> kind(0, 4);
  std::vector<VoxelKey> expected, actual;
  int differing = 0;
  for (int r = 0; r < rays; ++r) {
    const int k = kind(rng);
    const MapPoint from = random_point(rng, grid, centre, spread, k == 1 ? 1 : 0);
    const MapPoint to = random_point(rng, grid, from, spread, k);
    const bool expected_inside = octomap_ray(grid, from, to, expected);
    actual.clear();
    const bool inside = traverse_ray(grid, from, to, [&](const VoxelKey& key) { actual.push_back(key); });
    if (inside != expected_inside || actual != expected) {
      if (++differing <= 3) {
        ADD_FAILURE() << "ray " << r << " (kind " << k << ") from " << from.x << ' ' << from.y << ' ' << from.z
                      << " to " << to.x << ' ' << to.y << ' ' << to.z << ": " << actual.size() << " voxels, OctoMap "
                      << expected.size();
      }
    }
  }
  EXPECT_EQ(differing, 0);
}

TEST(RayTraversal, RandomRaysVisitOctomapsVoxels) {
  expect_rays_like_octomap(0.1, {0, 0, 0}, 12.0f, 60000, 1);
  expect_rays_like_octomap(0.05, {1.3f, -2.1f, 0.4f}, 6.0f, 60000, 2);
  expect_rays_like_octomap(0.25, {-3.0f, 7.0f, -1.0f}, 20.0f, 30000, 3);
  expect_rays_like_octomap(1.0, {0.5f, 0.5f, 0.5f}, 30.0f, 30000, 4);
}

TEST(RayTraversal, RandomRaysAtTheMapsEdgeVisitOctomapsVoxels) {
  // At 0.01 m the map ends at +-327.68 m: keys within a voxel or two of
  // 0 and 65535, and ends beyond it.
  expect_rays_like_octomap(0.01, {327.6f, 327.6f, -327.6f}, 0.2f, 20000, 5);
  expect_rays_like_octomap(0.01, {-327.66f, 0.0f, 327.66f}, 0.1f, 20000, 6);
}

}  // namespace ray_traversal_test
