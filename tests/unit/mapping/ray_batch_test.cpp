// Four rays in AVX2 lanes visit the voxels each visits alone, and the
// window's vector test leaves out only voxels already marked.
#include "mapping/ray_batch.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "mapping/scan_window.hpp"

namespace ray_batch_test {

using namespace rtfuse::mapping;

// Rays from one origin to points at up to `reach` metres, some along axes
// and diagonals (ties between the axes' distances), some random.
std::vector<MapPoint> ends(int count, float reach, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-reach, reach);
  std::vector<MapPoint> out;
  const float axis[] = {0.0f, 1.0f, -1.0f};
  for (float x : axis)
    for (float y : axis)
      for (float z : axis) out.push_back({x * reach * 0.7f + 0.013f, y * reach * 0.7f - 0.021f, z * reach * 0.5f});
  while (static_cast<int>(out.size()) < count) out.push_back({u(rng), u(rng), u(rng)});
  return out;
}

// Every voxel after the origin's, each ray alone (run_ray) and four at a
// time (step_rays4, lanes refilled as rays end): the same multiset.
std::vector<std::uint64_t> alone(const VoxelGrid& grid, const MapPoint& origin, const std::vector<MapPoint>& to) {
  std::vector<std::uint64_t> keys;
  auto push = [&](std::uint64_t k) { keys.push_back(k); };
  for (const MapPoint& p : to) {
    RayState state{};
    detail::RaySetup setup;
    if (start_ray(grid, origin, p, state, setup) == RayStart::kFast) run_ray(state, push);
  }
  return keys;
}

std::vector<std::uint64_t> batched(const VoxelGrid& grid, const MapPoint& origin, const std::vector<MapPoint>& to,
                                   const ScanWindow::Probe& window, std::size_t capacity) {
  std::vector<std::uint64_t> keys;
  std::vector<std::uint64_t> out(capacity);
  RayState lanes[4] = {};
  unsigned live = 0;
  const auto run = [&](bool drain) {
    while (live == 15u || (drain && live != 0)) {
      const std::size_t n = step_rays4(lanes, live, window, out.data(), out.size());
      keys.insert(keys.end(), out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n));
    }
  };
  for (const MapPoint& p : to) {
    RayState state{};
    detail::RaySetup setup;
    if (start_ray(grid, origin, p, state, setup) != RayStart::kFast) continue;
    const int lane = __builtin_ctz(~live & 15u);
    lanes[lane] = state;
    live |= 1u << lane;
    run(false);
  }
  run(true);
  return keys;
}

TEST(RayBatch, FourLanesVisitWhatEachRayVisitsAlone) {
  if (!ray_batch_available()) GTEST_SKIP() << "no AVX2 here: the rays are stepped one by one";
  for (double resolution : {0.05, 0.1, 0.37}) {
    const VoxelGrid grid(resolution);
    const MapPoint origin{0.031f, -0.017f, 0.52f};
    const std::vector<MapPoint> to = ends(2000, 9.0f, static_cast<std::uint32_t>(resolution * 1000));
    ScanWindow none;  // never begun: every voxel is outside it, so every one comes out
    for (std::size_t capacity : {std::size_t{4}, std::size_t{7}, std::size_t{4096}}) {
      std::vector<std::uint64_t> a = alone(grid, origin, to);
      std::vector<std::uint64_t> b = batched(grid, origin, to, none.probe(), capacity);
      ASSERT_GT(a.size(), 20000u);
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      EXPECT_EQ(a, b) << "resolution " << resolution << ", capacity " << capacity;
    }
  }
}

TEST(RayBatch, VoxelsMarkedInTheWindowAreLeftOutAndNoOthers) {
  if (!ray_batch_available()) GTEST_SKIP() << "no AVX2 here: the rays are stepped one by one";
  const VoxelGrid grid(0.1);
  const MapPoint origin{0.031f, -0.017f, 0.52f};
  // Far enough that the rays leave the window's 256-voxel cube.
  const std::vector<MapPoint> to = ends(1000, 16.0f, 7);
  std::vector<std::uint64_t> all = alone(grid, origin, to);
  ScanWindow window;
  VoxelKey key;
  ASSERT_TRUE(grid.key_of(origin, key));
  window.begin(key);
  const ScanWindow::Probe probe = window.probe();
  // Mark every other distinct voxel the rays visit that lies inside.
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  std::vector<std::uint64_t> marked, expected;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i % 2 == 0 && probe.visit(all[i])) {
      marked.push_back(all[i]);
    } else {
      expected.push_back(all[i]);
    }
  }
  ASSERT_GT(marked.size(), 1000u);
  std::vector<std::uint64_t> got = batched(grid, origin, to, probe, 4096);
  std::sort(got.begin(), got.end());
  got.erase(std::unique(got.begin(), got.end()), got.end());
  EXPECT_EQ(got, expected);  // every voxel not marked (outside ones included), no marked one
  window.drain([](std::uint64_t, const std::uint64_t*) {});
}

}  // namespace ray_batch_test
