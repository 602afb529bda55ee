// Lone obstacle cells dropped, everything else kept: pairs, lines, the
// grid's edges and corners, unknown and free untouched.
#include "navigation/speckle_filter.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace rtfuse::navigation {
namespace speckle_filter_test {

TEST(SpeckleFilter, LoneCellsGoNeighboursStay) {
  const int w = 6, h = 5;
  // clang-format off
  const std::vector<std::int8_t> in = {
      100, -1,   0,   0,   0, 100,
       -1,  0,   0, 100,   0,   0,
        0,  0,   0,   0, 100,   0,
        0, 100,  0,   0,   0,  -1,
      100, 100,  0,  70,   0, 100};
  const std::vector<std::int8_t> want = {
        0, -1,   0,   0,   0,   0,
       -1,  0,   0, 100,   0,   0,
        0,  0,   0,   0, 100,   0,
        0, 100,  0,   0,   0,  -1,
      100, 100,  0,   0,   0,   0};
  // clang-format on
  std::vector<std::int8_t> out(in.size(), 42);
  EXPECT_EQ(drop_speckles(in.data(), out.data(), w, h, 65), 4u);
  EXPECT_EQ(out, want);
}

TEST(SpeckleFilter, MatchesABruteForceNeighbourCount) {
  std::mt19937 rng(3);
  const int w = 37, h = 23;
  std::vector<std::int8_t> in(static_cast<std::size_t>(w * h));
  for (auto& v : in) {
    const int r = static_cast<int>(rng() % 10);
    v = static_cast<std::int8_t>(r == 0 ? 100 : r == 1 ? -1 : r == 2 ? 80 : 0);
  }
  std::vector<std::int8_t> out(in.size());
  const std::size_t dropped = drop_speckles(in.data(), out.data(), w, h, 65);
  std::size_t expect_dropped = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::int8_t v = in[static_cast<std::size_t>(y * w + x)];
      int n = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if ((dx || dy) && x + dx >= 0 && x + dx < w && y + dy >= 0 && y + dy < h &&
              in[static_cast<std::size_t>((y + dy) * w + x + dx)] >= 65)
            ++n;
      const bool lone = v >= 65 && n == 0;
      expect_dropped += lone ? 1 : 0;
      ASSERT_EQ(out[static_cast<std::size_t>(y * w + x)], lone ? 0 : v) << x << " " << y;
    }
  }
  EXPECT_EQ(dropped, expect_dropped);
  EXPECT_GT(dropped, 10u);
}

}  // namespace speckle_filter_test
}  // namespace rtfuse::navigation
