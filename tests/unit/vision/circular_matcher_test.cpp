// Circular matching on synthetic pairs cut from one texture, where every
// disparity and every motion is known: the circles that close say exactly
// those, with and without a prediction, and a feature that has no partner
// in one image closes no circle.
#include "vision/circular_matcher.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "vision/feature_filters.hpp"

namespace rtfuse::vision {
namespace circular_matcher_test {

constexpr int kW = 200, kH = 120;

// A texture of random 3x3 blocks, smooth enough for the 5x5 filters.
struct Texture {
  std::vector<std::uint8_t> t;
  int w = 400, h = 300;
  explicit Texture(std::uint32_t seed) : t(static_cast<std::size_t>(400 * 300)) {
    std::mt19937 rng(seed);
    std::vector<std::uint8_t> blocks(static_cast<std::size_t>((w / 3 + 1) * (h / 3 + 1)));
    for (auto& b : blocks) b = static_cast<std::uint8_t>(rng() % 256);
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) t[static_cast<std::size_t>(v * w + u)] = blocks[static_cast<std::size_t>((v / 3) * (w / 3 + 1) + u / 3)];
  }
  Plane<std::uint8_t> cut(int ou, int ov) const {
    Plane<std::uint8_t> img(kW, kH);
    for (int v = 0; v < kH; ++v)
      for (int u = 0; u < kW; ++u) img.row(v)[u] = t[static_cast<std::size_t>((v + ov) * w + u + ou)];
    return img;
  }
};

struct Image {
  std::vector<Feature> features;
  FeatureIndex index;
  explicit Image(const Plane<std::uint8_t>& img) : index(kW, kH, max_features(kW, kH, SuppressionParams{})) {
    FeatureFilters f(kW);
    Plane<std::uint8_t> du(kW, kH), dv(kW, kH);
    Plane<std::int16_t> blob(kW, kH), corner(kW, kH);
    f.sobel5x5(view_of(img), du, dv);
    f.blob_corner5x5(view_of(img), blob, corner);
    features.resize(static_cast<std::size_t>(max_features(kW, kH, SuppressionParams{})));
    int dropped = 0;
    const int n = suppress_non_maxima(blob, corner, SuppressionParams{}, features.data(),
                                      static_cast<int>(features.size()), &dropped);
    features.resize(static_cast<std::size_t>(n));
    describe(du, dv, features.data(), n);
    index.build(features.data(), n);
  }
};

// The previous pair at texture offset (50, 60), disparity 12; the current
// pair moved by (flow_u, flow_v) in the image, disparity 12 again.
struct Scene {
  Image lp, rp, lc, rc;
  Scene(const Texture& t, int flow_u, int flow_v)
      : lp(t.cut(50, 60)),
        rp(t.cut(50 + 12, 60)),  // R(u) = L(u + d): the right eye sees a point d pixels further left
        lc(t.cut(50 - flow_u, 60 - flow_v)),
        rc(t.cut(50 - flow_u + 12, 60 - flow_v)) {}
};

class ExactShift final : public MotionPrediction {
 public:
  ExactShift(int fu, int fv) : fu_(fu), fv_(fv) {}
  bool predict(int u, int v, int d, int* ur, int* vr, int* ul, int* vl) const noexcept override {
    *ul = u + fu_, *vl = v + fv_, *ur = u - d + fu_, *vr = v + fv_;
    return true;
  }

 private:
  int fu_, fv_;
};

int count_exact(const Scene& s, const std::vector<CircularMatch>& m, int fu, int fv) {
  int exact = 0;
  for (const CircularMatch& c : m) {
    const Feature& a = s.lp.features[static_cast<std::size_t>(c.lp)];
    const Feature& b = s.rp.features[static_cast<std::size_t>(c.rp)];
    const Feature& l = s.lc.features[static_cast<std::size_t>(c.lc)];
    const Feature& r = s.rc.features[static_cast<std::size_t>(c.rc)];
    if (a.u - b.u == 12 && l.u - r.u == 12 && l.u - a.u == fu && l.v - a.v == fv && a.v == b.v && l.v == r.v) ++exact;
  }
  return exact;
}

// Nearly every closed circle is the true one. The rest are features whose
// partner left the image, closed by a wrong partner that happens to be each
// other's best (the egomotion's RANSAC rejects those).
// Matches the scene with a 40 px disparity range and a 30 px motion window.
std::vector<CircularMatch> match(const Scene& s, const MotionPrediction* predict, int predicted_radius = 10) {
  CircularMatcher matcher(static_cast<int>(s.lc.features.size()));
  std::vector<CircularMatch> out(2000);
  MatchParams p;
  p.max_disparity = 40;
  p.flow_radius = 30;
  p.predicted_radius = predicted_radius;
  const int n = matcher.match(s.lp.index, s.rp.index, s.lc.index, s.rc.index, p, predict, out.data(), 2000);
  out.resize(static_cast<std::size_t>(n));
  return out;
}

void check(const Scene& s, const std::vector<CircularMatch>& m, int fu, int fv) {
  ASSERT_GT(m.size(), 50u);
  const int exact = count_exact(s, m, fu, fv);
  EXPECT_GE(exact, static_cast<int>(m.size()) * 95 / 100) << exact << " of " << m.size();
}

TEST(CircularMatcher, RecoversDisparityAndMotionOfEveryClosedCircle) {
  const Texture t(1);
  for (const auto& [fu, fv] : {std::pair{0, 0}, std::pair{7, -3}, std::pair{-20, 5}}) {
    const Scene s(t, fu, fv);
    check(s, match(s, nullptr), fu, fv);
  }
}

TEST(CircularMatcher, APredictionNarrowsTheSearchToTheSameAnswer) {
  const Texture t(2);
  const int fu = 45, fv = -12;  // beyond a 30 px window: only the prediction finds it
  const Scene s(t, fu, fv);
  const ExactShift predict(fu, fv);
  const std::vector<CircularMatch> with = match(s, &predict, 4);
  check(s, with, fu, fv);
  EXPECT_LT(count_exact(s, match(s, nullptr), fu, fv), static_cast<int>(with.size()) / 20)
      << "a 30 px window cannot reach a 47 px motion";
}

TEST(CircularMatcher, EachCurrentFeatureClosesOneCircleAndCapacityHolds) {
  const Texture t(3);
  const Scene s(t, 3, 2);
  CircularMatcher matcher(static_cast<int>(s.lc.features.size()));
  std::vector<CircularMatch> out(2000);
  MatchParams p;
  p.max_disparity = 40;
  p.flow_radius = 20;
  const int n = matcher.match(s.lp.index, s.rp.index, s.lc.index, s.rc.index, p, nullptr, out.data(), 2000);
  std::vector<int> seen(s.lc.features.size(), 0);
  for (int i = 0; i < n; ++i) EXPECT_EQ(++seen[static_cast<std::size_t>(out[static_cast<std::size_t>(i)].lc)], 1);
  EXPECT_EQ(matcher.match(s.lp.index, s.rp.index, s.lc.index, s.rc.index, p, nullptr, out.data(), 10), 10);
}

}  // namespace circular_matcher_test
}  // namespace rtfuse::vision
