#pragma once
// A plot area of a figure mapped from data units (metres, frames, ...):
// the ranges padded and widened to whole ticks, equal scale on both axes
// when asked (a top view in metres must not stretch a curve into a
// straight line), the grid, the frame, labelled 1-2-5 ticks and the axis
// titles, and data drawn clipped to the area. A tool's writer (allocates);
// never on the real-time path.
#include <limits>
#include <string>
#include <vector>

#include "apps/canvas.hpp"

namespace rtfuse::apps {

// A data range; empty (lo > hi) until a finite value is included.
struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void include(double v) noexcept;  // non-finite values are ignored
  bool empty() const noexcept { return !(lo <= hi); }
};

// A point in data units.
struct DataPoint {
  double x = 0.0, y = 0.0;
};

struct AxesOptions {
  bool equal_aspect = false;     // one data unit is as many pixels across as up
  double pad_fraction = 0.04;    // of the span, added at both ends before rounding to ticks
  int min_px_per_tick = 70;      // ticks no closer than this
  bool y_from_zero = false;      // the y range starts at 0 (errors, distances)
  double min_x_step = 0.0;       // e.g. 1 for frames: no tick between two frames
  std::string x_title, y_title;  // e.g. "x [m]"
  int scale = 2;                 // of the tick labels and titles
};

struct AxesStyle {
  Rgb frame{0, 0, 0};
  Rgb grid{222, 222, 222};
  Rgb text{0, 0, 0};
};

class Axes {
 public:
  // `area` is where the data goes; tick labels and titles are drawn outside
  // it (left, below, and the y title above its top-left corner). An empty
  // range shows -1..1, a range of one value a span of 1 about it, so a
  // picture is drawn for any data without dividing by zero.
  Axes(const Rect& area, Range x, Range y, const AxesOptions& options);

  const Rect& area() const noexcept { return area_; }
  const Range& x_range() const noexcept { return x_; }
  const Range& y_range() const noexcept { return y_; }
  double x_step() const noexcept { return x_step_; }
  double y_step() const noexcept { return y_step_; }
  double px_per_unit_x() const noexcept { return sx_; }
  double px_per_unit_y() const noexcept { return sy_; }
  std::vector<double> x_ticks() const;
  std::vector<double> y_ticks() const;

  // The line above the area that the y title takes (clear of the top tick
  // label), and the column one past the title's end: a panel puts its
  // legend on that line, right of the title.
  int title_line_y() const noexcept;
  int y_title_end_x() const;

  // Data to pixels: x grows to the right, y upwards.
  PointPx to_px(DataPoint p) const noexcept;

  // The grid and the frame: before the data, which goes on top of them (an
  // error of zero lies on the frame's bottom edge and must still show).
  void draw_grid(Canvas& canvas, const AxesStyle& style = {}) const;
  // The tick marks, the tick labels and the axis titles, outside the area:
  // data never reach them.
  void draw_labels(Canvas& canvas, const AxesStyle& style = {}) const;

  // Data drawn clipped to the area (the canvas' clip is restored after).
  void polyline(Canvas& canvas, const std::vector<DataPoint>& points, Rgb c, int thickness) const;
  void dashed_line(Canvas& canvas, DataPoint a, DataPoint b, Rgb c, int thickness) const;
  void marker(Canvas& canvas, DataPoint p, Marker kind, int radius, Rgb c, int thickness = 2) const;

 private:
  int y_title_x() const;

  Rect area_;
  Range x_, y_;
  double x_step_ = 1.0, y_step_ = 1.0;
  double sx_ = 1.0, sy_ = 1.0;  // pixels per unit
  AxesOptions options_;
};

}  // namespace rtfuse::apps
