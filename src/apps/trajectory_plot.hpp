#pragma once
// rtfuse-vo's picture of a run: a top view of the estimated camera path
// against the ground truth (KITTI camera frame: x right, z forward, equal
// scale, in metres, the start marked), a legend, the run's key figures,
// and below it the position error over frames with its RMS. Readable on its
// own: which line is which, how far apart, how good. A tool's writer
// (allocates, does file I/O); never on the real-time path.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "apps/canvas.hpp"
#include "apps/trajectory_metrics.hpp"

namespace rtfuse::apps {

inline constexpr int kTrajectoryPlotWidth = 1280;
inline constexpr int kTrajectoryPlotHeight = 1100;
inline constexpr Rgb kTruthRgb{40, 40, 40};
inline constexpr Rgb kEstimateRgb{214, 39, 40};
inline constexpr Rgb kStartRgb{0, 150, 60};
inline constexpr Rgb kStretchRgb{31, 100, 200};

// What the program already computed about the run; the picture prints it
// and computes none of it again.
struct TrajectoryPlotFigures {
  std::string title;  // e.g. the sequence folder's name
  int frames = 0;
  std::int64_t solved = 0, failed = 0, unreadable = 0;
  double ms_per_frame_median = 0.0, ms_per_frame_p99 = 0.0;
  std::optional<TrajectoryErrors> errors;  // against the ground truth, when there is one
  int eval_from = 0;                       // > 0: the stretch from this frame, re-anchored
  std::optional<TrajectoryErrors> stretch_errors;
};

// The picture, kTrajectoryPlotWidth x kTrajectoryPlotHeight. truth may be
// empty (then only the estimate and the figures that exist); either may be
// a single pose or none.
Canvas draw_trajectory_plot(const std::vector<Eigen::Matrix4d>& estimate, const std::vector<Eigen::Matrix4d>& truth,
                            const TrajectoryPlotFigures& figures);

// draw_trajectory_plot written to `path`. False and *error naming the path
// and the cause (the errno text for I/O).
bool write_trajectory_plot(const std::string& path, const std::vector<Eigen::Matrix4d>& estimate,
                           const std::vector<Eigen::Matrix4d>& truth, const TrajectoryPlotFigures& figures,
                           std::string* error);

// The key-figure lines the picture shows (a "# " line is a heading).
std::vector<std::string> trajectory_key_figures(const TrajectoryPlotFigures& figures);

}  // namespace rtfuse::apps
