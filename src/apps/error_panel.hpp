#pragma once
// The second panel of a trajectory figure: how far each estimate is from
// the ground truth over frames (or time), with its RMS as a dashed line of
// the same colour and in the legend, so the one figure a run is judged by
// can be seen growing. A tool's writer; never on the real-time path.
#include <string>
#include <vector>

#include "apps/canvas.hpp"
#include "apps/plot_axes.hpp"

namespace rtfuse::apps {

struct ErrorSeries {
  std::string label;
  Rgb colour;
  std::vector<DataPoint> points;  // (frame or time, error [m])
  double rms_m = 0.0;
};

struct ErrorPanelOptions {
  std::string x_title = "frame";
  double min_x_step = 1.0;  // whole frames; 0 for time
  std::string y_title = "position error [m]";
  std::string empty_note = "no ground truth: no error to show";
  int scale = 2;
};

// `area` is the plot area: the y title and the legend ("label (dashed: RMS
// 0.123 m)" per series) go above it (the legend on the title's line when it
// fits beside it, else on the line above), the tick labels and the x title
// below it. Without points in any series, the empty note sits in the middle
// of an empty frame, without ticks.
void draw_error_panel(Canvas& canvas, const Rect& area, const std::vector<ErrorSeries>& series,
                      const ErrorPanelOptions& options);

// The legend label of a series: "label (dashed: RMS 0.123 m)".
std::string error_series_label(const ErrorSeries& s);

}  // namespace rtfuse::apps
