// The mapping path on the simulator's obstacle course, scored against the
// world's truth (issue 27): the camera's pairs rendered along the scenario's
// drive (config/scenarios/obstacles.toml) every 2 s, each one's dense
// disparity (half resolution, 64 disparities: the live default), textureless
// pixels dropped, turned into points with the camera's true pose and
// inserted at 0.05 m with a 6 m range, then the 2-D grid between 0.1 and
// 2 m. True poses: this scores the depth and the map, not the filter.
// The map's frame lies half a cell off the world's, as a robot's map has
// no reason to start on its walls' lines; on them, a point on a face that
// looks toward +x or +y belongs to the voxel outside it, and the renderer's
// true disparity put 28 % of the occupied cells in free space.
//
// The issue's first target, "at least 95 % of the true obstacle cells the
// camera saw are occupied", is scored as it reads: the cells of the drive
// area where a surface the camera truly saw lies (each pixel's ray, at the
// disparity's resolution, cast against the world, within the range and the
// grid's heights). It is
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
//
// Scored twice: with OctoMap's occupancy threshold (0.5: one hit occupies),
// the mapper's default 6 m range and a keyframe every 2 s; and as
// config/sim_nav.toml maps, a keyframe every 0.2 s (the mapper's 5 a
// second), a 4 m range and a voxel occupied at 0.8 (two hits more than its
// misses' worth): a surface seen from frame to frame stays, a stray match
// seldom repeats. "Seen" is within each one's range. And a third time with
// the renderer's true disparity in place of the matcher's: both targets
// hold, so the scoring and the path from disparity to grid are right, and
// the matcher's depth is what misses the second; and with an oracle that
// keeps only estimates near the truth, to show how near they would have
// to be.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "mapping/grid_projection.hpp"
#include "mapping/occupancy_map.hpp"
#include "sim/camera_world.hpp"
#include "support/obstacle_course_map.hpp"
#include "support/world_depth.hpp"

namespace sim_map_accuracy_test {

using namespace rtfuse;

using test::CourseMappingSettings;
using test::ObstacleCourseMapping;

struct Score {
  int cells_seen = 0;
  double seen_recall = 0.0;   // the first target's share
  double recall = 0.0;        // of every solid cell the map knows
  double recall_near = 0.0;   // the same, an occupied cell within one
  double false_share = 0.0;   // the second target's share
  double far_share = 0.0;     // occupied more than a cell from any solid
};

// The map's frame half a cell off the world's: every face of the course
// then runs through the middle of a cell (CourseMappingSettings says why).
CourseMappingSettings settings(double occupancy_threshold, double range) {
  CourseMappingSettings s;
  s.occupancy_threshold = occupancy_threshold;
  s.range = range;
  const double half_cell = 0.5 * ObstacleCourseMapping::kResolution;
  s.map_offset = Eigen::Vector3d(half_cell, half_cell, 0.0);
  return s;
}

// Maps the course with a keyframe every every_s seconds and scores the
// grid between 0.1 and 2 m against the world.
void score_course(double every_s, const CourseMappingSettings& settings, Score* out) {
  ObstacleCourseMapping course(settings);
  ASSERT_EQ(course.error(), "");
  const Eigen::Vector3d& offset = course.map_offset();
  const sim::CameraWorld& world = course.world();
  const mapping::OccupancyMap& map = course.map();
  constexpr double kF = ObstacleCourseMapping::kF, kCx = ObstacleCourseMapping::kCx, kCy = ObstacleCourseMapping::kCy;
  constexpr double kResolution = ObstacleCourseMapping::kResolution;
  const int downscale = ObstacleCourseMapping::disparity_params().downscale;
  // The world points the camera truly saw through each matched pixel,
  // within the range (the "seen" of the first target).
  std::vector<Eigen::Vector3d> seen_points;
  const int frames = course.drive(every_s, [&](const geometry::RigidTransform& world_T_camera) {
    for (int v = 0; v < course.disparity_height(); ++v) {
      for (int u = 0; u < course.disparity_width(); ++u) {
        const double pu = downscale * u + 0.5 * (downscale - 1), pv = downscale * v + 0.5 * (downscale - 1);
        const double z = test::true_depth(world, world_T_camera, kF, kCx, kCy, pu, pv);
        const Eigen::Vector3d in_camera((pu - kCx) * z / kF, (pv - kCy) * z / kF, z);
        if (std::isfinite(z) && in_camera.norm() <= course.range()) {
          seen_points.push_back(world_T_camera * in_camera);  // the world's frame
        }
      }
    }
  });
  ASSERT_GT(frames, 0) << course.error();
  EXPECT_EQ(map.dropped_updates(), 0u);

  // The drive area only (the boxes beyond it stand askew); a cell is solid
  // when a solid overlaps it, so the cell a face runs through is.
  const sim::CameraWorldConfig& area = world.config();
  mapping::GridSpec spec;
  spec.z_min = 0.1;  // above the floor's voxels
  spec.z_max = 2.0;
  ASSERT_TRUE(map.grid().key_of(area.min_x + offset.x(), spec.first_x) &&
              map.grid().key_of(area.min_y + offset.y(), spec.first_y));
  spec.width = static_cast<int>((area.max_x - area.min_x) / kResolution);
  spec.height = static_cast<int>((area.max_y - area.min_y) / kResolution);
  std::vector<std::int8_t> cells(spec.cells());
  mapping::project_to_grid(map, spec, cells.data());
  // The grid's corner in the world's frame.
  const double x0 = mapping::grid_origin_x(map.grid(), spec) - offset.x();
  const double y0 = mapping::grid_origin_y(map.grid(), spec) - offset.y();
  const auto cell_at = [&](int i, int j) {
    if (i < 0 || j < 0 || i >= spec.width || j >= spec.height) return mapping::kCellUnknown;
    return cells[static_cast<std::size_t>(j) * static_cast<std::size_t>(spec.width) + static_cast<std::size_t>(i)];
  };
  // Solid anywhere in the square of cells within r of cell (i, j).
  const auto solid_near = [&](int i, int j, int r) {
    const double bx = x0 + (i - r) * kResolution, by = y0 + (j - r) * kResolution;
    const double side = (2 * r + 1) * kResolution;
    return world.solid_in(bx, by, bx + side, by + side, spec.z_min, spec.z_max);
  };
  // The first target: of the cells where a surface the camera saw lies,
  // the share occupied.
  std::vector<std::uint8_t> seen(spec.cells(), 0);
  for (const Eigen::Vector3d& q : seen_points) {
    if (q.z() < spec.z_min || q.z() > spec.z_max) continue;
    const int i = static_cast<int>(std::floor((q.x() - x0) / kResolution));
    const int j = static_cast<int>(std::floor((q.y() - y0) / kResolution));
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
  ASSERT_GT(cells_seen, 50);  // the course's obstacles were in view (106 within 2 m)
  const double seen_recall = static_cast<double>(seen_occupied) / cells_seen;
  std::printf("%d obstacle cells the camera saw: %.1f %% occupied (the issue: at least 95 %%)\n", cells_seen,
              100.0 * seen_recall);

  // Strictly, and within a cell.
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
  ASSERT_GT(solid_seen, 100);  // the course's obstacles were seen (193 within 2 m)
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
  *out = Score{cells_seen, seen_recall, recall, recall_near, false_share, far_share};
}

TEST(SimMapAccuracy, ObstacleCourseAgainstTheWorldsTruth) {
  Score s;
  ASSERT_NO_FATAL_FAILURE(score_course(2.0, settings(0.5, ObstacleCourseMapping::kRange), &s));
  EXPECT_GE(s.seen_recall, 0.95);
  // Today (4 paths): 97 % of the seen cells occupied; 64 % (85 % within a
  // cell) of every known solid cell, and 62 % of the occupied cells free
  // in truth (50 % more than a cell from a solid); the issue asks at most
  // 2 % free.
  EXPECT_GE(s.recall, 0.60);
  EXPECT_GE(s.recall_near, 0.84);
  EXPECT_LE(s.false_share, 0.68);
  EXPECT_LE(s.far_share, 0.56);
}

TEST(SimMapAccuracy, AsTheNavigationConfigMapsIt) {
  Score s;
  ASSERT_NO_FATAL_FAILURE(score_course(0.2, settings(0.8, 4.0), &s));
  // Today: 94.6 % of the seen obstacle cells occupied (two hits cost some
  // of what is seen only briefly; the 95 % holds at the defaults
  // above), and 39 % of the occupied cells free in truth, 16 % more than
  // a cell from a solid; the issue asks at most 2 %.
  EXPECT_GE(s.seen_recall, 0.90);
  EXPECT_LE(s.false_share, 0.44);
  EXPECT_LE(s.far_share, 0.22);
}

TEST(SimMapAccuracy, TheTrueDisparityMeetsBothTargets) {
  CourseMappingSettings truth = settings(0.5, ObstacleCourseMapping::kRange);
  truth.true_disparity = true;
  Score s;
  ASSERT_NO_FATAL_FAILURE(score_course(2.0, truth, &s));
  // Today: 97.7 % and 0.0 % (the seen cells the matcher left no pixel
  // of, or saw only at a slant that later rays carved, stay unknown or
  // free). The pipeline from disparity to grid meets the targets:
  // what misses the second is the matcher's depth.
  EXPECT_GE(s.seen_recall, 0.95);
  EXPECT_LE(s.false_share, 0.02);

  // On the world's own voxel lines the same perfect depth fails both: a
  // point on a face that looks toward +x or +y belongs to the voxel outside
  // it (today 84 % and 28 %). Why the map lies half a cell off.
  truth.map_offset = Eigen::Vector3d::Zero();
  ASSERT_NO_FATAL_FAILURE(score_course(2.0, truth, &s));
  EXPECT_LT(s.seen_recall, 0.95);
  EXPECT_GT(s.false_share, 0.2);
}

// How good the depth would have to be: only the matcher's estimates
// within a tolerance of the true disparity kept (an oracle no matcher
// has), and the matcher's at a 2 m range. Today 51.5, 50.0, 43.6 and
// 31.3 % of the occupied cells free in truth within 1, 0.5, 0.25 and
// 0.1 matched px, 35.1 % at 2 m: none near the 2 %, which the
// true disparity (1/32 px in the matcher's fixed point) meets. At 6 m a
// matched pixel is 1.7 m of depth.
TEST(SimMapAccuracy, DepthGoodToATenthOfAPixelStillMissesThePrecisionTarget) {
  for (const double px : {1.0, 0.5, 0.25, 0.1}) {
    SCOPED_TRACE(px);
    CourseMappingSettings oracle = settings(0.5, ObstacleCourseMapping::kRange);
    oracle.keep_within_px = px;
    std::printf("the matcher's estimates within %.2f px of the truth:\n", px);
    Score s;
    ASSERT_NO_FATAL_FAILURE(score_course(2.0, oracle, &s));
    EXPECT_GT(s.false_share, 0.2);
  }
  std::printf("the matcher's at a 2 m range:\n");
  Score s;
  ASSERT_NO_FATAL_FAILURE(score_course(2.0, settings(0.5, 2.0), &s));
  EXPECT_GT(s.false_share, 0.2);
}

}  // namespace sim_map_accuracy_test
