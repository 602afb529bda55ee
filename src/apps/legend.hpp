#pragma once
// The words beside a plot that make it readable on its own: a legend (a
// swatch of each series' colour and what it is) and a block of key-figure
// lines. Both are drawn at a position the figure chooses outside its data,
// so they never hide a curve. A tool's writer; never on the real-time path.
#include <string>
#include <vector>

#include "apps/canvas.hpp"

namespace rtfuse::apps {

struct LegendEntry {
  std::string label;
  Rgb colour;
  bool is_marker = false;          // a marker swatch (a start point) rather than a line
  Marker marker = Marker::kDisc;
  int thickness = 2;               // of the series' line; the swatch is at least 3 pixels thick
  bool dashed = false;
};

// The swatch: a line this long, or the marker centred in that space.
inline constexpr int kSwatchPx = 32;

// The size of a legend box with one row per entry at this scale.
Rect legend_box_size(const std::vector<LegendEntry>& entries, int scale);

// A framed white box with its top-left corner at (x, y), one row per entry:
// the swatch, then the label. Returns the box.
Rect draw_legend(Canvas& canvas, int x, int y, const std::vector<LegendEntry>& entries, int scale);

// The entries side by side on one line, from (x, y) (a panel's legend on
// the line above it); no box. Returns the space taken.
Rect draw_legend_row(Canvas& canvas, int x, int y, const std::vector<LegendEntry>& entries, int scale);
// Width draw_legend_row takes, to right-align it.
int legend_row_width(const std::vector<LegendEntry>& entries, int scale);

// One line each, kLineSpacing * scale apart, from (x, y). A line that starts
// with "# " is a heading: drawn bold, without the "# ". Returns the space taken.
Rect draw_text_lines(Canvas& canvas, int x, int y, const std::vector<std::string>& lines, Rgb c, int scale);

}  // namespace rtfuse::apps
