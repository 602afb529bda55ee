#pragma once
// The points a disparity image sees, in the map's frame: each valid pixel
// of the left eye back-projected through the rectified camera
// (Z = f B / d, X = (u - cu) Z / f, Y = (v - cv) Z / f in the optical frame:
// x right, y down, z forward) and carried by map_T_camera. Invalid pixels
// and zero disparities (a point at infinity: no range to mark, and on sky
// or blank walls mostly a wrong match) are skipped and counted. Far points
// are kept: the map's maximum range turns them into free space up to it,
// as OctoMap does with a laser's long returns.
#include <cstddef>
#include <cstdint>

#include "geometry/rigid_transform.hpp"
#include "mapping/map_point.hpp"
#include "vision/disparity_image.hpp"
#include "vision/stereo_egomotion.hpp"

namespace rtfuse::mapping {

struct DisparityPointCounts {
  std::uint32_t points = 0;       // written
  std::uint32_t invalid = 0;      // no estimate
  std::uint32_t at_infinity = 0;  // disparity 0
  std::uint32_t truncated = 0;    // beyond the output's capacity
};

// disparity: the matcher's output for input images of the camera's size,
// downscale its factor (a pixel (u, v) stands for the input's
// downscale x downscale block). The camera's baseline and focal length must
// be positive and map_T_camera finite (the caller checks; a zero baseline
// gives no points, counted as invalid).
DisparityPointCounts disparity_points(const vision::DisparityImage& disparity, int downscale,
                                      const vision::StereoCameraModel& camera,
                                      const geometry::RigidTransform& map_T_camera, MapPoint* out,
                                      std::size_t capacity) noexcept;

}  // namespace rtfuse::mapping
