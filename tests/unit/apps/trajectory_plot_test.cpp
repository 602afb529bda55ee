// rtfuse-vo's picture, read back from the PNG: the series' colours in the
// top view and in the legend beside it, the start marked, the error panel,
// the key figures as the program computed them; a valid picture for an
// empty, single-pose or motionless run; and errors naming the path.
#include "apps/trajectory_plot.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "unit/apps/png_readback.hpp"

namespace rtfuse::apps {
namespace trajectory_plot_test {

using test_png::read_rgb_png;
using test_png::RgbImage;

Eigen::Matrix4d at(double x, double z, double yaw = 0.0) {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t.topLeftCorner<3, 3>() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  t(0, 3) = x;
  t(2, 3) = z;
  return t;
}

// A gentle left curve, and an estimate drifting right of it.
void curve(std::vector<Eigen::Matrix4d>* truth, std::vector<Eigen::Matrix4d>* estimate, int n) {
  for (int i = 0; i < n; ++i) {
    const double s = i;
    truth->push_back(at(-0.01 * s * s, s, -0.02 * s));
    estimate->push_back(at(-0.01 * s * s + 0.02 * s, 1.01 * s, -0.02 * s));
  }
}

int count(const RgbImage& img, Rgb c, int x0, int y0, int x1, int y1) {
  return img.count(c.r, c.g, c.b, x0, y0, x1, y1);
}
int count(const RgbImage& img, Rgb c) { return img.count(c.r, c.g, c.b); }

RgbImage write_and_read(const char* name, const std::vector<Eigen::Matrix4d>& estimate,
                        const std::vector<Eigen::Matrix4d>& truth, const TrajectoryPlotFigures& figures) {
  const std::string path = test_png::temp_png("rtfuse_trajectory_plot_", name);
  std::string error;
  EXPECT_TRUE(write_trajectory_plot(path, estimate, truth, figures, &error)) << error;
  RgbImage img = read_rgb_png(path);
  ::unlink(path.c_str());
  EXPECT_EQ(img.width, kTrajectoryPlotWidth);
  EXPECT_EQ(img.height, kTrajectoryPlotHeight);
  return img;
}

TrajectoryPlotFigures figures_of(const std::vector<Eigen::Matrix4d>& estimate,
                                 const std::vector<Eigen::Matrix4d>& truth, int eval_from) {
  TrajectoryPlotFigures f;
  f.title = "curve";
  f.frames = static_cast<int>(estimate.size());
  f.solved = f.frames - 1;
  f.ms_per_frame_median = 12.5;
  f.ms_per_frame_p99 = 20.0;
  if (!truth.empty()) f.errors = compare_trajectories(estimate, truth);
  if (eval_from > 0) {
    f.eval_from = eval_from;
    f.stretch_errors = compare_trajectories(reanchored(estimate, static_cast<std::size_t>(eval_from)),
                                            reanchored(truth, static_cast<std::size_t>(eval_from)));
  }
  return f;
}

// The legend and figures sit right of the top view (x >= 780) and above the
// error panel (y < 800), where no data is drawn: a colour found there is a
// legend swatch.
constexpr int kColumn = 780, kPanelTop = 800;

TEST(TrajectoryPlot, SeriesColoursInTheDataAndInTheLegend) {
  std::vector<Eigen::Matrix4d> truth, estimate;
  curve(&truth, &estimate, 40);
  const RgbImage img = write_and_read("curve.png", estimate, truth, figures_of(estimate, truth, 10));
  for (const Rgb c : {kTruthRgb, kEstimateRgb, kStartRgb, kStretchRgb}) {
    EXPECT_GT(count(img, c, 0, 0, kColumn, kPanelTop), 10) << "in the top view: " << int(c.r);
    EXPECT_GT(count(img, c, kColumn, 0, img.width, kPanelTop), 10) << "in the legend: " << int(c.r);
  }
  // The error panel: both error series (and their RMS lines), no truth line.
  EXPECT_GT(count(img, kEstimateRgb, 0, kPanelTop, img.width, img.height), 500);
  EXPECT_GT(count(img, kStretchRgb, 0, kPanelTop, img.width, img.height), 300);
  EXPECT_EQ(count(img, kTruthRgb, 0, kPanelTop, img.width, img.height), 0);
}

// Without ground truth: the estimate, its legend and the run's figures; no
// truth colour, no error curve, no error figures.
TEST(TrajectoryPlot, WithoutGroundTruthOnlyTheEstimate) {
  std::vector<Eigen::Matrix4d> truth, estimate;
  curve(&truth, &estimate, 30);
  const TrajectoryPlotFigures f = figures_of(estimate, {}, 0);
  const RgbImage img = write_and_read("no_truth.png", estimate, {}, f);
  EXPECT_EQ(count(img, kTruthRgb), 0);
  EXPECT_EQ(count(img, kStretchRgb), 0);
  EXPECT_GT(count(img, kEstimateRgb, kColumn, 0, img.width, kPanelTop), 10) << "its legend swatch";
  EXPECT_EQ(count(img, kEstimateRgb, 0, kPanelTop, img.width, img.height), 0) << "no error curve";
  EXPECT_GT(count(img, kStartRgb), 20);
  const std::vector<std::string> lines = trajectory_key_figures(f);
  bool said = false, ate = false;
  for (const std::string& l : lines) {
    said = said || l.find("no ground truth") != std::string::npos;
    ate = ate || l.find("ATE") != std::string::npos;
  }
  EXPECT_TRUE(said);
  EXPECT_FALSE(ate);
}

// The figures are the program's, printed as given (not recomputed).
TEST(TrajectoryPlot, KeyFiguresAreTheProgramsNumbers) {
  TrajectoryPlotFigures f;
  f.frames = 51;
  f.solved = 50;
  f.failed = 1;
  f.ms_per_frame_median = 13.87;
  f.ms_per_frame_p99 = 21.6;
  TrajectoryErrors whole;
  whole.path_length_m = 59.86;
  whole.final_error_m = 0.5094;
  whole.final_error_pct = 0.851;
  whole.ate_rmse_m = 0.3174;
  f.errors = whole;
  TrajectoryErrors stretch;
  stretch.final_error_m = 0.3025;
  stretch.final_error_pct = 0.647;
  stretch.ate_rmse_m = 0.1779;
  f.eval_from = 11;
  f.stretch_errors = stretch;
  std::string all;
  for (const std::string& l : trajectory_key_figures(f)) all += l + "\n";
  for (const char* want : {"frames      51", "50 (1 failed", "13.9 ms median", "21.6 ms p99", "path        59.9 m",
                           "final error 0.509 m (0.85 %)", "ATE RMS     0.317 m", "from frame 11",
                           "final error 0.302 m (0.65 %)", "ATE RMS     0.178 m"})
    EXPECT_NE(all.find(want), std::string::npos) << want << " in\n" << all;
}

// Nothing to plot, one pose, a run that never moved, a pose gone NaN: a
// whole picture each time, the start still marked where there is one.
TEST(TrajectoryPlot, DegenerateRunsStillDraw) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Eigen::Matrix4d> one = {Eigen::Matrix4d::Identity()};
  const std::vector<Eigen::Matrix4d> still(5, at(2.0, 3.0));
  std::vector<Eigen::Matrix4d> broken = {at(0, 0), at(0, 1), at(nan, nan), at(0, 3)};
  {
    const RgbImage img = write_and_read("empty.png", {}, {}, TrajectoryPlotFigures{});
    EXPECT_EQ(count(img, kStartRgb), 0);
  }
  {
    const RgbImage img = write_and_read("one.png", one, one, figures_of(one, one, 0));
    EXPECT_GT(count(img, kStartRgb, 0, 0, kColumn, kPanelTop), 20);
  }
  {
    const RgbImage img = write_and_read("still.png", still, still, figures_of(still, still, 2));
    EXPECT_GT(count(img, kStartRgb, 0, 0, kColumn, kPanelTop), 20);
    EXPECT_GT(count(img, kEstimateRgb, 0, kPanelTop, img.width, img.height), 100) << "a zero error line";
  }
  {
    const RgbImage img = write_and_read("broken.png", broken, one, figures_of(broken, one, 0));
    EXPECT_GT(count(img, kEstimateRgb, 0, 0, kColumn, kPanelTop), 10);
  }
}

TEST(TrajectoryPlot, UnwritablePathNamesThePathAndErrno) {
  const std::string path = test_png::temp_png("rtfuse_trajectory_plot_", "no_such_dir") + "/plot.png";
  std::string error;
  EXPECT_FALSE(write_trajectory_plot(path, {Eigen::Matrix4d::Identity()}, {}, TrajectoryPlotFigures{}, &error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("No such file or directory"), std::string::npos) << error;
}

}  // namespace trajectory_plot_test
}  // namespace rtfuse::apps
