// Sub-pixel alignment on images drawn from a smooth function at known
// fractional shifts: the shift comes back to a few hundredths of a pixel,
// with or without a change of exposure; a flat patch and a shift too far
// are refused.
#include "vision/patch_aligner.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rtfuse::vision {
namespace patch_aligner_test {

// A smooth texture, sampled at (u + du, v + dv), plus an exposure offset.
Plane<std::uint8_t> draw(double du, double dv, double offset = 0.0) {
  Plane<std::uint8_t> p(64, 64);
  for (int v = 0; v < 64; ++v)
    for (int u = 0; u < 64; ++u) {
      const double x = u + du, y = v + dv;
      const double g = 128.0 + 50.0 * std::sin(0.35 * x + 0.2 * y) + 40.0 * std::cos(0.27 * y - 0.1 * x) + offset;
      p.row(v)[u] = static_cast<std::uint8_t>(std::lround(std::max(0.0, std::min(255.0, g))));
    }
  return p;
}

TEST(PatchAligner, FindsFractionalShifts) {
  const Plane<std::uint8_t> ref = draw(0.0, 0.0);
  PatchAligner a;
  ASSERT_TRUE(a.set_reference(ref, 32, 32));
  for (const auto& [du, dv] : {std::pair{0.3, -0.2}, std::pair{-0.7, 0.45}, std::pair{1.2, 0.9}, std::pair{0.0, 0.0}}) {
    // The target shows the texture shifted by (du, dv): the reference's
    // centre is at (32 - du, 32 - dv) there.
    const Plane<std::uint8_t> target = draw(du, dv);
    double u = 0, v = 0;
    ASSERT_TRUE(a.align(target, std::round(32 - du), std::round(32 - dv), 1.5, &u, &v)) << du << "," << dv;
    EXPECT_NEAR(u, 32 - du, 0.05) << du;
    EXPECT_NEAR(v, 32 - dv, 0.05) << dv;
  }
}

TEST(PatchAligner, AnExposureOffsetDoesNotMoveTheFit) {
  const Plane<std::uint8_t> ref = draw(0.0, 0.0);
  PatchAligner a;
  ASSERT_TRUE(a.set_reference(ref, 30, 34));
  double u = 0, v = 0;
  ASSERT_TRUE(a.align(draw(0.4, 0.1, 25.0), 30, 34, 1.5, &u, &v));
  EXPECT_NEAR(u, 29.6, 0.06);
  EXPECT_NEAR(v, 33.9, 0.06);
}

TEST(PatchAligner, FlatPatchesBordersAndRunawaysAreRefused) {
  Plane<std::uint8_t> flat(32, 32);
  for (int v = 0; v < 32; ++v)
    for (int u = 0; u < 32; ++u) flat.row(v)[u] = 90;
  PatchAligner a;
  EXPECT_FALSE(a.set_reference(flat, 16, 16));
  // Stripes: texture in one direction only.
  for (int v = 0; v < 32; ++v)
    for (int u = 0; u < 32; ++u) flat.row(v)[u] = static_cast<std::uint8_t>(u % 4 < 2 ? 40 : 200);
  EXPECT_FALSE(a.set_reference(flat, 16, 16));
  const Plane<std::uint8_t> ref = draw(0.0, 0.0);
  EXPECT_FALSE(a.set_reference(ref, 3, 32));
  ASSERT_TRUE(a.set_reference(ref, 32, 32));
  double u = 0, v = 0;
  EXPECT_FALSE(a.align(draw(6.0, 0.0), 32, 32, 1.5, &u, &v));  // the fit would have to run 6 px
  EXPECT_FALSE(a.align(ref, 60, 32, 1.5, &u, &v));             // off the image
}

}  // namespace patch_aligner_test
}  // namespace rtfuse::vision
