// The mapping path on the simulator's obstacle course, scored against the
// world's truth (issue 27): the camera's pairs rendered along the scenario's
// drive (config/scenarios/obstacles.toml) every 2 s, each one's dense
// disparity (half resolution, 64 disparities: the live default), textureless
// pixels dropped, turned into points with the camera's true pose and
// inserted at 0.05 m with a 6 m range, then the 2-D grid between 0.1 and
// 2 m. True poses: this scores the depth and the map, not the filter.
//
// The issue's first target, "at least 95 % of the true obstacle cells the
// camera saw are occupied", is scored as it reads: the cells of the drive
// area where a surface the camera truly saw lies (each matched pixel's ray
// cast against the world, within the range and the grid's heights). It is
// met. Scored instead over every solid cell whose column the map knows, it
// is not, and cannot be: a box's inside is known from the rays over its
// top and never seen.
//
// The second, "at most 2 % of occupied cells are free in truth", is NOT
// met: at half resolution a matched pixel is 0.2-1.7 m of depth at 2-6 m,
// so hits scatter in front of and behind the obstacles (docs/performance.md,
// "Map accuracy in simulation"). The bounds below are today's figures with
// a margin: they catch a regression (a geometry slip put 93 % of the
// occupied cells in free space), not the goal.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "mapping/disparity_points.hpp"
#include "mapping/grid_projection.hpp"
#include "mapping/occupancy_map.hpp"
#include "sim/camera_world.hpp"
#include "sim/drive_scenario.hpp"
#include "sim/path_plan.hpp"
#include "sim/stereo_renderer.hpp"
#include "support/pinhole_stereo.hpp"
#include "support/world_depth.hpp"
#include "vision/semi_global_matcher.hpp"
#include "vision/texture_filter.hpp"

namespace sim_map_accuracy_test {

using namespace rtfuse;

constexpr int kW = 672, kH = 376;  // a ZED's VGA-class eye
constexpr double kF = 350.0, kCx = 336.0, kCy = 188.0, kBaseline = 0.12;

drivers::StereoCalibration pinhole_pair() { return test::pinhole_stereo_pair(kW, kH, kF, kCx, kCy, kBaseline); }

// config/sim.toml's camera mount: 0.2 m ahead, 0.06 m left, 0.3 m up,
// optical axes (x right, y down, z forward).
geometry::RigidTransform base_T_camera() {
  Eigen::Matrix3d r;
  r << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  geometry::RigidTransform t;
  t.rotation = Eigen::Quaterniond(r);
  t.translation = Eigen::Vector3d(0.2, 0.06, 0.3);
  return t;
}

TEST(SimMapAccuracy, ObstacleCourseAgainstTheWorldsTruth) {
  sim::DriveScenario scenario;
  std::string error;
  ASSERT_TRUE(sim::load_drive_scenario(std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/obstacles.toml",
                                       &scenario, &error))
      << error;
  sim::PathPlan plan;
  sim::PlanProblem problem;
  ASSERT_TRUE(sim::PathPlan::build(scenario, &plan, &problem)) << problem.message;
  sim::CameraWorldConfig world_config;
  world_config.seed = scenario.seed;
  world_config.obstacles = scenario.obstacles;
  const sim::CameraWorld world(world_config);
  sim::StereoRenderer renderer(pinhole_pair(), world);
  ASSERT_TRUE(renderer.valid()) << renderer.error();

  vision::DisparityParams dp;
  dp.disparities = 64;
  dp.downscale = 2;
  vision::SemiGlobalMatcher matcher(kW, kH, dp);
  ASSERT_TRUE(matcher.valid()) << matcher.error();
  vision::TextureFilter texture(kW, kH);
  mapping::OccupancyParams mp;
  mp.resolution = 0.05;
  mapping::OccupancyMap map(mp, mapping::capacity_for_bytes(std::size_t{256} << 20));

  const int bpl = renderer.min_bytes_per_line();
  std::vector<std::uint8_t> frame(static_cast<std::size_t>(bpl) * kH);
  vision::Plane<std::uint8_t> left(kW, kH), right(kW, kH);
  vision::Plane<std::uint16_t> disparity(matcher.output_width(kW), matcher.output_height(kH));
  std::vector<mapping::MapPoint> points(static_cast<std::size_t>(disparity.width()) * disparity.height());
  const vision::StereoCameraModel camera{kF, kCx, kCy, kBaseline};
  // The world points the camera truly saw through each matched pixel,
  // within the range (the "seen" of the first target).
  std::vector<Eigen::Vector3d> seen_points;
  int frames = 0;
  for (double t = 0.0; t <= plan.end_time(); t += 2.0, ++frames) {
    const sim::PathPoint p = plan.at(t);
    geometry::RigidTransform world_T_base;
    world_T_base.translation = Eigen::Vector3d(p.x, p.y, 0.0);
    world_T_base.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(p.heading, Eigen::Vector3d::UnitZ()));
    const geometry::RigidTransform world_T_camera = world_T_base * base_T_camera();
    ASSERT_TRUE(renderer.render(world_T_camera, 0, static_cast<std::uint32_t>(frames), frame.data(), bpl));
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        left.row(y)[x] = frame[static_cast<std::size_t>(y) * bpl + 2 * static_cast<std::size_t>(x)];
        right.row(y)[x] = frame[static_cast<std::size_t>(y) * bpl + 2 * static_cast<std::size_t>(kW + x)];
      }
    }
    for (int v = 0; v < disparity.height(); ++v) {
      for (int u = 0; u < disparity.width(); ++u) {
        const double pu = dp.downscale * u + 0.5 * (dp.downscale - 1), pv = dp.downscale * v + 0.5 * (dp.downscale - 1);
        const double z = test::true_depth(world, world_T_camera, kF, kCx, kCy, pu, pv);
        const Eigen::Vector3d in_camera((pu - kCx) * z / kF, (pv - kCy) * z / kF, z);
        if (std::isfinite(z) && in_camera.norm() <= 6.0) seen_points.push_back(world_T_camera * in_camera);
      }
    }
    ASSERT_EQ(matcher.compute(vision::view_of(left), vision::view_of(right), vision::view_of(disparity)),
              vision::DisparityStatus::kOk);
    texture.apply(vision::view_of(left), dp.downscale, vision::view_of(disparity));
    const mapping::DisparityPointCounts c = mapping::disparity_points(
        vision::view_of(disparity), dp.downscale, camera, world_T_camera, points.data(), points.size());
    const Eigen::Vector3d& o = world_T_camera.translation;
    map.insert_scan(points.data(), c.points,
                    {static_cast<float>(o.x()), static_cast<float>(o.y()), static_cast<float>(o.z())}, 6.0);
  }
  EXPECT_EQ(map.dropped_updates(), 0u);

  // The drive area only: its obstacles stand on the grid's lines, so a cell
  // is wholly solid or wholly free (the boxes beyond it stand askew).
  const sim::CameraWorldConfig& area = world.config();
  mapping::GridSpec spec;
  spec.z_min = 0.1;  // above the floor's voxels
  spec.z_max = 2.0;
  ASSERT_TRUE(map.grid().key_of(area.min_x, spec.first_x) && map.grid().key_of(area.min_y, spec.first_y));
  spec.width = static_cast<int>((area.max_x - area.min_x) / mp.resolution);
  spec.height = static_cast<int>((area.max_y - area.min_y) / mp.resolution);
  std::vector<std::int8_t> cells(spec.cells());
  mapping::project_to_grid(map, spec, cells.data());
  const double x0 = mapping::grid_origin_x(map.grid(), spec), y0 = mapping::grid_origin_y(map.grid(), spec);
  const auto cell_at = [&](int i, int j) {
    if (i < 0 || j < 0 || i >= spec.width || j >= spec.height) return mapping::kCellUnknown;
    return cells[static_cast<std::size_t>(j) * static_cast<std::size_t>(spec.width) + static_cast<std::size_t>(i)];
  };
  // Solid anywhere in the square of cells within r of cell (i, j).
  const auto solid_near = [&](int i, int j, int r) {
    const double bx = x0 + (i - r) * mp.resolution, by = y0 + (j - r) * mp.resolution;
    const double side = (2 * r + 1) * mp.resolution;
    return world.solid_in(bx, by, bx + side, by + side, spec.z_min, spec.z_max);
  };
  // The first target: of the cells where a surface the camera saw lies,
  // the share occupied.
  std::vector<std::uint8_t> seen(spec.cells(), 0);
  for (const Eigen::Vector3d& q : seen_points) {
    if (q.z() < spec.z_min || q.z() > spec.z_max) continue;
    const int i = static_cast<int>(std::floor((q.x() - x0) / mp.resolution));
    const int j = static_cast<int>(std::floor((q.y() - y0) / mp.resolution));
    if (i >= 0 && j >= 0 && i < spec.width && j < spec.height) {
      seen[static_cast<std::size_t>(j) * static_cast<std::size_t>(spec.width) + static_cast<std::size_t>(i)] = 1;
    }
  }
  int cells_seen = 0, seen_occupied = 0;
  for (int j = 0; j < spec.height; ++j) {
    for (int i = 0; i < spec.width; ++i) {
      if (!seen[static_cast<std::size_t>(j) * static_cast<std::size_t>(spec.width) + static_cast<std::size_t>(i)]) {
        continue;
      }
      ++cells_seen;
      seen_occupied += cell_at(i, j) == mapping::kCellOccupied;
    }
  }
  ASSERT_GT(cells_seen, 200);  // the course's obstacles were in view
  const double seen_recall = static_cast<double>(seen_occupied) / cells_seen;
  std::printf("%d obstacle cells the camera saw: %.1f %% occupied (the issue: at least 95 %%)\n", cells_seen,
              100.0 * seen_recall);
  EXPECT_GE(seen_recall, 0.95);

  // Strictly, and within a cell: a face on a cell line leaves its fringe of
  // hits one cell out, and a face cell seen past at a slant is carved free.
  int solid_seen = 0, solid_occupied = 0, solid_occupied_near = 0, occupied = 0, occupied_free = 0,
      occupied_far = 0;
  for (int j = 0; j < spec.height; ++j) {
    for (int i = 0; i < spec.width; ++i) {
      const std::int8_t cell = cell_at(i, j);
      if (cell == mapping::kCellUnknown) continue;
      if (solid_near(i, j, 0)) {
        ++solid_seen;
        solid_occupied += cell == mapping::kCellOccupied;
        bool near = false;
        for (int dj = -1; dj <= 1; ++dj) {
          for (int di = -1; di <= 1; ++di) near = near || cell_at(i + di, j + dj) == mapping::kCellOccupied;
        }
        solid_occupied_near += near;
      }
      if (cell == mapping::kCellOccupied) {
        ++occupied;
        occupied_free += !solid_near(i, j, 0);
        occupied_far += !solid_near(i, j, 1);
      }
    }
  }
  ASSERT_GT(solid_seen, 1000);  // the course's obstacles were seen
  ASSERT_GT(occupied, 0);
  const double recall = static_cast<double>(solid_occupied) / solid_seen;
  const double recall_near = static_cast<double>(solid_occupied_near) / solid_seen;
  const double false_share = static_cast<double>(occupied_free) / occupied;
  const double far_share = static_cast<double>(occupied_far) / occupied;
  std::printf("%d keyframes, %llu voxels known, %llu occupied; %d solid cells seen: %.1f %% occupied (%.1f %% "
              "within a cell); %d occupied cells: %.1f %% free in truth (%.1f %% more than a cell from a solid)\n",
              frames, static_cast<unsigned long long>(map.known_voxels()),
              static_cast<unsigned long long>(map.occupied_voxels()), solid_seen, 100.0 * recall,
              100.0 * recall_near, occupied, 100.0 * false_share, 100.0 * far_share);
  // Today (4 paths): 66 % (87 % within a cell) and 61 % (50 %) over every
  // known solid cell; the issue asks at most 2 % free.
  EXPECT_GE(recall, 0.60);
  EXPECT_GE(recall_near, 0.84);
  EXPECT_LE(false_share, 0.68);
  EXPECT_LE(far_share, 0.56);
}

}  // namespace sim_map_accuracy_test
