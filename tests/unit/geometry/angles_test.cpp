#include "geometry/angles.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace angles_test {

using rtfuse::geometry::kPi;
using rtfuse::geometry::kTwoPi;
using rtfuse::geometry::wrap_angle;

bool in_range(double a) { return a >= -kPi && a < kPi; }

TEST(GeometryWrapAngle, HalfOpenInterval) {
  EXPECT_EQ(wrap_angle(kPi), -kPi);  // pi itself is excluded
  EXPECT_EQ(wrap_angle(-kPi), -kPi);
  EXPECT_EQ(wrap_angle(std::nextafter(kPi, 0.0)), std::nextafter(kPi, 0.0));
  EXPECT_TRUE(in_range(wrap_angle(3 * kPi)));
  EXPECT_NEAR(wrap_angle(3 * kPi), -kPi, 1e-12);
  EXPECT_TRUE(in_range(wrap_angle(-3 * kPi)));
  EXPECT_NEAR(wrap_angle(-3 * kPi), -kPi, 1e-12);
}

TEST(GeometryWrapAngle, KnownValues) {
  EXPECT_EQ(wrap_angle(0.0), 0.0);
  EXPECT_EQ(wrap_angle(0.5), 0.5);
  EXPECT_EQ(wrap_angle(-0.5), -0.5);
  EXPECT_NEAR(wrap_angle(kTwoPi), 0.0, 1e-15);
  EXPECT_NEAR(wrap_angle(-7.5 * kPi), 0.5 * kPi, 1e-12);  // -7.5pi + 8pi
  EXPECT_NEAR(wrap_angle(7.5 * kPi), -0.5 * kPi, 1e-12);
  EXPECT_NEAR(wrap_angle(1.5 * kPi), -0.5 * kPi, 1e-15);
  // 1e6 - 159155 * 2pi, computed to 50 digits; the 4e-11 gap is the
  // difference between 2pi and its double, times 159155 turns.
  EXPECT_NEAR(wrap_angle(1e6), -0.357564167085735, 1e-10);
  EXPECT_NEAR(wrap_angle(-1e6), 0.357564167085735, 1e-10);
}

TEST(GeometryWrapAngle, HugeAndTinyInputs) {
  for (double a : {1e15, -1e15, 1e300, -1e300, 4.9e-324, -4.9e-324, 1e-300}) {
    const double w = wrap_angle(a);
    EXPECT_TRUE(std::isfinite(w)) << a;
    EXPECT_TRUE(in_range(w)) << a;
  }
  EXPECT_EQ(wrap_angle(1e-300), 1e-300);
  EXPECT_TRUE(std::isnan(wrap_angle(std::nan(""))));
}

TEST(GeometryWrapAngle, SameDirectionAndInRangeOverASweep) {
  for (int i = -20000; i <= 20000; ++i) {
    const double a = i * 0.0137 * kPi;
    const double w = wrap_angle(a);
    ASSERT_TRUE(in_range(w)) << a;
    ASSERT_NEAR(std::cos(w), std::cos(a), 1e-9) << a;
    ASSERT_NEAR(std::sin(w), std::sin(a), 1e-9) << a;
    // Values already in range are returned unchanged.
    if (a >= -kPi && a < kPi) {
      ASSERT_EQ(w, a);
    }
  }
}

}  // namespace angles_test
