#pragma once
// The simulator's obstacle course (config/scenarios/obstacles.toml) mapped
// by the camera path: the lap's rendered pairs at true poses, one every
// `every_s` seconds of the drive, each one's dense disparity (half
// resolution, 64 disparities: the live default), textureless pixels
// dropped, turned into points and inserted at 0.05 m with a 6 m range.
// True poses: what the map shows is the depth's and the map's doing, not
// the filter's. CourseMappingSettings can put the world's origin off the
// map's voxel lines and replace the matcher's disparities with the truth.
// The map accuracy test scores it against the world's truth;
// the planner's reference test and benchmark plan on its costmap, a map
// from a simulated drive (issue 28).
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "mapping/disparity_points.hpp"
#include "mapping/grid_projection.hpp"
#include "mapping/occupancy_map.hpp"
#include "navigation/grid_planner.hpp"
#include "sim/camera_world.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/path_plan.hpp"
#include "sim/stereo_renderer.hpp"
#include "support/pinhole_stereo.hpp"
#include "support/synthetic_costmap.hpp"
#include "support/world_depth.hpp"
#include "vision/semi_global_matcher.hpp"
#include "vision/texture_filter.hpp"

namespace rtfuse::test {

// How the course is mapped: OctoMap's occupancy threshold and the mapper's
// default 6 m range unless a config sets others, as config/sim_nav.toml
// does.
struct CourseMappingSettings {
  double occupancy_threshold = 0.5;
  double range = 6.0;
  // Where the world's origin lies in the map's frame. Zero puts the
  // course's faces on voxel boundaries, where a point on a face belongs to
  // the voxel on its positive side: outside every face that looks toward
  // +x or +y. A robot's map starts where it does, not on the walls' lines.
  Eigen::Vector3d map_offset = Eigen::Vector3d::Zero();
  // The renderer's true disparity (in the matcher's fixed point) at every
  // pixel the matcher estimated, in place of its estimate: the map with
  // the stereo's error taken out.
  bool true_disparity = false;
  // Otherwise, when positive: an oracle that keeps only the matcher's
  // estimates within this many matched pixels of the truth, to show how
  // good the depth would have to be.
  double keep_within_px = 0.0;
};

class ObstacleCourseMapping {
 public:
  static constexpr int kWidth = 672, kHeight = 376;  // a ZED's VGA-class eye
  static constexpr double kF = 350.0, kCx = 336.0, kCy = 188.0, kBaseline = 0.12;
  static constexpr double kResolution = 0.05;
  static constexpr double kRange = 6.0;

  explicit ObstacleCourseMapping(const CourseMappingSettings& settings = CourseMappingSettings())
      : settings_(settings),
        map_(occupancy_params(settings.occupancy_threshold), mapping::capacity_for_bytes(std::size_t{256} << 20)),
        matcher_(kWidth, kHeight, disparity_params()),
        texture_(kWidth, kHeight) {
    if (!sim::load_drive_scenario(std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/obstacles.toml", &scenario_,
                                  &error_)) {
      return;
    }
    sim::PlanProblem problem;
    if (!sim::PathPlan::build(scenario_, &plan_, &problem)) {
      error_ = problem.message;
      return;
    }
    sim::CameraWorldConfig world_config;
    world_config.seed = scenario_.seed;
    world_config.obstacles = scenario_.obstacles;
    world_ = std::make_unique<sim::CameraWorld>(world_config);
    renderer_ = std::make_unique<sim::StereoRenderer>(
        pinhole_stereo_pair(kWidth, kHeight, kF, kCx, kCy, kBaseline), *world_);
    if (!renderer_->valid()) error_ = renderer_->error();
    if (!matcher_.valid()) error_ = matcher_.error();
  }

  // Empty when the scenario, the renderer and the matcher are ready.
  const std::string& error() const { return error_; }
  const sim::CameraWorld& world() const { return *world_; }
  const mapping::OccupancyMap& map() const { return map_; }
  double range() const { return settings_.range; }
  const Eigen::Vector3d& map_offset() const { return settings_.map_offset; }
  static mapping::OccupancyParams occupancy_params(double occupancy_threshold = 0.5) {
    mapping::OccupancyParams mp;
    mp.resolution = kResolution;
    mp.occupancy_threshold = occupancy_threshold;
    return mp;
  }
  static vision::DisparityParams disparity_params() {
    vision::DisparityParams dp;
    dp.disparities = 64;
    dp.downscale = 2;
    return dp;
  }
  int disparity_width() const { return matcher_.output_width(kWidth); }
  int disparity_height() const { return matcher_.output_height(kHeight); }

  // config/sim.toml's camera mount: 0.2 m ahead, 0.06 m left, 0.3 m up,
  // optical axes (x right, y down, z forward).
  static geometry::RigidTransform base_T_camera() {
    Eigen::Matrix3d r;
    r << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    geometry::RigidTransform t;
    t.rotation = Eigen::Quaterniond(r);
    t.translation = Eigen::Vector3d(0.2, 0.06, 0.3);
    return t;
  }

  // Maps a pair every every_s seconds of the lap, from its start to its
  // end; on_frame(world_T_camera) sees each camera pose (in the world's
  // frame) before its pair is inserted. The keyframes mapped, or -1 when a
  // pair could not be rendered or matched (error() says which).
  template <typename OnFrame>
  int drive(double every_s, OnFrame&& on_frame) {
    if (!error_.empty()) return -1;
    const int bpl = renderer_->min_bytes_per_line();
    std::vector<std::uint8_t> frame(static_cast<std::size_t>(bpl) * kHeight);
    vision::Plane<std::uint8_t> left(kWidth, kHeight), right(kWidth, kHeight);
    vision::Plane<std::uint16_t> disparity(disparity_width(), disparity_height());
    std::vector<mapping::MapPoint> points(static_cast<std::size_t>(disparity.width()) * disparity.height());
    const vision::StereoCameraModel camera{kF, kCx, kCy, kBaseline};
    int frames = 0;
    for (double t = 0.0; t <= plan_.end_time(); t += every_s, ++frames) {
      const sim::PathPoint p = plan_.at(t);
      geometry::RigidTransform world_T_base;
      world_T_base.translation = Eigen::Vector3d(p.x, p.y, 0.0);
      world_T_base.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(p.heading, Eigen::Vector3d::UnitZ()));
      const geometry::RigidTransform world_T_camera = world_T_base * base_T_camera();
      if (!renderer_->render(world_T_camera, 0, static_cast<std::uint32_t>(frames), frame.data(), bpl)) {
        error_ = "the renderer refused the pair at " + std::to_string(t) + " s";
        return -1;
      }
      for (int y = 0; y < kHeight; ++y) {
        for (int x = 0; x < kWidth; ++x) {
          left.row(y)[x] = frame[static_cast<std::size_t>(y) * bpl + 2 * static_cast<std::size_t>(x)];
          right.row(y)[x] = frame[static_cast<std::size_t>(y) * bpl + 2 * static_cast<std::size_t>(kWidth + x)];
        }
      }
      on_frame(world_T_camera);
      if (matcher_.compute(vision::view_of(left), vision::view_of(right), vision::view_of(disparity)) !=
          vision::DisparityStatus::kOk) {
        error_ = "the matcher refused the pair at " + std::to_string(t) + " s";
        return -1;
      }
      const int downscale = disparity_params().downscale;
      texture_.apply(vision::view_of(left), downscale, vision::view_of(disparity));
      if (settings_.true_disparity || settings_.keep_within_px > 0.0) apply_truth(world_T_camera, &disparity);
      geometry::RigidTransform map_T_camera = world_T_camera;
      map_T_camera.translation += settings_.map_offset;
      const mapping::DisparityPointCounts c = mapping::disparity_points(
          vision::view_of(disparity), downscale, camera, map_T_camera, points.data(), points.size());
      const Eigen::Vector3d& o = map_T_camera.translation;
      map_.insert_scan(points.data(), c.points,
                       {static_cast<float>(o.x()), static_cast<float>(o.y()), static_cast<float>(o.z())},
                       settings_.range);
    }
    return frames;
  }

 private:
  void apply_truth(const geometry::RigidTransform& world_T_camera, vision::Plane<std::uint16_t>* disparity) {
    const int downscale = disparity_params().downscale;
    // Matched pixels in the disparity's fixed point (input pixels).
    const double tolerance = settings_.keep_within_px * downscale * vision::kDisparityScale;
    for (int v = 0; v < disparity->height(); ++v) {
      for (int u = 0; u < disparity->width(); ++u) {
        std::uint16_t& d = disparity->row(v)[u];
        if (d == vision::kInvalidDisparity) continue;
        const double z = true_depth(*world_, world_T_camera, kF, kCx, kCy, downscale * u + 0.5 * (downscale - 1),
                                    downscale * v + 0.5 * (downscale - 1));
        const double raw = std::isfinite(z) ? std::round(kF * kBaseline * vision::kDisparityScale / z) : 0.0;
        if (!settings_.true_disparity) {
          if (std::abs(d - raw) > tolerance) d = vision::kInvalidDisparity;
        } else {
          d = raw < vision::kInvalidDisparity ? static_cast<std::uint16_t>(raw) : vision::kInvalidDisparity;
        }
      }
    }
  }

  CourseMappingSettings settings_;
  sim::DriveScenario scenario_;
  sim::PathPlan plan_;
  std::unique_ptr<sim::CameraWorld> world_;
  std::unique_ptr<sim::StereoRenderer> renderer_;
  mapping::OccupancyMap map_;
  vision::SemiGlobalMatcher matcher_;
  vision::TextureFilter texture_;
  std::string error_;
};

// The costmap a robot would plan on after that lap: a size x size grid at
// 0.05 m (400: 20 m, issue 28's benchmark size) centred on the lap's
// middle, its cells from the map between 0.1 and 2 m (the mapper's
// default grid heights above the floor's voxels), made into costs by
// navigation::Costmap with its defaults, and `pairs` start/goal pairs of
// passable cells with a route between them (the planner's own Dijkstra
// says which; the reference test checks it against Boost's). Unknown
// cells are closed (the planner's default), so the pairs lie in what the
// camera saw. Raw mt19937 words, as synthetic_costmap's.
inline SyntheticCostmap obstacle_course_costmap(const mapping::OccupancyMap& map, int size = 400,
                                                std::size_t pairs = 100, std::uint32_t seed = 28) {
  // The lap: x from -2 to 8, y from 0 to 10 (obstacles.toml).
  const mapping::GridSpec spec = mapping::grid_around(map.grid(), 3.0, 5.0, size, size, 0.1, 2.0);
  std::vector<std::int8_t> cells(spec.cells());
  mapping::project_to_grid(map, spec, cells.data());
  SyntheticCostmap out = costmap_of_grid(cells, size);
  std::mt19937 rng(seed);
  const auto random_cell = [&] {
    const int x = static_cast<int>(rng() % static_cast<std::uint32_t>(size));
    return navigation::GridCell{x, static_cast<int>(rng() % static_cast<std::uint32_t>(size))};
  };
  const auto passable = [&](navigation::GridCell c) { return out.view().at(c.x, c.y) < navigation::kCostInscribed; };
  navigation::GridPlanner planner(size, size, static_cast<std::size_t>(size) * static_cast<std::size_t>(size));
  navigation::PlannerParams params;
  params.mode = navigation::SearchMode::kDijkstra;
  // Bounded: a map with too little room gives fewer pairs (callers check).
  for (std::size_t tries = 0; out.starts.size() < pairs && tries < 1000 * pairs; ++tries) {
    const navigation::GridCell s = random_cell(), e = random_cell();
    if (!passable(s) || !passable(e) || !planner.plan(out.view(), s, e, params).ok()) continue;
    out.starts.push_back(s);
    out.goals.push_back(e);
  }
  return out;
}

}  // namespace rtfuse::test
