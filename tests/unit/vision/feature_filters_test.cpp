// The integer filters against direct 5x5 convolutions with the masks
// written out, on random images: equal everywhere, neutral at the border.
#include "vision/feature_filters.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <tuple>

namespace rtfuse::vision {
namespace feature_filters_test {

Plane<std::uint8_t> random_image(int w, int h, std::uint32_t seed) {
  Plane<std::uint8_t> img(w, h);
  std::mt19937 rng(seed);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) img.row(v)[u] = static_cast<std::uint8_t>(rng() & 0xff);
  return img;
}

int convolve(const Plane<std::uint8_t>& img, int u, int v, const int mask[5][5]) {
  int sum = 0;
  for (int j = -2; j <= 2; ++j)
    for (int i = -2; i <= 2; ++i) sum += mask[j + 2][i + 2] * img.at(u + i, v + j);
  return sum;
}

int floor_div128(int g) { return g >= 0 ? g / 128 : -((-g + 127) / 128); }

constexpr int kSobelU[5][5] = {{-1, -2, 0, 2, 1}, {-4, -8, 0, 8, 4}, {-6, -12, 0, 12, 6}, {-4, -8, 0, 8, 4},
                               {-1, -2, 0, 2, 1}};
constexpr int kSobelV[5][5] = {{-1, -4, -6, -4, -1}, {-2, -8, -12, -8, -2}, {0, 0, 0, 0, 0}, {2, 8, 12, 8, 2},
                               {1, 4, 6, 4, 1}};
constexpr int kBlob[5][5] = {{-1, -1, -1, -1, -1}, {-1, 1, 1, 1, -1}, {-1, 1, 8, 1, -1}, {-1, 1, 1, 1, -1},
                             {-1, -1, -1, -1, -1}};
constexpr int kCorner[5][5] = {{-1, -1, 0, 1, 1}, {-1, -1, 0, 1, 1}, {0, 0, 0, 0, 0}, {1, 1, 0, -1, -1},
                               {1, 1, 0, -1, -1}};

TEST(FeatureFilters, EqualDirectConvolutionEverywhere) {
  for (const auto& [w, h] : {std::pair{37, 23}, std::pair{64, 48}, std::pair{5, 5}}) {
    const Plane<std::uint8_t> img = random_image(w, h, static_cast<std::uint32_t>(w * 1000 + h));
    FeatureFilters f(w);
    Plane<std::uint8_t> du(w, h), dv(w, h);
    Plane<std::int16_t> blob(w, h), corner(w, h);
    f.sobel5x5(view_of(img), du, dv);
    f.blob_corner5x5(view_of(img), blob, corner);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const bool border = u < 2 || v < 2 || u >= w - 2 || v >= h - 2;
        if (border) {
          ASSERT_EQ(du.at(u, v), 128) << u << "," << v;
          ASSERT_EQ(dv.at(u, v), 128) << u << "," << v;
          ASSERT_EQ(blob.at(u, v), 0);
          ASSERT_EQ(corner.at(u, v), 0);
          continue;
        }
        ASSERT_EQ(du.at(u, v), floor_div128(convolve(img, u, v, kSobelU)) + 128) << u << "," << v;
        ASSERT_EQ(dv.at(u, v), floor_div128(convolve(img, u, v, kSobelV)) + 128) << u << "," << v;
        ASSERT_EQ(blob.at(u, v), convolve(img, u, v, kBlob)) << u << "," << v;
        ASSERT_EQ(corner.at(u, v), convolve(img, u, v, kCorner)) << u << "," << v;
      }
    }
  }
}

TEST(FeatureFilters, ExtremeImagesStayInRange) {
  // A checkerboard of 0 and 255 drives every filter to its bounds.
  const int w = 16, h = 16;
  Plane<std::uint8_t> img(w, h);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) img.row(v)[u] = ((u / 2 + v / 2) % 2) ? 255 : 0;
  FeatureFilters f(w);
  Plane<std::uint8_t> du(w, h), dv(w, h);
  Plane<std::int16_t> blob(w, h), corner(w, h);
  f.sobel5x5(view_of(img), du, dv);
  f.blob_corner5x5(view_of(img), blob, corner);
  for (int v = 2; v < h - 2; ++v) {
    for (int u = 2; u < w - 2; ++u) {
      EXPECT_EQ(du.at(u, v), floor_div128(convolve(img, u, v, kSobelU)) + 128);
      EXPECT_GE(du.at(u, v), 32);
      EXPECT_LE(du.at(u, v), 223);
      EXPECT_EQ(blob.at(u, v), convolve(img, u, v, kBlob));
      EXPECT_EQ(corner.at(u, v), convolve(img, u, v, kCorner));
    }
  }
}

TEST(FeatureFilters, AWindowsGradientsAreTheWholeImages) {
  const int w = 64, h = 48;
  const Plane<std::uint8_t> img = random_image(w, h, 13);
  FeatureFilters f(w);
  Plane<std::uint8_t> du(w, h), dv(w, h);
  f.sobel5x5(view_of(img), du, dv);
  for (const auto& [u0, v0, ww, wh] : {std::tuple{2, 2, 15, 15}, std::tuple{30, 20, 11, 11}, std::tuple{2, 31, 60, 15},
                                       std::tuple{47, 2, 15, 44}}) {
    Plane<std::uint8_t> wu(ww, wh), wv(ww, wh);
    FeatureFilters::sobel5x5_window(view_of(img), u0, v0, wu, wv);
    for (int y = 0; y < wh; ++y)
      for (int x = 0; x < ww; ++x) {
        ASSERT_EQ(wu.at(x, y), du.at(u0 + x, v0 + y)) << u0 + x << "," << v0 + y;
        ASSERT_EQ(wv.at(x, y), dv.at(u0 + x, v0 + y)) << u0 + x << "," << v0 + y;
      }
  }
}

TEST(FeatureFilters, HalveIsTheTruncatedMeanOfEachSquare) {
  const Plane<std::uint8_t> img = random_image(33, 21, 7);
  Plane<std::uint8_t> half(16, 10);
  FeatureFilters::halve(view_of(img), half);
  for (int v = 0; v < 10; ++v)
    for (int u = 0; u < 16; ++u) {
      const int sum = img.at(2 * u, 2 * v) + img.at(2 * u + 1, 2 * v) + img.at(2 * u, 2 * v + 1) +
                      img.at(2 * u + 1, 2 * v + 1);
      ASSERT_EQ(half.at(u, v), sum / 4) << u << "," << v;
    }
}

}  // namespace feature_filters_test
}  // namespace rtfuse::vision
