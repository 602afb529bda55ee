// Tick steps a reader can add up (1, 2 or 5 times a power of ten), as few
// as the room allows but never fewer than asked, ticks on the step's
// multiples covering the range, and labels without stray decimals or "-0".
#include "apps/nice_ticks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace rtfuse::apps {
namespace nice_ticks_test {

// The mantissa of a 1-2-5 step: 1, 2 or 5 (to rounding).
double mantissa(double step) { return step / std::pow(10.0, std::floor(std::log10(step) + 1e-9)); }

bool is_one_two_five(double step) {
  const double m = mantissa(step);
  return std::abs(m - 1.0) < 1e-9 || std::abs(m - 2.0) < 1e-9 || std::abs(m - 5.0) < 1e-9;
}

// Over spans from micrometres to thousands of kilometres: the step is 1-2-5,
// splits the span into no more intervals than allowed, and the next smaller
// 1-2-5 step would split it into more (the step is the finest that fits).
TEST(NiceTicks, StepIsTheFinestOneTwoFiveThatFits) {
  const double spans[] = {1e-6, 3.7e-4, 0.013, 0.9, 1.0, 2.5, 7.3, 10.0, 59.86, 123.0, 4096.0, 3.3e6};
  for (const double span : spans)
    for (int max_intervals = 1; max_intervals <= 20; ++max_intervals) {
      const double step = nice_step(span, max_intervals);
      ASSERT_TRUE(is_one_two_five(step)) << span << " / " << max_intervals << " -> " << step;
      EXPECT_LE(span / step, max_intervals * (1.0 + 1e-9)) << span << " / " << max_intervals << " -> " << step;
      const double m = mantissa(step);
      const double finer = step * (std::abs(m - 1.0) < 1e-9 ? 0.5 : std::abs(m - 2.0) < 1e-9 ? 0.5 : 0.4);
      EXPECT_GT(span / finer, max_intervals * (1.0 - 1e-9)) << span << " / " << max_intervals << " -> " << step;
    }
}

TEST(NiceTicks, SeriesGoesOneTwoFive) {
  EXPECT_DOUBLE_EQ(next_nice_step(1.0), 2.0);
  EXPECT_DOUBLE_EQ(next_nice_step(2.0), 5.0);
  EXPECT_DOUBLE_EQ(next_nice_step(5.0), 10.0);
  EXPECT_DOUBLE_EQ(next_nice_step(0.05), 0.1);
  EXPECT_DOUBLE_EQ(nice_step_at_least(0.2), 0.2);  // not 0.5 because 0.2 is not exact in binary
  EXPECT_DOUBLE_EQ(nice_step_at_least(0.21), 0.5);
  EXPECT_DOUBLE_EQ(nice_step_at_least(5000.0), 5000.0);
}

// No data, NaN or infinity must still give a usable step, not 0 or NaN
// (which would divide by zero or loop for ever when drawing ticks).
TEST(NiceTicks, DegenerateSpansGiveAUsableStep) {
  EXPECT_DOUBLE_EQ(nice_step(0.0, 5), 1.0);
  EXPECT_DOUBLE_EQ(nice_step(std::numeric_limits<double>::quiet_NaN(), 5), 1.0);
  EXPECT_DOUBLE_EQ(nice_step(std::numeric_limits<double>::infinity(), 5), 1.0);
  EXPECT_DOUBLE_EQ(nice_step(10.0, 0), 10.0);  // at least one interval
  EXPECT_DOUBLE_EQ(nice_step(-10.0, 5), 2.0);  // a span's size, whichever way round
}

// The ticks are the multiples inside the range, ends included even when
// floating point puts a multiple a hair outside.
TEST(NiceTicks, TicksAreTheMultiplesCoveringTheRange) {
  const std::vector<double> t = tick_values(-0.3, 0.9, 0.2);
  ASSERT_EQ(t.size(), 6u);
  EXPECT_NEAR(t.front(), -0.2, 1e-12);
  EXPECT_NEAR(t.back(), 0.8, 1e-12);
  for (std::size_t i = 1; i < t.size(); ++i) EXPECT_NEAR(t[i] - t[i - 1], 0.2, 1e-12);

  const std::vector<double> ends = tick_values(0.1 * 3, 0.7, 0.1);  // 0.30000000000000004
  ASSERT_EQ(ends.size(), 5u);
  EXPECT_NEAR(ends.front(), 0.3, 1e-12);
  EXPECT_NEAR(ends.back(), 0.7, 1e-12);

  EXPECT_TRUE(tick_values(1.0, 0.0, 0.5).empty());
  EXPECT_TRUE(tick_values(0.0, 1.0, 0.0).empty());
  EXPECT_TRUE(tick_values(0.0, 1.0, -1.0).empty());
  EXPECT_TRUE(tick_values(0.0, std::numeric_limits<double>::infinity(), 1.0).empty());
  EXPECT_TRUE(tick_values(0.0, 1e9, 1.0).empty()) << "no million ticks";
  EXPECT_EQ(tick_values(2.5, 2.5, 0.5).size(), 1u);
}

TEST(NiceTicks, LabelsCarryTheStepsDecimals) {
  EXPECT_EQ(tick_label(2.5, 0.5), "2.5");
  EXPECT_EQ(tick_label(3.0, 0.5), "3.0");
  EXPECT_EQ(tick_label(40.0, 20.0), "40");
  EXPECT_EQ(tick_label(0.15000000000000002, 0.05), "0.15");
  EXPECT_EQ(tick_label(-1e-17, 0.1), "0.0");
  EXPECT_EQ(tick_label(-1e-13, 5.0), "0");
  EXPECT_EQ(tick_label(-0.2, 0.1), "-0.2");
  EXPECT_EQ(tick_label(1000.0, 200.0), "1000");
}

}  // namespace nice_ticks_test
}  // namespace rtfuse::apps
