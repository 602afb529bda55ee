// The index finds exactly the features of a class inside a window, in row
// then column order, for any window, against a plain scan.
#include "vision/feature_index.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace rtfuse::vision {
namespace feature_index_test {

TEST(FeatureIndex, FindsExactlyWhatAScanFinds) {
  const int w = 120, h = 80;
  std::mt19937 rng(9);
  std::vector<Feature> f(700);
  for (Feature& x : f) {
    x.u = static_cast<int>(rng() % w);
    x.v = static_cast<int>(rng() % h);
    x.cls = static_cast<std::uint8_t>(rng() % 4);
  }
  FeatureIndex index(w, h, 1000);
  index.build(f.data(), static_cast<int>(f.size()));
  EXPECT_EQ(index.count(), 700);
  for (int trial = 0; trial < 500; ++trial) {
    const int cls = static_cast<int>(rng() % 4);
    const int u0 = static_cast<int>(rng() % (w + 20)) - 10, v0 = static_cast<int>(rng() % (h + 20)) - 10;
    const int u1 = u0 + static_cast<int>(rng() % 60), v1 = v0 + static_cast<int>(rng() % 30);
    std::vector<int> got, want;
    index.for_each_in(cls, u0, u1, v0, v1, [&](int i) { got.push_back(i); });
    for (int v = v0; v <= v1; ++v)
      for (int u = u0; u <= u1; ++u)
        for (int i = 0; i < static_cast<int>(f.size()); ++i)
          if (f[static_cast<std::size_t>(i)].cls == cls && f[static_cast<std::size_t>(i)].u == u &&
              f[static_cast<std::size_t>(i)].v == v)
            want.push_back(i);
    ASSERT_EQ(got, want) << "window " << u0 << ".." << u1 << " x " << v0 << ".." << v1 << " class " << cls;
  }
}

// Columns outside the image (a caller's mistake) and rows crowded into one
// stretch of columns still come out in column order.
TEST(FeatureIndex, ColumnsAnywhereAreFound) {
  std::vector<Feature> f;
  for (int u : {-40, -1, 0, 31, 32, 33, 63, 64, 70, 99, 100, 150}) {
    Feature x;
    x.u = u;
    x.v = 3;
    x.cls = 2;
    f.push_back(x);
  }
  std::reverse(f.begin(), f.end());
  FeatureIndex index(100, 10, 100);
  index.build(f.data(), static_cast<int>(f.size()));
  for (const auto& [u0, u1] : {std::pair{-100, 200}, std::pair{-5, 31}, std::pair{32, 64}, std::pair{65, 99},
                               std::pair{99, 160}, std::pair{200, 300}}) {
    std::vector<int> got, want;
    index.for_each_in(2, u0, u1, 0, 9, [&](int i) { got.push_back(f[static_cast<std::size_t>(i)].u); });
    for (int i = static_cast<int>(f.size()) - 1; i >= 0; --i) {
      const int u = f[static_cast<std::size_t>(i)].u;
      if (u >= u0 && u <= u1) want.push_back(u);
    }
    EXPECT_EQ(got, want) << u0 << ".." << u1;
  }
}

TEST(FeatureIndex, KeepsAtMostItsCapacityAndSkipsImpossibleFeatures) {
  std::vector<Feature> f(10);
  for (int i = 0; i < 10; ++i) {
    f[static_cast<std::size_t>(i)].u = i;
    f[static_cast<std::size_t>(i)].v = 5;
    f[static_cast<std::size_t>(i)].cls = 1;
  }
  f[2].v = 99;  // outside the image
  f[3].cls = 7;  // no such class
  FeatureIndex index(20, 20, 6);
  index.build(f.data(), 10);
  EXPECT_EQ(index.count(), 6);
  std::vector<int> got;
  index.for_each_in(1, 0, 19, 0, 19, [&](int i) { got.push_back(i); });
  EXPECT_EQ(got, (std::vector<int>{0, 1, 4, 5, 6, 7}));
}

}  // namespace feature_index_test
}  // namespace rtfuse::vision
