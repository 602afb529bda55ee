#include "apps/trajectory_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "apps/bitmap_font.hpp"
#include "apps/error_panel.hpp"
#include "apps/legend.hpp"
#include "apps/plot_axes.hpp"

namespace rtfuse::apps {
namespace {

constexpr int kScale = 2;  // labels, legend and figures: 10 x 14 pixel capitals
constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kInk{0, 0, 0};
constexpr Rgb kSubtle{90, 90, 90};
constexpr Rect kTopView{110, 120, 640, 600};
constexpr int kColumnX = 800;  // legend and figures, right of the top view
constexpr Rect kErrorArea{110, 880, 1140, 150};

// Top view: x right, z forward (up in the picture).
DataPoint ground(const Eigen::Matrix4d& pose) { return DataPoint{pose(0, 3), pose(2, 3)}; }

std::vector<DataPoint> ground_track(const std::vector<Eigen::Matrix4d>& poses) {
  std::vector<DataPoint> out;
  out.reserve(poses.size());
  for (const Eigen::Matrix4d& p : poses) out.push_back(ground(p));
  return out;
}

// Position error of each frame both have, at x = first + index.
ErrorSeries error_series(const std::vector<Eigen::Matrix4d>& est, const std::vector<Eigen::Matrix4d>& gt,
                         std::size_t first, std::string label, Rgb colour, const std::optional<TrajectoryErrors>& e) {
  ErrorSeries s{std::move(label), colour, {}, 0.0};
  const std::size_t n = std::min(est.size(), gt.size());
  double sq = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double d = (est[i].topRightCorner<3, 1>() - gt[i].topRightCorner<3, 1>()).norm();
    s.points.push_back(DataPoint{static_cast<double>(first + i), d});
    sq += d * d;
  }
  // The program's ATE RMS is this series' RMS; it is used when given, so
  // the picture and the JSON line print the same number.
  s.rms_m = e ? e->ate_rmse_m : (n > 0 ? std::sqrt(sq / static_cast<double>(n)) : 0.0);
  return s;
}

std::string format(const char* fmt, double a, double b = 0.0) {
  char buf[128];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

void error_lines(const TrajectoryErrors& e, std::vector<std::string>* lines) {
  lines->push_back(format("path        %.1f m", e.path_length_m));
  lines->push_back(format("final error %.3f m (%.2f %%)", e.final_error_m, e.final_error_pct));
  lines->push_back(format("ATE RMS     %.3f m", e.ate_rmse_m));
  lines->push_back(format("heading     %.2f deg off at the end", e.final_rotation_error_deg));
}

}  // namespace

std::vector<std::string> trajectory_key_figures(const TrajectoryPlotFigures& f) {
  std::vector<std::string> lines;
  lines.push_back("# the run");
  lines.push_back("frames      " + std::to_string(f.frames));
  lines.push_back("solved      " + std::to_string(f.solved) + " (" + std::to_string(f.failed) + " failed, " +
                  std::to_string(f.unreadable) + " unread)");
  lines.push_back(format("time/frame  %.1f ms median", f.ms_per_frame_median));
  lines.push_back(format("            %.1f ms p99", f.ms_per_frame_p99));
  if (!f.errors) {
    lines.push_back("");
    lines.push_back("# no ground truth (no poses.txt)");
    return lines;
  }
  lines.push_back("");
  lines.push_back("# against the ground truth");
  error_lines(*f.errors, &lines);
  if (f.eval_from > 0 && f.stretch_errors) {
    lines.push_back("");
    lines.push_back("# from frame " + std::to_string(f.eval_from) + " on (--eval-from)");
    lines.push_back("both re-anchored at frame " + std::to_string(f.eval_from));
    error_lines(*f.stretch_errors, &lines);
  }
  return lines;
}

Canvas draw_trajectory_plot(const std::vector<Eigen::Matrix4d>& estimate, const std::vector<Eigen::Matrix4d>& truth,
                            const TrajectoryPlotFigures& figures) {
  Canvas canvas(kTrajectoryPlotWidth, kTrajectoryPlotHeight, kWhite);
  canvas.text(24, 18, figures.title.empty() ? "rtfuse-vo" : figures.title, kInk, 3, true);
  canvas.text(24, 18 + text_height(3) + 10, "rtfuse-vo: top view of the left camera, x right, z forward, equal scale",
              kSubtle, kScale);

  const std::vector<DataPoint> est = ground_track(estimate), gt = ground_track(truth);
  Range x, z;
  for (const auto* track : {&est, &gt})
    for (const DataPoint& p : *track) {
      x.include(p.x);
      z.include(p.y);
    }
  AxesOptions ao;
  ao.equal_aspect = true;
  ao.x_title = "x [m]";
  ao.y_title = "z [m]";
  ao.scale = kScale;
  const Axes top(kTopView, x, z, ao);
  top.draw_grid(canvas);
  std::vector<LegendEntry> legend;
  if (!gt.empty()) {
    top.polyline(canvas, gt, kTruthRgb, 3);
    legend.push_back(LegendEntry{"ground truth", kTruthRgb, false, Marker::kDisc, 3, false});
  }
  if (!est.empty()) {
    top.polyline(canvas, est, kEstimateRgb, 2);
    legend.push_back(LegendEntry{"visual odometry", kEstimateRgb, false, Marker::kDisc, 2, false});
  }
  const bool stretch = figures.eval_from > 0 && static_cast<std::size_t>(figures.eval_from) < gt.size();
  if (stretch) {
    top.marker(canvas, gt[static_cast<std::size_t>(figures.eval_from)], Marker::kSquare, 6, kStretchRgb, 2);
    legend.push_back(LegendEntry{"frame " + std::to_string(figures.eval_from) + " (--eval-from)", kStretchRgb, true,
                                 Marker::kSquare, 2, false});
  }
  const std::vector<DataPoint>& first = !gt.empty() ? gt : est;
  if (!first.empty()) {
    top.marker(canvas, first.front(), Marker::kDisc, 6, kStartRgb);
    legend.push_back(LegendEntry{"start (frame 0)", kStartRgb, true, Marker::kDisc, 2, false});
  }
  top.draw_labels(canvas);

  const Rect box = draw_legend(canvas, kColumnX, kTopView.y, legend, kScale);
  draw_text_lines(canvas, kColumnX, box.bottom() + 28, trajectory_key_figures(figures), kInk, kScale);

  std::vector<ErrorSeries> errors;
  if (!truth.empty() && !estimate.empty()) {
    errors.push_back(error_series(estimate, truth, 0, "visual odometry", kEstimateRgb, figures.errors));
    if (stretch) {
      const auto k = static_cast<std::size_t>(figures.eval_from);
      errors.push_back(error_series(reanchored(estimate, k), reanchored(truth, k), k,
                                    "from frame " + std::to_string(k), kStretchRgb,
                                    figures.stretch_errors));
    }
  }
  ErrorPanelOptions eo;
  eo.empty_note = truth.empty() ? "no ground truth: no error to show" : "no estimate: no error to show";
  draw_error_panel(canvas, kErrorArea, errors, eo);
  return canvas;
}

bool write_trajectory_plot(const std::string& path, const std::vector<Eigen::Matrix4d>& estimate,
                           const std::vector<Eigen::Matrix4d>& truth, const TrajectoryPlotFigures& figures,
                           std::string* error) {
  return write_png(draw_trajectory_plot(estimate, truth, figures), path, error);
}

}  // namespace rtfuse::apps
