#include "apps/error_panel.hpp"

#include <algorithm>
#include <cstdio>

#include "apps/bitmap_font.hpp"
#include "apps/legend.hpp"

namespace rtfuse::apps {

std::string error_series_label(const ErrorSeries& s) {
  char rms[64];
  std::snprintf(rms, sizeof rms, " (dashed: RMS %.3f m)", s.rms_m);
  return s.label + rms;
}

void draw_error_panel(Canvas& canvas, const Rect& area, const std::vector<ErrorSeries>& series,
                      const ErrorPanelOptions& options) {
  Range x, y;
  for (const ErrorSeries& s : series) {
    for (const DataPoint& p : s.points) {
      x.include(p.x);
      y.include(p.y);
    }
    if (!s.points.empty()) y.include(s.rms_m);
  }
  AxesOptions ao;
  ao.x_title = options.x_title;
  ao.y_title = options.y_title;
  ao.y_from_zero = true;
  ao.pad_fraction = 0.0;
  ao.min_px_per_tick = 40;
  ao.min_x_step = options.min_x_step;
  ao.scale = options.scale;
  const int sc = options.scale;
  const Axes axes(area, x, y, ao);
  if (x.empty()) {
    // Nothing to scale: a frame with the reason, and no made-up ticks.
    canvas.stroke_rect(axes.area(), AxesStyle{}.frame);
    canvas.text(area.x, axes.title_line_y(), options.y_title, AxesStyle{}.text, sc);
    const int w = text_width(options.empty_note, sc);
    canvas.text(area.x + (area.w - w) / 2, area.y + (area.h - text_height(sc)) / 2, options.empty_note,
                Rgb{90, 90, 90}, sc);
    return;
  }
  axes.draw_grid(canvas);
  std::vector<LegendEntry> legend;
  for (const ErrorSeries& s : series) {
    if (s.points.empty()) continue;
    axes.polyline(canvas, s.points, s.colour, 2);
    const double x0 = axes.x_range().lo, x1 = axes.x_range().hi;
    axes.dashed_line(canvas, DataPoint{x0, s.rms_m}, DataPoint{x1, s.rms_m}, s.colour, 1);
    legend.push_back(LegendEntry{error_series_label(s), s.colour, false, Marker::kDisc, 2, false});
  }
  axes.draw_labels(canvas);
  // Right-aligned on the y title's line, or on the line above when the
  // title is in the way: above the data, never over it.
  const int w = legend_row_width(legend, sc);
  const int x0 = std::max(0, area.right() - w);
  const int y0 = axes.title_line_y();
  const bool fits = x0 >= axes.y_title_end_x() + 2 * kGlyphAdvance * sc;
  draw_legend_row(canvas, x0, fits ? y0 : y0 - kLineSpacing * sc, legend, sc);
}

}  // namespace rtfuse::apps
