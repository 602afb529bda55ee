#pragma once
// Writing a disparity map the way the KITTI stereo benchmark stores one: a
// 16-bit grey PNG, disparity in pixels times 256, 0 where there is no
// estimate. A tool's writer (allocates, does file I/O); never on the
// real-time path.
#include <cstdint>
#include <string>

#include "vision/disparity_image.hpp"

namespace rtfuse::apps {

// The KITTI value of one matcher value (vision/disparity_image.hpp): a
// valid disparity of exactly 0 becomes 1 (1/256 px) so it is not read as
// "no estimate"; disparities past 255.996 px, which 16 bits cannot hold,
// are clamped.
std::uint16_t kitti_disparity_value(std::uint16_t matcher_value) noexcept;

// Writes `path`: width x height pixels (the matcher's input size), each
// from the disparity map's pixel (x / scale, y / scale), clamped to the map
// (scale: the matcher's downscale). False and *error naming the path and
// libpng's reason.
bool write_kitti_disparity_png(const std::string& path, const vision::DisparityImage& disparity, int scale, int width,
                               int height, std::string* error);

}  // namespace rtfuse::apps
