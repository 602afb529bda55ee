// Block non-maximum suppression against its definition checked pixel by
// pixel, the features of simple shapes where they must be, descriptors
// read at their sample points.
#include "vision/feature_detector.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "vision/feature_filters.hpp"

namespace rtfuse::vision {
namespace feature_detector_test {

struct Responses {
  Plane<std::uint8_t> du, dv;
  Plane<std::int16_t> blob, corner;
  Responses(const Plane<std::uint8_t>& img)
      : du(img.width(), img.height()),
        dv(img.width(), img.height()),
        blob(img.width(), img.height()),
        corner(img.width(), img.height()) {
    FeatureFilters f(img.width());
    f.sobel5x5(view_of(img), du, dv);
    f.blob_corner5x5(view_of(img), blob, corner);
  }
};

Plane<std::uint8_t> flat(int w, int h, std::uint8_t grey) {
  Plane<std::uint8_t> img(w, h);
  for (int v = 0; v < h; ++v) std::fill(img.row(v), img.row(v) + w, grey);
  return img;
}

Plane<std::uint8_t> random_plane(int w, int h, std::uint32_t seed) {
  Plane<std::uint8_t> img(w, h);
  std::mt19937 rng(seed);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) img.row(v)[u] = static_cast<std::uint8_t>(rng() % 256);
  return img;
}

std::vector<Feature> detect(const Responses& r, const SuppressionParams& p) {
  std::vector<Feature> out(static_cast<std::size_t>(max_features(r.blob.width(), r.blob.height(), p)));
  int dropped = -1;
  const int n = suppress_non_maxima(r.blob, r.corner, p, out.data(), static_cast<int>(out.size()), &dropped);
  EXPECT_EQ(dropped, 0);
  out.resize(static_cast<std::size_t>(n));
  return out;
}

TEST(FeatureDetector, FlatImageHasNoFeatures) {
  const Responses r(flat(80, 60, 120));
  EXPECT_TRUE(detect(r, SuppressionParams{}).empty());
}

TEST(FeatureDetector, BrightAndDarkSpotsAreBlobMaximaAndMinima) {
  Plane<std::uint8_t> img = flat(80, 60, 100);
  img.row(30)[20] = 255;  // bright spot
  img.row(25)[55] = 0;    // dark spot
  const Responses r(img);
  const std::vector<Feature> f = detect(r, SuppressionParams{});
  auto has = [&](int u, int v, int cls) {
    return std::any_of(f.begin(), f.end(), [&](const Feature& x) { return x.u == u && x.v == v && x.cls == cls; });
  };
  EXPECT_TRUE(has(20, 30, kBlobMax));
  EXPECT_TRUE(has(55, 25, kBlobMin));
  for (const Feature& x : f) {
    EXPECT_GE(std::abs(x.value), 50);
    EXPECT_GE(x.u, 9);
    EXPECT_LT(x.u, 80 - 9);
  }
}

TEST(FeatureDetector, ACheckerCornerIsACornerFeature) {
  Plane<std::uint8_t> img = flat(80, 60, 0);
  for (int v = 0; v < 60; ++v)
    for (int u = 0; u < 80; ++u) img.row(v)[u] = ((u < 40) != (v < 30)) ? 200 : 20;
  const Responses r(img);
  const std::vector<Feature> f = detect(r, SuppressionParams{});
  const bool found = std::any_of(f.begin(), f.end(), [](const Feature& x) {
    return (x.cls == kCornerMin || x.cls == kCornerMax) && std::abs(x.u - 40) <= 1 && std::abs(x.v - 30) <= 1;
  });
  EXPECT_TRUE(found);
}

// The definition, by brute force: a block's first extreme pixel per class,
// beyond tau, with nothing strictly more extreme in its (2n+1)^2 window
// outside the block (within the margin).
// Textures: uniform noise, and noise of four grey levels, whose responses
// have plateaus (ties inside blocks and between neighbours).
Plane<std::uint8_t> texture(int w, int h, std::uint32_t seed, bool coarse) {
  Plane<std::uint8_t> img = random_plane(w, h, seed);
  if (coarse) {
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) img.row(v)[u] = static_cast<std::uint8_t>((img.row(v)[u] >> 6) * 60);
  }
  return img;
}

TEST(FeatureDetector, EqualsTheDefinitionOnRandomTexture) {
  const int w = 97, h = 71;
  for (const bool coarse : {false, true}) {
    const Responses r(texture(w, h, 3, coarse));
    for (const SuppressionParams& p : {SuppressionParams{3, 50, 9}, SuppressionParams{9, 200, 9},
                                       SuppressionParams{2, 0, 8}, SuppressionParams{0, 30, 8},
                                       SuppressionParams{15, 10, 8}}) {
      std::set<std::tuple<int, int, int>> expected;
      const int umax = w - 1 - p.margin, vmax = h - 1 - p.margin;
      for (int bv = p.n + p.margin; bv < h - p.n - p.margin; bv += p.n + 1) {
        for (int bu = p.n + p.margin; bu < w - p.n - p.margin; bu += p.n + 1) {
          for (int k = 0; k < 4; ++k) {
            const Plane<std::int16_t>& resp = k < 2 ? r.blob : r.corner;
            const int sign = (k % 2) ? 1 : -1;
            int bestu = -1, bestv = -1, best = 0;
            for (int v = bv; v <= std::min(bv + p.n, vmax); ++v)
              for (int u = bu; u <= std::min(bu + p.n, umax); ++u)
                if (bestu < 0 || sign * resp.at(u, v) > sign * best) bestu = u, bestv = v, best = resp.at(u, v);
            if (sign * best < p.tau) continue;
            bool ok = true;
            for (int v = std::max(0, bestv - p.n); v <= std::min(vmax, bestv + p.n) && ok; ++v)
              for (int u = std::max(0, bestu - p.n); u <= std::min(umax, bestu + p.n); ++u) {
                const bool in_block = u >= bu && u <= bu + p.n && v >= bv && v <= bv + p.n;
                if (!in_block && sign * resp.at(u, v) > sign * best) ok = false;
              }
            if (ok) expected.insert({bestu, bestv, k});
          }
        }
      }
      std::set<std::tuple<int, int, int>> got;
      for (const Feature& f : detect(r, p)) {
        got.insert({f.u, f.v, f.cls});
        EXPECT_EQ(f.value, (f.cls < 2 ? r.blob : r.corner).at(f.u, f.v));
      }
      EXPECT_EQ(got, expected) << "n " << p.n << " tau " << p.tau << " coarse " << coarse;
      EXPECT_GT(got.size(), p.n == 15 ? 0u : 10u);  // few blocks that large
    }
  }
}

// The vector version (SSE2 here, NEON on aarch64) finds the same features
// in the same order as the plain one, on widths that leave partial vectors
// at the right edge.
TEST(FeatureDetector, VectorSuppressionEqualsThePlainOne) {
  for (const auto& [w, h] : {std::pair{97, 71}, std::pair{613, 185}, std::pair{45, 37}}) {
    for (const bool coarse : {false, true}) {
      const Responses r(texture(w, h, static_cast<std::uint32_t>(w + h), coarse));
      for (const SuppressionParams& p :
           {SuppressionParams{}, SuppressionParams{1, 0, 8}, SuppressionParams{7, 100, 10}}) {
        std::vector<Feature> a(static_cast<std::size_t>(std::max(1, max_features(w, h, p)))), b = a;
        int da = -1, db = -1;
        const int na = suppress_non_maxima(r.blob, r.corner, p, a.data(), static_cast<int>(a.size()), &da);
        const int nb = suppress_non_maxima_plain(r.blob, r.corner, p, b.data(), static_cast<int>(b.size()), &db);
        ASSERT_EQ(na, nb) << w << " n " << p.n;
        EXPECT_EQ(da, db);
        EXPECT_GT(na, 0);
        for (int i = 0; i < na; ++i) {
          const Feature &x = a[static_cast<std::size_t>(i)], &y = b[static_cast<std::size_t>(i)];
          ASSERT_EQ(std::tie(x.u, x.v, x.value, x.cls), std::tie(y.u, y.v, y.value, y.cls)) << i;
        }
      }
    }
  }
}

TEST(FeatureDetector, ACapacityTooSmallCountsWhatItDrops) {
  const int w = 97, h = 71;
  Plane<std::uint8_t> img = random_plane(w, h, 5);
  const Responses r(img);
  const std::vector<Feature> all = detect(r, SuppressionParams{});
  std::vector<Feature> some(10);
  int dropped = 0;
  const int n = suppress_non_maxima(r.blob, r.corner, SuppressionParams{}, some.data(), 10, &dropped);
  EXPECT_EQ(n, 10);
  EXPECT_EQ(dropped, static_cast<int>(all.size()) - 10);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(some[static_cast<std::size_t>(i)].u, all[static_cast<std::size_t>(i)].u);
}

TEST(FeatureDetector, DescriptorsHoldTheGradientsAtTheSamplePoints) {
  const int w = 64, h = 48;
  Plane<std::uint8_t> img = random_plane(w, h, 11);
  const Responses r(img);
  Feature f[2];
  f[0].u = 20, f[0].v = 20;
  f[1].u = 40, f[1].v = 30;
  describe(r.du, r.dv, f, 2);
  EXPECT_EQ(f[0].descriptor[0], r.du.at(17, 19));  // (-3, -1)
  EXPECT_EQ(f[0].descriptor[1], r.dv.at(17, 19));
  EXPECT_EQ(f[0].descriptor[30], r.du.at(25, 23));  // (+5, +3)
  EXPECT_EQ(f[0].descriptor[31], r.dv.at(25, 23));
  EXPECT_EQ(descriptor_sad(f[0].descriptor, f[0].descriptor), 0);
  int sad = 0;
  for (int i = 0; i < kDescriptorBytes; ++i) sad += std::abs(f[0].descriptor[i] - f[1].descriptor[i]);
  EXPECT_EQ(descriptor_sad(f[0].descriptor, f[1].descriptor), sad);
  EXPECT_GT(sad, 0);
}

TEST(FeatureDetector, MaxFeaturesBoundsWhatIsFound) {
  SuppressionParams p;
  EXPECT_EQ(max_features(20, 20, p), 0);  // the margin leaves no block
  // 1226 x 370 KITTI frames at half resolution (613 x 185), n = 3.
  EXPECT_EQ(max_features(613, 185, p), 148 * 41 * 4);
}

}  // namespace feature_detector_test
}  // namespace rtfuse::vision

namespace rtfuse::vision {
namespace feature_detector_test {

// The vector SAD (SSE2 here, NEON on aarch64) equals the one written out.
TEST(FeatureDetector, DescriptorSadEqualsThePlainSum) {
  std::mt19937 rng(17);
  std::uint8_t a[kDescriptorBytes], b[kDescriptorBytes];
  for (int trial = 0; trial < 2000; ++trial) {
    for (int i = 0; i < kDescriptorBytes; ++i) {
      a[i] = static_cast<std::uint8_t>(rng());
      b[i] = trial % 3 == 0 ? static_cast<std::uint8_t>(255 - a[i]) : static_cast<std::uint8_t>(rng());
    }
    ASSERT_EQ(descriptor_sad(a, b), descriptor_sad_plain(a, b)) << trial;
  }
  std::fill(a, a + kDescriptorBytes, 0);
  std::fill(b, b + kDescriptorBytes, 255);
  EXPECT_EQ(descriptor_sad(a, b), 32 * 255);
}

}  // namespace feature_detector_test
}  // namespace rtfuse::vision
