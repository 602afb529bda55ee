// The data-to-pixel mapping of a plot: equal scale when asked, every datum
// inside the area, 1-2-5 ticks covering the range and spaced for their
// labels, a drawable picture for empty or single-valued data, and data
// kept inside the frame.
#include "apps/plot_axes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include "apps/bitmap_font.hpp"
#include "apps/nice_ticks.hpp"

namespace rtfuse::apps {
namespace plot_axes_test {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kRed{200, 0, 0};

Range range(double lo, double hi) {
  Range r;
  r.include(lo);
  r.include(hi);
  return r;
}

bool is_one_two_five_step(double step) {
  const double m = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
  return std::abs(m - 1.0) < 1e-9 || std::abs(m - 2.0) < 1e-9 || std::abs(m - 5.0) < 1e-9;
}

bool inside(const Rect& area, PointPx p) {
  return p.x >= area.x - 1e-9 && p.x <= area.right() - 1 + 1e-9 && p.y >= area.y - 1e-9 &&
         p.y <= area.bottom() - 1 + 1e-9;
}

// A 10 m x 100 m path in a wide area and a 100 m x 10 m one in a tall area:
// one metre is as many pixels across as up, a square stays a square, and
// the data fill the area along the tighter axis.
TEST(PlotAxes, EqualAspectKeepsOneScale) {
  AxesOptions o;
  o.equal_aspect = true;
  const Rect wide{50, 40, 600, 300}, tall{50, 40, 300, 600};
  for (const auto& [area, x, y] : {std::tuple{wide, range(0, 10), range(0, 100)},
                                   std::tuple{tall, range(0, 100), range(0, 10)},
                                   std::tuple{wide, range(-3, 250), range(7, 8)}}) {
    const Axes axes(area, x, y, o);
    EXPECT_DOUBLE_EQ(axes.px_per_unit_x(), axes.px_per_unit_y());
    const PointPx a = axes.to_px({1.0, 1.0}), b = axes.to_px({2.0, 2.0});
    EXPECT_NEAR(b.x - a.x, a.y - b.y, 1e-9) << "a unit square maps to a square";
    for (const double px : {x.lo, x.hi})
      for (const double py : {y.lo, y.hi}) EXPECT_TRUE(inside(area, axes.to_px({px, py}))) << px << ", " << py;
    // The tighter axis is nearly filled (only the padding left over).
    const double used_x = (x.hi - x.lo) * axes.px_per_unit_x() / (area.w - 1);
    const double used_y = (y.hi - y.lo) * axes.px_per_unit_y() / (area.h - 1);
    EXPECT_GT(std::max(used_x, used_y), 0.85);
    EXPECT_EQ(axes.x_step(), axes.y_step()) << "square grid cells";
  }
}

// Without equal aspect each axis fills its side: ranges rounded out to
// whole 1-2-5 ticks that cover the data, ticks far enough apart.
TEST(PlotAxes, TicksCoverTheDataAndAreSpacedOut) {
  AxesOptions o;
  o.min_px_per_tick = 50;
  const Rect area{80, 30, 900, 200};
  const Axes axes(area, range(0.37, 51.2), range(-0.013, 0.61), o);
  EXPECT_TRUE(is_one_two_five_step(axes.x_step()));
  EXPECT_TRUE(is_one_two_five_step(axes.y_step()));
  const std::vector<double> xt = axes.x_ticks(), yt = axes.y_ticks();
  ASSERT_GE(xt.size(), 2u);
  ASSERT_GE(yt.size(), 2u);
  EXPECT_LE(xt.front(), 0.37);
  EXPECT_GE(xt.back(), 51.2);
  EXPECT_LE(yt.front(), -0.013);
  EXPECT_GE(yt.back(), 0.61);
  EXPECT_GE(axes.x_step() * axes.px_per_unit_x(), o.min_px_per_tick);
  EXPECT_GE(axes.y_step() * axes.px_per_unit_y(), o.min_px_per_tick);
  // The ends of the range land on the frame's first and last pixels.
  EXPECT_NEAR(axes.to_px({axes.x_range().lo, 0.0}).x, area.x, 1e-9);
  EXPECT_NEAR(axes.to_px({axes.x_range().hi, 0.0}).x, area.right() - 1, 1e-9);
  EXPECT_NEAR(axes.to_px({0.0, axes.y_range().lo}).y, area.bottom() - 1, 1e-9);
  EXPECT_NEAR(axes.to_px({0.0, axes.y_range().hi}).y, area.y, 1e-9);
}

// Long labels (UTM-like eastings) on a narrow axis: the step grows until
// neighbouring labels no longer touch.
TEST(PlotAxes, StepWidensForLongLabels) {
  AxesOptions o;
  o.min_px_per_tick = 10;
  o.scale = 2;
  const Axes axes(Rect{0, 0, 300, 100}, range(651230.0, 651290.0), range(0, 1), o);
  const std::vector<double> t = axes.x_ticks();
  ASSERT_GE(t.size(), 2u);
  int widest = 0;
  for (const double v : t) widest = std::max(widest, text_width(tick_label(v, axes.x_step()), 2));
  EXPECT_GE(axes.x_step() * axes.px_per_unit_x(), widest + kGlyphAdvance * 2);
}

// No data, one point, NaN and infinities: a finite, positive scale, the
// point inside the area, ticks to label. Nothing divides by zero.
TEST(PlotAxes, DegenerateDataStillMaps) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  Range from_nan;
  from_nan.include(nan);
  from_nan.include(inf);
  EXPECT_TRUE(from_nan.empty());
  const Rect area{10, 10, 400, 300};
  for (const bool equal : {false, true}) {
    AxesOptions o;
    o.equal_aspect = equal;
    for (const auto& [x, y] : {std::pair{Range{}, Range{}}, std::pair{range(5, 5), range(-2, -2)},
                               std::pair{range(1e6, 1e6), range(0, 0)}, std::pair{Range{nan, 1.0}, Range{-inf, inf}}}) {
      const Axes axes(area, x, y, o);
      EXPECT_TRUE(std::isfinite(axes.px_per_unit_x()) && axes.px_per_unit_x() > 0.0);
      EXPECT_TRUE(std::isfinite(axes.px_per_unit_y()) && axes.px_per_unit_y() > 0.0);
      EXPECT_FALSE(axes.x_ticks().empty());
      EXPECT_FALSE(axes.y_ticks().empty());
      if (!x.empty() && std::isfinite(x.lo) && !y.empty() && std::isfinite(y.lo)) {
        EXPECT_TRUE(inside(area, axes.to_px({x.lo, y.lo})));
      }
    }
  }
  AxesOptions from_zero;
  from_zero.y_from_zero = true;
  const Axes errors(area, range(0, 50), range(0, 0), from_zero);
  EXPECT_EQ(errors.y_range().lo, 0.0);
  EXPECT_GT(errors.y_range().hi, 0.0);
  EXPECT_NEAR(errors.to_px({0.0, 0.0}).y, area.bottom() - 1, 1e-9) << "zero error on the frame's bottom";
}

// Data far outside (a diverged estimate at 1e12 m) is cut at the frame:
// nothing is drawn outside the area and the call returns at once.
TEST(PlotAxes, DataStaysInsideTheFrame) {
  Canvas canvas(300, 200, kWhite);
  const Rect area{50, 40, 200, 120};
  const Axes axes(area, range(0, 10), range(0, 10), AxesOptions{});
  axes.polyline(canvas, {{5.0, 5.0}, {1e12, -3e11}, {-1e12, 1e12}, {5.0, 9.0}}, kRed, 3);
  axes.marker(canvas, {10.0, 10.0}, Marker::kDisc, 8, kRed);
  int outside = 0, in = 0;
  for (int y = 0; y < canvas.height(); ++y)
    for (int x = 0; x < canvas.width(); ++x) {
      if (canvas.at(x, y) != kRed) continue;
      (area.contains(x, y) ? in : outside) += 1;
    }
  EXPECT_EQ(outside, 0);
  EXPECT_GT(in, 100);
  EXPECT_EQ(canvas.clip().w, 300) << "the canvas' clip is restored";
}

}  // namespace plot_axes_test
}  // namespace rtfuse::apps
