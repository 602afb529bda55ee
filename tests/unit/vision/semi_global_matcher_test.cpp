// The dense stereo matcher on synthetic rectified pairs whose disparity is
// known exactly: a textured plane shifted by an integer and by a fraction,
// a slanted plane, a foreground square whose occlusion band the left-right
// check must remove; the invalid border; bad input refused without a crash;
// the same bytes twice and from every backend (plain, the baseline's SSE2
// or NEON, AVX2 where the CPU has it), the same digest as before; no
// allocation per frame.
#include "vision/semi_global_matcher.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <random>
#include <vector>

#include "core/xxh64.hpp"
#include "support/alloc_counter.hpp"
#include "vision/census_cost.hpp"
#include "vision/census_transform.hpp"
#include "vision/disparity_selection.hpp"
#include "vision/packed_winner.hpp"
#include "vision/simd_avx2.hpp"
#include "vision/simd_u8.hpp"

namespace rtfuse::vision {
namespace semi_global_matcher_test {

constexpr int kW = 160;
constexpr int kH = 96;

// A smooth random texture, defined between pixels too (bilinear between
// random grey levels every 3 px), so a pair can be shifted by a fraction.
class Texture {
 public:
  explicit Texture(std::uint32_t seed, int cells_x = 200, int cells_y = 60) : nx_(cells_x), ny_(cells_y) {
    std::mt19937 rng(seed);
    grid_.resize(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_));
    for (auto& g : grid_) g = static_cast<double>(rng() % 256);
  }
  double at(double u, double v) const {
    const double gu = std::clamp(u / kCell, 0.0, nx_ - 1.001), gv = std::clamp(v / kCell, 0.0, ny_ - 1.001);
    const int i = static_cast<int>(gu), j = static_cast<int>(gv);
    const double a = gu - i, b = gv - j;
    return (1 - a) * (1 - b) * g(i, j) + a * (1 - b) * g(i + 1, j) + (1 - a) * b * g(i, j + 1) + a * b * g(i + 1, j + 1);
  }

 private:
  static constexpr double kCell = 3.0;
  double g(int i, int j) const { return grid_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)]; }
  int nx_, ny_;
  std::vector<double> grid_;
};

std::uint8_t grey(double v) { return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L)); }

struct Pair {
  Plane<std::uint8_t> left{kW, kH}, right{kW, kH};
};

// left(x, y) = f(x, y); right(x, y) = g(x, y): the caller's scene.
Pair make_pair(const std::function<double(int, int)>& left, const std::function<double(int, int)>& right) {
  Pair p;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      p.left.row(y)[x] = grey(left(x, y));
      p.right.row(y)[x] = grey(right(x, y));
    }
  }
  return p;
}

// A fronto-parallel plane at disparity d: right(x) = left(x + d).
Pair shifted_plane(double d, std::uint32_t seed = 1) {
  const Texture t(seed);
  return make_pair([&](int x, int y) { return t.at(x + 10.0, y); }, [&](int x, int y) { return t.at(x + 10.0 + d, y); });
}

double disparity_px(std::uint16_t v) { return static_cast<double>(v) / kDisparityScale; }

struct Match {
  Plane<std::uint16_t> out;
  DisparityStatus status = DisparityStatus::kOk;
  int valid = 0;
};

Match run(const Pair& p, const DisparityParams& params = {}) {
  SemiGlobalMatcher m(kW, kH, params);
  EXPECT_TRUE(m.valid()) << m.error();
  Match r{Plane<std::uint16_t>(m.output_width(kW), m.output_height(kH))};
  r.status = m.compute(view_of(p.left), view_of(p.right), view_of(r.out));
  r.valid = m.valid_pixels();
  return r;
}

// Share of valid pixels with x >= x0 within tol px of truth(x, y), and
// how many there were.
double share_within(const Match& r, int x0, double tol, const std::function<double(int, int)>& truth, int* count) {
  int n = 0, good = 0;
  for (int y = 0; y < r.out.height(); ++y) {
    for (int x = x0; x < r.out.width(); ++x) {
      const std::uint16_t v = r.out.at(x, y);
      if (v == kInvalidDisparity) continue;
      ++n;
      good += std::fabs(disparity_px(v) - truth(x, y)) <= tol ? 1 : 0;
    }
  }
  *count = n;
  return n > 0 ? static_cast<double>(good) / n : 0.0;
}

DisparityParams params32() {
  DisparityParams p;
  p.disparities = 32;
  return p;
}

TEST(SemiGlobalMatcher, IntegerShiftFound) {
  const Match r = run(shifted_plane(12.0), params32());
  ASSERT_EQ(r.status, DisparityStatus::kOk);
  int n = 0;
  // The winner is right everywhere; the parabola's fraction wanders a
  // little (census costs are not symmetric about a true integer shift).
  EXPECT_GE(share_within(r, 32, 0.5, [](int, int) { return 12.0; }, &n), 0.99) << n;
  EXPECT_GT(n, (kW - 32 - 4) * (kH - 6) * 95 / 100);
  EXPECT_GE(share_within(r, 32, 0.25, [](int, int) { return 12.0; }, &n), 0.95);
}

TEST(SemiGlobalMatcher, FractionalShiftWithinAQuarterPixel) {
  const Match r = run(shifted_plane(7.5), params32());
  ASSERT_EQ(r.status, DisparityStatus::kOk);
  int n = 0;
  EXPECT_GE(share_within(r, 32, 1.0, [](int, int) { return 7.5; }, &n), 0.99);
  // The parabola's fraction: most estimates nearer 7.5 than the integers
  // (census costs pull fractions towards whole pixels, so not all).
  EXPECT_GE(share_within(r, 32, 0.25, [](int, int) { return 7.5; }, &n), 0.7);
}

TEST(SemiGlobalMatcher, SlantedPlaneWithinOnePixel) {
  // d = a + b x_left; the right pixel x_r sees x_left = x_r + d, so
  // d = (a + b x_r) / (1 - b).
  const double a = 4.0, b = 0.08;
  const Texture t(2);
  const Pair p = make_pair([&](int x, int y) { return t.at(x, y); },
                           [&](int x, int y) { return t.at(x + (a + b * x) / (1 - b), y); });
  const Match r = run(p, params32());
  ASSERT_EQ(r.status, DisparityStatus::kOk);
  int n = 0;
  EXPECT_GE(share_within(r, 32, 1.0, [&](int x, int) { return a + b * x; }, &n), 0.95);
  EXPECT_GT(n, (kW - 32) * (kH - 6) * 8 / 10);
}

// Background at disparity 4, a square at 20 over columns [60, 100) of the
// left view: left columns [44, 60) show background the right eye cannot see.
Pair occlusion_scene() {
  const Texture bg(3), fg(4);
  auto in_square_rows = [](int y) { return y >= 24 && y < 72; };
  return make_pair(
      [&](int x, int y) { return in_square_rows(y) && x >= 60 && x < 100 ? fg.at(x, y) : bg.at(x, y); },
      [&](int x, int y) { return in_square_rows(y) && x >= 40 && x < 80 ? fg.at(x + 20.0, y) : bg.at(x + 4.0, y); });
}

int invalid_in_band(const Match& r, int* total) {
  int invalid = 0;
  *total = 0;
  for (int y = 30; y < 66; ++y) {
    for (int x = 46; x < 58; ++x) {
      ++*total;
      invalid += r.out.at(x, y) == kInvalidDisparity ? 1 : 0;
    }
  }
  return invalid;
}

TEST(SemiGlobalMatcher, LeftRightCheckInvalidatesTheOcclusion) {
  const Pair p = occlusion_scene();
  DisparityParams checked = params32();
  checked.uniqueness_percent = 0;
  checked.speckle_window = 0;
  DisparityParams unchecked = checked;
  unchecked.lr_max_diff = -1;
  int total = 0;
  const Match with = run(p, checked), without = run(p, unchecked);
  const int invalid_with = invalid_in_band(with, &total), invalid_without = invalid_in_band(without, &total);
  EXPECT_EQ(invalid_without, 0);
  EXPECT_GE(invalid_with, total * 8 / 10) << invalid_with << " of " << total;
  // Where both eyes see the surface, the estimates stay.
  int n = 0;
  EXPECT_GE(share_within(with, 64, 1.0,
                         [](int x, int y) { return y >= 24 && y < 72 && x >= 60 && x < 100 ? 20.0 : 4.0; }, &n),
            0.95);
}

TEST(SemiGlobalMatcher, BorderAndShortRangeMarkedInvalid) {
  const Match r = run(shifted_plane(12.0), params32());
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const bool border = y < kCensusHalfHeight || y >= kH - kCensusHalfHeight || x < kCensusHalfWidth ||
                          x >= kW - kCensusHalfWidth;
      if (border) {
        ASSERT_EQ(r.out.at(x, y), kInvalidDisparity) << x << "," << y;
      }
      // Left of column 12 the true match lies outside the right image.
      if (x < 12 && r.out.at(x, y) != kInvalidDisparity) {
        ASSERT_LE(disparity_px(r.out.at(x, y)), x + 0.5);
      }
    }
  }
  EXPECT_NEAR(r.out.at(kW / 2, kH / 2), 12 * kDisparityScale, kDisparityScale / 4);
}

TEST(SemiGlobalMatcher, HalfResolutionReportsInputPixels) {
  DisparityParams p;
  p.disparities = 32;
  p.downscale = 2;
  const Match r = run(shifted_plane(12.0), p);
  ASSERT_EQ(r.status, DisparityStatus::kOk);
  EXPECT_EQ(r.out.width(), kW / 2);
  EXPECT_EQ(r.out.height(), kH / 2);
  int n = 0;
  EXPECT_GE(share_within(r, 16, 1.0, [](int, int) { return 12.0; }, &n), 0.95);
  EXPECT_GT(n, 600);
}

TEST(SemiGlobalMatcher, BadParametersRefusedAtConstruction) {
  auto refused = [](int w, int h, DisparityParams p) {
    SemiGlobalMatcher m(w, h, p);
    return !m.valid() && m.error() != nullptr && std::strlen(m.error()) > 10;
  };
  DisparityParams p;
  EXPECT_TRUE(refused(0, 10, p));
  EXPECT_TRUE(refused(100, -1, p));
  p.disparities = 24;  // not a multiple of 16
  EXPECT_TRUE(refused(640, 480, p));
  p.disparities = 0;
  EXPECT_TRUE(refused(640, 480, p));
  p.disparities = 64;
  EXPECT_TRUE(refused(64, 480, p));  // range as wide as the image
  p.downscale = 3;
  EXPECT_TRUE(refused(640, 480, p));
  p.downscale = 2;
  p.disparities = 48;  // 24 at half resolution
  EXPECT_TRUE(refused(640, 480, p));
  p = DisparityParams{};
  p.paths = 6;
  EXPECT_TRUE(refused(640, 480, p));
  p = DisparityParams{};
  p.p2 = 500;
  EXPECT_TRUE(refused(640, 480, p));
  p = DisparityParams{};
  p.uniqueness_percent = 100;
  EXPECT_TRUE(refused(640, 480, p));
  EXPECT_TRUE(SemiGlobalMatcher(640, 480, DisparityParams{}).valid());
  // A refused matcher says so instead of computing.
  SemiGlobalMatcher bad(0, 0);
  Plane<std::uint8_t> img(32, 32);
  Plane<std::uint16_t> out(32, 32);
  EXPECT_EQ(bad.compute(view_of(img), view_of(img), view_of(out)), DisparityStatus::kNotConstructed);
}

TEST(SemiGlobalMatcher, BadImagesReturnAStatus) {
  SemiGlobalMatcher m(kW, kH, params32());
  ASSERT_TRUE(m.valid());
  Plane<std::uint8_t> a(kW, kH), b(kW, kH), narrow(kW - 8, kH), big(kW + 16, kH), tiny(32, kH);
  Plane<std::uint16_t> out(kW, kH), out_big(kW + 16, kH), out_tiny(32, kH);
  EXPECT_EQ(m.compute(view_of(a), view_of(narrow), view_of(out)), DisparityStatus::kSizeMismatch);
  EXPECT_EQ(m.compute(view_of(a), view_of(b), view_of(out_tiny)), DisparityStatus::kSizeMismatch);
  EXPECT_EQ(m.compute(view_of(big), view_of(big), view_of(out_big)), DisparityStatus::kLargerThanWorkspace);
  EXPECT_EQ(m.compute(view_of(tiny), view_of(tiny), view_of(out_tiny)), DisparityStatus::kRangeTooWide);
  EXPECT_EQ(m.compute(GreyView{}, view_of(b), view_of(out)), DisparityStatus::kBadImage);
  GreyView short_stride = view_of(a);
  short_stride.stride = kW - 1;
  EXPECT_EQ(m.compute(short_stride, view_of(b), view_of(out)), DisparityStatus::kBadImage);
  EXPECT_EQ(m.compute(view_of(a), view_of(b), DisparityImage{}), DisparityStatus::kBadImage);
  EXPECT_STRNE(to_string(DisparityStatus::kRangeTooWide), "unknown");
}

TEST(SemiGlobalMatcher, SameBytesTwiceAndNoAllocation) {
  const Pair p = occlusion_scene();
  for (const DisparityBackend backend : {DisparityBackend::kAuto, DisparityBackend::kBaseline, DisparityBackend::kPlain}) {
    SemiGlobalMatcher m(kW, kH, params32(), backend);
    Plane<std::uint16_t> a(kW, kH), b(kW, kH);
    ASSERT_EQ(m.compute(view_of(p.left), view_of(p.right), view_of(a)), DisparityStatus::kOk);
    {
      test::AllocScope scope;
      ASSERT_EQ(m.compute(view_of(p.left), view_of(p.right), view_of(b)), DisparityStatus::kOk);
      EXPECT_EQ(scope.count(), 0u) << to_string(m.backend());
    }
    for (int y = 0; y < kH; ++y) ASSERT_EQ(std::memcmp(a.row(y), b.row(y), kW * sizeof(std::uint16_t)), 0) << y;
  }
}

// The vector backends (SSE2 or NEON) against the plain definitions, on
// random images: census, costs and selection give the same integers.
TEST(SemiGlobalMatcher, VectorAndPlainBackendsAgree) {
  std::mt19937 rng(7);
  const int w = 77, h = 19, d = 32;
  Plane<std::uint8_t> img(w, h), other(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      img.row(y)[x] = static_cast<std::uint8_t>(rng() & 0xff);
      other.row(y)[x] = static_cast<std::uint8_t>(rng() & 0xff);
    }
  }
  Plane<std::uint8_t> native[kCensusPlanes], plain[kCensusPlanes], right[kCensusPlanes];
  for (int g = 0; g < kCensusPlanes; ++g) {
    native[g] = Plane<std::uint8_t>(w, h);
    plain[g] = Plane<std::uint8_t>(w, h);
    right[g] = Plane<std::uint8_t>(w, h);
  }
  census_transform_9x7(view_of(img), native);
  census_transform_9x7_portable(view_of(img), plain);
  census_transform_9x7(view_of(other), right);
  for (int g = 0; g < kCensusPlanes; ++g) {
    for (int y = 0; y < h; ++y) ASSERT_EQ(std::memcmp(native[g].row(y), plain[g].row(y), w), 0) << g << "," << y;
  }
  const int y = h / 2;
  std::vector<std::uint8_t> reversed(static_cast<std::size_t>(kCensusPlanes) * (w + d + 32), 0);
  const std::uint8_t *lp[kCensusPlanes], *rp[kCensusPlanes];
  for (int g = 0; g < kCensusPlanes; ++g) {
    std::uint8_t* rev = reversed.data() + static_cast<std::size_t>(g) * (w + d + 32);
    for (int x = 0; x < w; ++x) rev[w - 1 - x] = right[g].row(y)[x];
    lp[g] = native[g].row(y);
    rp[g] = rev;
  }
  std::vector<std::uint8_t> cost_native(static_cast<std::size_t>(w) * d + 16), cost_plain(cost_native.size());
  census_cost_row(lp, rp, w, d, cost_native.data());
  census_cost_row_portable(lp, rp, w, d, cost_plain.data());
  ASSERT_EQ(std::memcmp(cost_native.data(), cost_plain.data(), static_cast<std::size_t>(w) * d), 0);
  std::vector<std::int16_t> sums(static_cast<std::size_t>(w) * d);
  for (auto& s : sums) s = static_cast<std::int16_t>(rng() % 400);
  std::vector<std::int16_t> lb(w), rb(w + d), rc(w + d), out_native(w), out_plain(w);
  const DisparityRowScratch scratch{lb.data(), rb.data(), rc.data()};
  for (const int uniqueness : {0, 10}) {
    select_disparity_row(sums.data(), w, d, uniqueness, 1, scratch, out_native.data());
    select_disparity_row_portable(sums.data(), w, d, uniqueness, 1, scratch, out_plain.data());
    ASSERT_EQ(out_native, out_plain);
  }
  // Four planes' counts at once, on the worst case for its nibble sums
  // (every bit different) and on random bytes.
  std::uint8_t a[8][16];
  for (int round = 0; round < 64; ++round) {
    for (int k = 0; k < 8; ++k) {
      for (int i = 0; i < 16; ++i) {
        const auto r = static_cast<std::uint8_t>(rng());
        a[k][i] = round % 2 == 0 ? static_cast<std::uint8_t>((r & 1) != 0 ? 0xff : 0) : r;
        if (k >= 6) a[k][i] &= 0x7f;  // the last plane's 7 bits
      }
    }
    using N = simd::NativeU8;
    using P = simd::PlainU8;
    std::uint8_t native_count[16];
    N::store(native_count, N::xor_popcount4(N::load(a[0]), N::load(a[1]), N::load(a[2]), N::load(a[3]), N::load(a[4]),
                                            N::load(a[5]), N::load(a[6]), N::load(a[7])));
    const P::V plain_count = P::xor_popcount4(P::load(a[0]), P::load(a[1]), P::load(a[2]), P::load(a[3]),
                                              P::load(a[4]), P::load(a[5]), P::load(a[6]), P::load(a[7]));
    ASSERT_EQ(std::memcmp(native_count, plain_count.x, 16), 0) << round;
  }
}

// The selection fused into the matcher's last pass (packed_winner.hpp)
// against the two-pass selection, with every backend: the same
// disparities, on random sums with many ties, with and without the cut of
// the left columns, uniqueness and the left-right check.
TEST(SemiGlobalMatcher, PackedSelectionMatchesTwoPassSelection) {
  std::mt19937 rng(11);
  for (const int d : {16, 32, 64}) {
    const int w = 150;
    std::vector<std::int16_t> sums(static_cast<std::size_t>(w) * d);
    std::vector<std::int16_t> lb(w), rb(w + d), rc(w + d), expected(w), native(w), plain(w), avx2(w);
    const DisparityRowScratch scratch{lb.data(), rb.data(), rc.data()};
    for (int round = 0; round < 20; ++round) {
      const int range = round % 2 == 0 ? 8 : 728;  // ties, or the default's largest sums
      for (auto& s : sums) s = static_cast<std::int16_t>(rng() % range);
      ASSERT_TRUE(packed_winner_fits(728, d));
      for (const int uniqueness : {0, 10, 50}) {
        for (const int lr : {-1, 0, 1}) {
          select_disparity_row_portable(sums.data(), w, d, uniqueness, lr, scratch, expected.data());
          select_disparity_row_packed(sums.data(), w, d, uniqueness, lr, scratch, native.data());
          select_disparity_row_packed_portable(sums.data(), w, d, uniqueness, lr, scratch, plain.data());
          ASSERT_EQ(native, expected) << d << " " << round << " " << uniqueness << " " << lr;
          ASSERT_EQ(plain, expected) << d << " " << round << " " << uniqueness << " " << lr;
          // Sixteen lanes of AVX2 where the CPU has it (else nothing to
          // compare: Avx2BackendAgreesWithPlain says so by skipping).
          if (select_disparity_row_packed_avx2(sums.data(), w, d, uniqueness, lr, scratch, avx2.data())) {
            ASSERT_EQ(avx2, expected) << d << " " << round << " " << uniqueness << " " << lr;
          }
        }
      }
    }
  }
  EXPECT_FALSE(packed_winner_fits(728, 128));  // the matcher selects in two passes then
}

#if RTFUSE_SIMD_AVX2
RTFUSE_AVX2_BEGIN
// Avx2U8's four-plane count of a[0] ^ a[1], ..., a[6] ^ a[7] into out;
// compiled for AVX2, so called only where the CPU has it.
void avx2_xor_popcount4(const std::uint8_t (*a)[32], std::uint8_t* out) {
  using A = simd::Avx2U8;
  A::store(out, A::xor_popcount4(A::load(a[0]), A::load(a[1]), A::load(a[2]), A::load(a[3]), A::load(a[4]),
                                 A::load(a[5]), A::load(a[6]), A::load(a[7])));
}
RTFUSE_AVX2_END
#endif

bool cpu_runs_avx2() {
#if RTFUSE_SIMD_AVX2
  return simd::cpu_has_avx2();
#else
  return false;
#endif
}

// AVX2's 32 lanes (simd_avx2.hpp) against the plain definitions: the
// four-plane bit count (every bit different, and random bytes) and cost
// rows at several ranges, on random census planes. (Its selection:
// PackedSelectionMatchesTwoPassSelection; the whole matcher:
// Avx2MatcherGivesThePlainBytes.)
TEST(SemiGlobalMatcher, Avx2BackendAgreesWithPlain) {
  if (!cpu_runs_avx2()) GTEST_SKIP() << "no AVX2 on this CPU or architecture: nothing runs it";
#if RTFUSE_SIMD_AVX2
  std::mt19937 rng(29);
  std::uint8_t a[8][32];
  for (int round = 0; round < 64; ++round) {
    for (int k = 0; k < 8; ++k) {
      for (int i = 0; i < 32; ++i) {
        const auto r = static_cast<std::uint8_t>(rng());
        a[k][i] = round % 2 == 0 ? static_cast<std::uint8_t>((r & 1) != 0 ? 0xff : 0) : r;
        if (k >= 6) a[k][i] &= 0x7f;  // the last plane's 7 bits
      }
    }
    std::uint8_t avx2_count[32];
    avx2_xor_popcount4(a, avx2_count);
    using P = simd::PlainU8;
    for (int half = 0; half < 2; ++half) {
      const int o = 16 * half;
      const P::V plain_count = P::xor_popcount4(P::load(a[0] + o), P::load(a[1] + o), P::load(a[2] + o),
                                                P::load(a[3] + o), P::load(a[4] + o), P::load(a[5] + o),
                                                P::load(a[6] + o), P::load(a[7] + o));
      ASSERT_EQ(std::memcmp(avx2_count + o, plain_count.x, 16), 0) << round << " " << half;
    }
  }
  for (const int d : {32, 64, 96, 128}) {
    const int w = d + 45, stride = w + d + 32;
    std::vector<std::uint8_t> left(static_cast<std::size_t>(kCensusPlanes) * w);
    std::vector<std::uint8_t> reversed(static_cast<std::size_t>(kCensusPlanes) * stride);
    for (auto* v : {&left, &reversed}) {
      for (std::size_t i = 0; i < v->size(); ++i) {
        (*v)[i] = static_cast<std::uint8_t>(rng() & (i % 4 == 3 ? 0x7f : 0xff));
      }
    }
    const std::uint8_t *lp[kCensusPlanes], *rp[kCensusPlanes];
    for (int g = 0; g < kCensusPlanes; ++g) {
      lp[g] = left.data() + static_cast<std::size_t>(g) * w;
      rp[g] = reversed.data() + static_cast<std::size_t>(g) * stride;
    }
    std::vector<std::uint8_t> cost_avx2(static_cast<std::size_t>(w) * d + 16), cost_plain(cost_avx2.size());
    ASSERT_TRUE(census_cost_row_avx2(lp, rp, w, d, cost_avx2.data()));
    census_cost_row_portable(lp, rp, w, d, cost_plain.data());
    ASSERT_EQ(std::memcmp(cost_avx2.data(), cost_plain.data(), static_cast<std::size_t>(w) * d), 0) << d;
  }
  std::uint8_t unused[48 * 16] = {};
  const std::uint8_t* planes[kCensusPlanes] = {unused, unused, unused, unused};
  EXPECT_FALSE(census_cost_row_avx2(planes, planes, 16, 48, unused));  // not a multiple of 32
#endif
}

// The digest's pairs: a texture of grey levels on a 3 px lattice, bilinear
// between them in integers, over a plane slanting from lo to hi px with a
// box in front at 1.25 hi, and +-2 grey levels of noise in each eye.
struct SizedPair {
  Plane<std::uint8_t> left, right;
};

SizedPair digest_pair(int w, int h, int lo, int hi, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const int cell = 3, gw = (w + 2 * hi) / cell + 3, gh = h / cell + 3;
  std::vector<int> grid(static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh));
  for (int& g : grid) g = static_cast<int>(rng() % 256);
  auto tex = [&](int u16, int v) {
    const int gu = u16 / (16 * cell), fu = u16 % (16 * cell), gv = v / cell, fv = v % cell;
    auto g = [&](int i, int j) { return grid[static_cast<std::size_t>(j) * static_cast<std::size_t>(gw) + static_cast<std::size_t>(i)]; };
    const int top = g(gu, gv) * (16 * cell - fu) + g(gu + 1, gv) * fu;
    const int bottom = g(gu, gv + 1) * (16 * cell - fu) + g(gu + 1, gv + 1) * fu;
    return (top * (cell - fv) + bottom * fv) / (16 * cell * cell);
  };
  auto clamp = [](int v) { return static_cast<std::uint8_t>(std::clamp(v, 0, 255)); };
  SizedPair p{Plane<std::uint8_t>(w, h), Plane<std::uint8_t>(w, h)};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool box = x > w / 3 && x < w / 2 && y > h / 4 && y < 3 * h / 4;
      const int d16 = box ? 16 * hi + 16 * (hi / 4) : 16 * lo + 16 * (hi - lo) * x / w;
      const int noise_left = static_cast<int>(rng() % 5) - 2, noise_right = static_cast<int>(rng() % 5) - 2;
      p.left.row(y)[x] = clamp(tex(16 * (x + hi + 2), y) + noise_left);
      p.right.row(y)[x] = clamp(tex(16 * (x + hi + 2) + d16, y) + noise_right);
    }
  }
  return p;
}

constexpr int kDigestW = 333, kDigestH = 61;  // odd sizes: no row a multiple of a vector
// The backends' comparisons run the plain lanes, several times slower (and
// far slower under the sanitizers and emulation): a band of the height.
constexpr int kCompareH = 25;

struct DigestCase {
  DisparityParams params;
  std::uint32_t seed;
};

// 48 configurations: 4 and 8 paths, full and half resolution, 16 to 256
// disparities, P2 60 and 96 (the fused selection and the two-pass one),
// and P1, uniqueness, the left-right check and the speckle filter varied
// along.
std::vector<DigestCase> digest_cases() {
  std::vector<DigestCase> cases;
  int i = 0;
  for (const int paths : {4, 8}) {
    for (const int downscale : {1, 2}) {
      for (const int disparities : {16, 32, 48, 64, 96, 128, 256}) {
        for (const int p2 : {60, 96}) {
          if (disparities % (16 * downscale) != 0) continue;
          DisparityParams p;
          p.paths = paths;
          p.downscale = downscale;
          p.disparities = disparities;
          p.p2 = p2;
          p.p1 = i % 3 == 0 ? 5 : 9;
          p.uniqueness_percent = i % 4 == 1 ? 0 : 10;
          p.lr_max_diff = i % 5 == 2 ? -1 : (i % 5 == 3 ? 0 : 1);
          p.speckle_window = i % 6 == 4 ? 0 : 100;
          cases.push_back({p, static_cast<std::uint32_t>(100 + i)});
          ++i;
        }
      }
    }
  }
  return cases;
}

// The disparities of one case on one backend, kDigestW x h.
Plane<std::uint16_t> match_case(const DigestCase& c, int h, DisparityBackend backend, DisparityBackend* used) {
  const SizedPair p = digest_pair(kDigestW, h, c.params.disparities / 8, c.params.disparities / 2, c.seed);
  SemiGlobalMatcher m(kDigestW, h, c.params, backend);
  EXPECT_TRUE(m.valid()) << m.error();
  Plane<std::uint16_t> out(m.output_width(kDigestW), m.output_height(h));
  EXPECT_EQ(m.compute(view_of(p.left), view_of(p.right), view_of(out)), DisparityStatus::kOk);
  *used = m.backend();
  return out;
}

bool same_bytes(const Plane<std::uint16_t>& a, const Plane<std::uint16_t>& b) {
  for (int y = 0; y < a.height(); ++y) {
    if (std::memcmp(a.row(y), b.row(y), static_cast<std::size_t>(a.width()) * sizeof(std::uint16_t)) != 0) return false;
  }
  return true;
}

// The digest of every configuration's disparities is the one the matcher
// gave before the AVX2 backend (SSE2, plain and NEON builds alike): on
// this machine's fastest backend, so on x86-64 with AVX2 it checks AVX2.
TEST(SemiGlobalMatcher, DigestOfConfigurationsUnchanged) {
  Xxh64 all;
  for (const DigestCase& c : digest_cases()) {
    DisparityBackend used = DisparityBackend::kAuto;
    const Plane<std::uint16_t> out = match_case(c, kDigestH, DisparityBackend::kAuto, &used);
    Xxh64 one;
    for (int y = 0; y < out.height(); ++y) one.update(out.row(y), static_cast<std::size_t>(out.width()) * 2);
    const std::uint64_t digest = one.digest();
    all.update(&digest, sizeof digest);  // little-endian on both architectures
  }
  EXPECT_EQ(all.digest(), 0x2a6a144db57688ecULL);
}

// The build's baseline lanes (SSE2, NEON) against the plain ones, through
// the whole matcher, on every configuration of the digest.
TEST(SemiGlobalMatcher, BaselineMatcherGivesThePlainBytes) {
  int i = 0;
  for (const DigestCase& c : digest_cases()) {
    DisparityBackend used_plain = DisparityBackend::kAuto, used = DisparityBackend::kAuto;
    const Plane<std::uint16_t> plain = match_case(c, kCompareH, DisparityBackend::kPlain, &used_plain);
    const Plane<std::uint16_t> baseline = match_case(c, kCompareH, DisparityBackend::kBaseline, &used);
    ASSERT_EQ(used_plain, DisparityBackend::kPlain);
    ASSERT_EQ(used, DisparityBackend::kBaseline);
    EXPECT_TRUE(same_bytes(baseline, plain)) << "case " << i;
    ++i;
  }
}

// AVX2 against the plain lanes through the whole matcher, on every
// configuration of the digest whose matched disparities are a multiple
// of 32 (the others run the baseline, as asked of kAvx2 there).
TEST(SemiGlobalMatcher, Avx2MatcherGivesThePlainBytes) {
  if (!cpu_runs_avx2()) GTEST_SKIP() << "no AVX2 on this CPU or architecture: nothing runs it";
  int i = 0, on_avx2 = 0;
  for (const DigestCase& c : digest_cases()) {
    DisparityBackend used_plain = DisparityBackend::kAuto, used = DisparityBackend::kAuto;
    const Plane<std::uint16_t> plain = match_case(c, kCompareH, DisparityBackend::kPlain, &used_plain);
    const Plane<std::uint16_t> avx2 = match_case(c, kCompareH, DisparityBackend::kAvx2, &used);
    const bool applies = (c.params.disparities / c.params.downscale) % 32 == 0;
    ASSERT_EQ(used, applies ? DisparityBackend::kAvx2 : DisparityBackend::kBaseline) << "case " << i;
    EXPECT_TRUE(same_bytes(avx2, plain)) << "case " << i;
    on_avx2 += applies ? 1 : 0;
    ++i;
  }
  EXPECT_EQ(on_avx2, 32);
}

TEST(SemiGlobalMatcher, BackendChosenAtConstruction) {
  DisparityParams p;  // 64 disparities
  EXPECT_EQ(SemiGlobalMatcher(640, 480, p, DisparityBackend::kPlain).backend(), DisparityBackend::kPlain);
  EXPECT_EQ(SemiGlobalMatcher(640, 480, p, DisparityBackend::kBaseline).backend(), DisparityBackend::kBaseline);
  const DisparityBackend fastest = cpu_runs_avx2() ? DisparityBackend::kAvx2 : DisparityBackend::kBaseline;
  EXPECT_EQ(SemiGlobalMatcher(640, 480, p).backend(), fastest);
  EXPECT_EQ(SemiGlobalMatcher(640, 480, p, DisparityBackend::kAvx2).backend(), fastest);
  p.disparities = 48;  // not a multiple of 32: the baseline
  EXPECT_EQ(SemiGlobalMatcher(640, 480, p).backend(), DisparityBackend::kBaseline);
  p.disparities = 64;
  p.downscale = 2;  // 32 matched
  EXPECT_EQ(SemiGlobalMatcher(640, 480, p).backend(), fastest);
  for (const auto b : {DisparityBackend::kAuto, DisparityBackend::kBaseline, DisparityBackend::kAvx2,
                       DisparityBackend::kPlain}) {
    EXPECT_STRNE(to_string(b), "unknown");
  }
}

// Sums too wide to pack with their disparity (a larger P2 and range) take
// the two-pass selection; both paths through the matcher find the scene.
TEST(SemiGlobalMatcher, WideSumsFallBackToTwoPassSelection) {
  const Pair p = occlusion_scene();
  DisparityParams fused = params32();
  ASSERT_TRUE(packed_winner_fits(fused.paths * (fused.p2 + kCensusBits), fused.disparities));
  DisparityParams two_pass = fused;
  two_pass.paths = 8;
  two_pass.p2 = 96;
  two_pass.disparities = 128;
  ASSERT_FALSE(packed_winner_fits(two_pass.paths * (two_pass.p2 + kCensusBits), two_pass.disparities));
  const Match a = run(p, fused), b = run(p, two_pass);
  ASSERT_EQ(a.status, DisparityStatus::kOk);
  ASSERT_EQ(b.status, DisparityStatus::kOk);
  int n = 0;
  const auto truth = [](int x, int y) { return y >= 24 && y < 72 && x >= 60 && x < 100 ? 20.0 : 4.0; };
  EXPECT_GE(share_within(b, 64, 1.0, truth, &n), 0.95);
  EXPECT_GE(share_within(a, 64, 1.0, truth, &n), 0.95);
}

TEST(SemiGlobalMatcher, SubpixelOffsetIsSymmetricAndBounded) {
  EXPECT_EQ(subpixel_offset(10, 0, 10), 0);
  EXPECT_EQ(subpixel_offset(20, 0, 10), -subpixel_offset(10, 0, 20));
  EXPECT_GT(subpixel_offset(20, 0, 10), 0);  // the vertex leans to the cheaper side
  EXPECT_LE(std::abs(subpixel_offset(100, 0, 0)), kDisparityScale / 2);
  EXPECT_EQ(subpixel_offset(5, 5, 5), 0);
}

}  // namespace semi_global_matcher_test
}  // namespace rtfuse::vision
