#pragma once
// One rectified stereo pair into the occupancy map: its dense disparity
// (vision/semi_global_matcher.hpp), textureless pixels taken back
// (vision/texture_filter.hpp: a guess there is a phantom obstacle), the
// valid pixels back-projected and carried into the map's frame
// (disparity_points.hpp), then inserted as one scan from the left eye's
// centre with the maximum range (occupancy_map.hpp). The two halves are
// separate calls so a caller can time them.
//
// Everything (matcher workspace, texture table, point buffer, map pool) is
// allocated in create(); points_of() and insert() allocate nothing.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "geometry/rigid_transform.hpp"
#include "mapping/disparity_points.hpp"
#include "mapping/occupancy_map.hpp"
#include "mapping/occupancy_params.hpp"
#include "vision/disparity_params.hpp"
#include "vision/plane.hpp"
#include "vision/stereo_egomotion.hpp"
#include "vision/texture_filter.hpp"

namespace rtfuse::vision {
class SemiGlobalMatcher;
}

namespace rtfuse::mapping {

struct KeyframeMapperParams {
  vision::DisparityParams disparity;
  vision::TextureParams texture;
  OccupancyParams occupancy;
  double max_range_m = 6.0;          // longer rays free up to it and mark nothing
  std::size_t pool_bytes = 64u << 20;
};

// What one pair gave.
struct KeyframePoints {
  DisparityPointCounts counts;
  int textureless = 0;  // valid disparities taken back for lack of texture
  bool ok = false;      // false: the matcher refused the pair (size)
};

class KeyframeMapper {
 public:
  // For pairs of width x height through `camera`. Null with *error saying
  // what to change when the camera (no focal length, no baseline), the
  // disparity range, the occupancy parameters or the pool cannot work.
  static std::unique_ptr<KeyframeMapper> create(int width, int height, const vision::StereoCameraModel& camera,
                                                const KeyframeMapperParams& params, std::string* error);
  ~KeyframeMapper();
  KeyframeMapper(const KeyframeMapper&) = delete;
  KeyframeMapper& operator=(const KeyframeMapper&) = delete;

  // The points of a pair seen from map_T_camera (the left eye's optical
  // frame, x right, y down, z forward), kept for insert().
  KeyframePoints points_of(const vision::GreyView& left, const vision::GreyView& right,
                           const geometry::RigidTransform& map_T_camera) noexcept;
  // The points of the last points_of() as one scan from its eye.
  ScanResult insert() noexcept;

  OccupancyMap& map() noexcept { return *map_; }
  const OccupancyMap& map() const noexcept { return *map_; }
  const KeyframeMapperParams& params() const noexcept { return params_; }
  std::size_t point_capacity() const noexcept { return capacity_; }

 private:
  KeyframeMapper() = default;

  KeyframeMapperParams params_;
  vision::StereoCameraModel camera_;
  int width_ = 0, height_ = 0;
  std::unique_ptr<vision::SemiGlobalMatcher> matcher_;
  std::unique_ptr<vision::TextureFilter> texture_;
  std::unique_ptr<std::uint16_t[]> disparity_;
  int disparity_width_ = 0, disparity_height_ = 0;
  std::unique_ptr<MapPoint[]> points_;
  std::size_t capacity_ = 0;
  std::uint32_t count_ = 0;
  MapPoint origin_;
  std::unique_ptr<OccupancyMap> map_;
};

// Bricks (8 x 8 x 8 voxels) one scan may need at most: the floor and walls
// a max_range circle of rays can reach, two brick layers high; a pool that
// cannot hold this fills on the first keyframes. A bound for a config
// check, not an exact count.
std::uint64_t bricks_for_one_scan(double resolution_m, double max_range_m) noexcept;

}  // namespace rtfuse::mapping
