// The per-frame rectifier on synthetic side-by-side YUYV frames: exact copies
// for an aligned pair, known sub-pixel interpolation, zeros where the source
// is outside the raw image, luma taken from even bytes only, frames it must
// refuse, a pinned checksum for bit-identical output across architectures,
// and no allocation per frame.
#include "drivers/camera/stereo_rectifier.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "drivers/camera/stereo_rectification.hpp"
#include "support/alloc_counter.hpp"
#include "unit/drivers/zed_test_calibrations.hpp"

namespace stereo_rectifier_test {

using rtfuse::drivers::GreyImageView;
using rtfuse::drivers::StereoCalibration;
using rtfuse::drivers::StereoRectification;
using rtfuse::drivers::StereoRectifier;
using rtfuse::drivers::YuyvFrameView;

constexpr int kW = 64;
constexpr int kH = 40;

// An undistorted, perfectly aligned pair: rectification changes nothing.
StereoCalibration aligned_pair(int w = kW, int h = kH) {
  StereoCalibration c;
  c.width = w;
  c.height = h;
  c.left = {50, 50, (w - 1) / 2.0, (h - 1) / 2.0, 0, 0, 0, 0, 0};
  c.right = c.left;
  c.translation = Eigen::Vector3d(-0.12, 0, 0);
  return c;
}

StereoRectification rectification_of(const StereoCalibration& c) {
  StereoRectification r;
  std::string error;
  EXPECT_TRUE(compute_stereo_rectification(c, &r, &error)) << error;
  return r;
}

// Side-by-side YUYV frame whose luma is luma(eye, x, y) and whose chroma
// bytes are extreme, so any chroma leaking into the output shows.
template <typename F>
std::vector<std::uint8_t> yuyv_frame(int eye_w, int h, int bpl, F luma) {
  std::vector<std::uint8_t> f(static_cast<std::size_t>(bpl) * static_cast<std::size_t>(h), 0xEE);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < 2 * eye_w; ++x) {
      const std::size_t o = static_cast<std::size_t>(y) * static_cast<std::size_t>(bpl) + static_cast<std::size_t>(x) * 2;
      f[o] = static_cast<std::uint8_t>(luma(x / eye_w, x % eye_w, y));
      f[o + 1] = (x & 1) ? 0xFF : 0x00;
    }
  }
  return f;
}

struct Output {
  int w, h, stride;
  std::vector<std::uint8_t> left, right;
  Output(int w_, int h_, int stride_)
      : w(w_), h(h_), stride(stride_),
        left(static_cast<std::size_t>(stride_) * static_cast<std::size_t>(h_), 0xAA),
        right(left.size(), 0xAA) {}
  int at(int eye, int u, int v) const {
    return (eye == 0 ? left : right)[static_cast<std::size_t>(v) * static_cast<std::size_t>(stride) +
                                     static_cast<std::size_t>(u)];
  }
  GreyImageView view(int eye) { return {(eye == 0 ? left : right).data(), stride}; }
};

TEST(StereoRectifier, AlignedPairIsCopiedExactlyFromTheLuma) {
  const StereoCalibration c = aligned_pair();
  StereoRectification r = rectification_of(c);
  // Exactly the raw camera, so every source position is an integer pixel.
  for (auto* eye : {&r.left, &r.right}) {
    eye->rotation.setIdentity();
    eye->projection.leftCols<3>() << 50, 0, (kW - 1) / 2.0, 0, 50, (kH - 1) / 2.0, 0, 0, 1;
  }
  const int bpl = kW * 4 + 24;  // padded lines
  const StereoRectifier rectifier(c, r, bpl);
  EXPECT_EQ(rectifier.bytes_per_line(), bpl);
  const auto frame = yuyv_frame(kW, kH, bpl, [](int eye, int x, int y) { return (eye * 97 + x * 3 + y * 5) & 0xFF; });
  Output out(kW, kH, kW + 8);
  ASSERT_TRUE(rectifier.rectify({frame.data(), frame.size(), 2 * kW, kH, bpl}, out.view(0), out.view(1)));
  for (int eye = 0; eye < 2; ++eye) {
    for (int v = 0; v < kH; ++v) {
      for (int u = 0; u < kW; ++u) ASSERT_EQ(out.at(eye, u, v), (eye * 97 + u * 3 + v * 5) & 0xFF) << eye << " " << u << " " << v;
      // Bytes past the eye's width in a padded output row stay untouched.
      for (int u = kW; u < out.stride; ++u) ASSERT_EQ(out.at(eye, u, v), 0xAA);
    }
  }
}

TEST(StereoRectifier, SubPixelSourceIsInterpolatedWithRoundingHalfUp) {
  const StereoCalibration c = aligned_pair();
  StereoRectification r = rectification_of(c);
  // Left eye samples a quarter pixel right of each rectified pixel, right eye
  // three quarters of a pixel down.
  for (auto* eye : {&r.left, &r.right}) {
    eye->rotation.setIdentity();
    eye->projection.leftCols<3>() << 50, 0, (kW - 1) / 2.0, 0, 50, (kH - 1) / 2.0, 0, 0, 1;
  }
  r.left.projection(0, 2) -= 0.25;
  r.right.projection(1, 2) -= 0.75;
  const StereoRectifier rectifier(c, r);
  const int bpl = kW * 4;
  const auto frame = yuyv_frame(kW, kH, bpl, [](int, int x, int y) { return 2 * x + 3 * y; });
  Output out(kW, kH, kW);
  ASSERT_TRUE(rectifier.rectify({frame.data(), frame.size(), 2 * kW, kH, bpl}, out.view(0), out.view(1)));
  for (int v = 0; v < kH; ++v) {
    for (int u = 0; u + 1 < kW; ++u) {
      // 2 (u + 0.25) + 3 v = 2u + 3v + 0.5: rounds up.
      ASSERT_EQ(out.at(0, u, v), 2 * u + 3 * v + 1) << u << " " << v;
    }
    if (v + 1 < kH) {
      for (int u = 0; u < kW; ++u) {
        // 2u + 3 (v + 0.75) = 2u + 3v + 2.25: rounds down.
        ASSERT_EQ(out.at(1, u, v), 2 * u + 3 * v + 2) << u << " " << v;
      }
    }
  }
  // The last column / row sample outside the raw image: 0.
  EXPECT_EQ(out.at(0, kW - 1, 5), 0);
  EXPECT_EQ(out.at(1, 5, kH - 1), 0);
}

TEST(StereoRectifier, SourceOutsideTheRawImageGivesZeroAndTheEdgeItself) {
  const StereoCalibration c = aligned_pair();
  StereoRectification r = rectification_of(c);
  for (auto* eye : {&r.left, &r.right}) {
    eye->rotation.setIdentity();
    eye->projection.leftCols<3>() << 50, 0, (kW - 1) / 2.0, 0, 50, (kH - 1) / 2.0, 0, 0, 1;
  }
  r.left.projection(0, 2) += 10;   // left eye: raw x = u - 10
  r.right.projection(1, 2) -= 10;  // right eye: raw y = v + 10
  const StereoRectifier rectifier(c, r);
  const int bpl = kW * 4;
  const auto frame = yuyv_frame(kW, kH, bpl, [](int, int, int) { return 200; });
  Output out(kW, kH, kW);
  ASSERT_TRUE(rectifier.rectify({frame.data(), frame.size(), 2 * kW, kH, bpl}, out.view(0), out.view(1)));
  for (int v = 0; v < kH; ++v) {
    for (int u = 0; u < kW; ++u) {
      ASSERT_EQ(out.at(0, u, v), u < 10 ? 0 : 200) << u << " " << v;
      ASSERT_EQ(out.at(1, u, v), v + 10 > kH - 1 ? 0 : 200) << u << " " << v;
    }
  }
  // Raw x = 0 and raw y = kH - 1 exactly are inside (the image's own edge).
  EXPECT_TRUE(rectifier.sample(0, 10, 0).inside);
  EXPECT_FALSE(rectifier.sample(0, 9, 0).inside);
  const StereoRectifier::Sample last_row = rectifier.sample(1, 0, kH - 11);
  EXPECT_TRUE(last_row.inside);
  EXPECT_EQ(last_row.y, kH - 2);  // the pair before the edge, fully weighted down
  EXPECT_EQ(last_row.wy, StereoRectifier::kOne);
  EXPECT_FALSE(rectifier.sample(1, 0, kH - 10).inside);
}

TEST(StereoRectifier, TableFollowsTheRemapToWithinAHundredTwentyEighthPixel) {
  const StereoCalibration c = rtfuse::test::zed_like_vga();
  const StereoRectification r = rectification_of(c);
  const StereoRectifier rectifier(c, r);
  EXPECT_EQ(rectifier.width(), 672);
  EXPECT_EQ(rectifier.height(), 376);
  for (int eye = 0; eye < 2; ++eye) {
    const rtfuse::drivers::RawPositionMap map(eye == 0 ? c.left : c.right, eye == 0 ? r.left : r.right);
    for (int v = 0; v < c.height; v += 7) {
      for (int u = 0; u < c.width; u += 5) {
        double x = 0, y = 0;
        ASSERT_TRUE(map.at(u, v, &x, &y));
        const StereoRectifier::Sample s = rectifier.sample(eye, u, v);
        ASSERT_TRUE(s.inside);
        EXPECT_NEAR(s.x + s.wx / 64.0, x, 1.0 / 128 + 1e-9);
        EXPECT_NEAR(s.y + s.wy / 64.0, y, 1.0 / 128 + 1e-9);
      }
    }
  }
}

// FNV-1a over both rectified eyes of a fixed frame through the ZED-like VGA
// calibration. The same number on x86-64 and aarch64 is the point: if it
// changes, the tables or the interpolation changed (update it deliberately).
TEST(StereoRectifier, OutputChecksumIsPinned) {
  const StereoCalibration c = rtfuse::test::zed_like_vga();
  const StereoRectifier rectifier(c, rectification_of(c));
  const int bpl = c.width * 4;
  const auto frame = yuyv_frame(c.width, c.height, bpl, [](int eye, int x, int y) {
    return (x * 7 + y * 13 + eye * 31 + ((x * y) >> 5)) & 0xFF;
  });
  Output out(c.width, c.height, c.width);
  ASSERT_TRUE(rectifier.rectify({frame.data(), frame.size(), 2 * c.width, c.height, bpl}, out.view(0), out.view(1)));
  std::uint64_t h = 1469598103934665603ull;
  for (const auto* img : {&out.left, &out.right}) {
    for (std::uint8_t b : *img) h = (h ^ b) * 1099511628211ull;
  }
  EXPECT_EQ(h, 0x6cac58a7e376be84ull) << std::hex << "0x" << h;
  // The plain C++ kernel (what aarch64 runs) gives the same bytes as the
  // SSE2 one, on every pixel, odd widths' scalar tails included.
  Output portable(c.width, c.height, c.width);
  ASSERT_TRUE(rectifier.rectify_portable({frame.data(), frame.size(), 2 * c.width, c.height, bpl}, portable.view(0),
                                         portable.view(1)));
  EXPECT_EQ(portable.left, out.left);
  EXPECT_EQ(portable.right, out.right);
}

TEST(StereoRectifier, PortableKernelMatchesOnOddWidthsAndEdges) {
  // 67 px per eye: 16 steps of four and a tail of three; a rotated pair so
  // that some pixels are outside and the weights cover the whole range.
  StereoCalibration c = rtfuse::test::rotated_vga();
  c.width = 67;
  c.height = 31;
  c.left.cx = c.right.cx = 33;
  c.left.cy = c.right.cy = 15;
  c.left.fx = c.left.fy = c.right.fx = c.right.fy = 40;
  StereoRectification r = rectification_of(c);
  r.left.projection(0, 2) += 3.3;  // push a few columns outside
  const StereoRectifier rectifier(c, r);
  const int bpl = c.width * 4;
  const auto frame = yuyv_frame(c.width, c.height, bpl, [](int eye, int x, int y) { return (x * 37 + y * 91 + eye) & 0xFF; });
  Output a(c.width, c.height, c.width + 5), b(c.width, c.height, c.width + 5);
  const YuyvFrameView view{frame.data(), frame.size(), 2 * c.width, c.height, bpl};
  ASSERT_TRUE(rectifier.rectify(view, a.view(0), a.view(1)));
  ASSERT_TRUE(rectifier.rectify_portable(view, b.view(0), b.view(1)));
  EXPECT_EQ(a.left, b.left);
  EXPECT_EQ(a.right, b.right);
  int zeros = 0;
  for (int v = 0; v < c.height; ++v) zeros += !rectifier.sample(0, 0, v).inside;
  EXPECT_GT(zeros, 0);
}

TEST(StereoRectifier, RefusesFramesThatDoNotFit) {
  const StereoCalibration c = aligned_pair();
  const StereoRectifier rectifier(c, rectification_of(c));
  const int bpl = kW * 4;
  const auto frame = yuyv_frame(kW, kH, bpl, [](int, int, int) { return 1; });
  Output out(kW, kH, kW);
  const YuyvFrameView good{frame.data(), frame.size(), 2 * kW, kH, bpl};
  ASSERT_TRUE(rectifier.rectify(good, out.view(0), out.view(1)));
  YuyvFrameView f = good;
  f.width = kW;  // one eye only
  EXPECT_FALSE(rectifier.rectify(f, out.view(0), out.view(1)));
  f = good;
  f.height = kH - 1;
  EXPECT_FALSE(rectifier.rectify(f, out.view(0), out.view(1)));
  f = good;
  f.bytes_per_line = bpl - 2;
  EXPECT_FALSE(rectifier.rectify(f, out.view(0), out.view(1)));
  f = good;
  f.bytes_per_line = bpl + 4;  // not the pitch the tables were built for
  EXPECT_FALSE(rectifier.rectify(f, out.view(0), out.view(1)));
  f = good;
  f.size = frame.size() - 1;  // a truncated buffer (bytes_used short)
  EXPECT_FALSE(rectifier.rectify(f, out.view(0), out.view(1)));
  f = good;
  f.data = nullptr;
  EXPECT_FALSE(rectifier.rectify(f, out.view(0), out.view(1)));
  EXPECT_FALSE(rectifier.rectify(good, {nullptr, kW}, out.view(1)));
  EXPECT_FALSE(rectifier.rectify(good, out.view(0), {out.right.data(), kW - 1}));
  // A rectifier too small to build refuses everything.
  StereoCalibration tiny = aligned_pair(1, 1);
  StereoRectification tiny_r;
  tiny_r.width = 1;
  tiny_r.height = 1;
  const StereoRectifier empty(tiny, tiny_r);
  EXPECT_EQ(empty.width(), 0);
  EXPECT_FALSE(empty.rectify({frame.data(), frame.size(), 2, 1, 8}, out.view(0), out.view(1)));
}

TEST(StereoRectifier, TablesFollowANewLinePitchInPlace) {
  const StereoCalibration c = rtfuse::test::zed_like_vga();
  const StereoRectification r = rectification_of(c);
  auto luma = [](int eye, int x, int y) { return (x * 5 + y * 3 + eye * 50) & 0xFF; };
  const int tight = c.width * 4;
  const int padded = tight + 64;
  const auto tight_frame = yuyv_frame(c.width, c.height, tight, luma);
  const auto padded_frame = yuyv_frame(c.width, c.height, padded, luma);
  StereoRectifier rectifier(c, r);
  EXPECT_EQ(rectifier.bytes_per_line(), tight);
  Output expected(c.width, c.height, c.width);
  ASSERT_TRUE(rectifier.rectify({tight_frame.data(), tight_frame.size(), 2 * c.width, c.height, tight},
                                expected.view(0), expected.view(1)));
  EXPECT_FALSE(rectifier.set_bytes_per_line(tight - 2));
  EXPECT_EQ(rectifier.bytes_per_line(), tight);
  ASSERT_TRUE(rectifier.set_bytes_per_line(padded));
  Output out(c.width, c.height, c.width);
  {
    rtfuse::test::AllocScope scope;
    ASSERT_TRUE(rectifier.rectify({padded_frame.data(), padded_frame.size(), 2 * c.width, c.height, padded},
                                  out.view(0), out.view(1)));
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_EQ(out.left, expected.left);
  EXPECT_EQ(out.right, expected.right);
  // The same as tables built for that pitch from the start.
  const StereoRectifier direct(c, r, padded);
  for (int v = 0; v < c.height; v += 11) {
    for (int u = 0; u < c.width; u += 13) {
      const StereoRectifier::Sample a = rectifier.sample(1, u, v);
      const StereoRectifier::Sample b = direct.sample(1, u, v);
      ASSERT_EQ(a.x, b.x);
      ASSERT_EQ(a.y, b.y);
      ASSERT_EQ(a.wx, b.wx);
      ASSERT_EQ(a.wy, b.wy);
    }
  }
}

TEST(StereoRectifier, NoAllocationPerFrame) {
  const StereoCalibration c = rtfuse::test::zed_like_vga();
  const StereoRectifier rectifier(c, rectification_of(c));
  const int bpl = c.width * 4;
  const auto frame = yuyv_frame(c.width, c.height, bpl, [](int, int x, int y) { return x ^ y; });
  Output out(c.width, c.height, c.width);
  const YuyvFrameView view{frame.data(), frame.size(), 2 * c.width, c.height, bpl};
  ASSERT_TRUE(rectifier.rectify(view, out.view(0), out.view(1)));
  rtfuse::test::AllocScope scope;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(rectifier.rectify(view, out.view(0), out.view(1)));
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace stereo_rectifier_test
