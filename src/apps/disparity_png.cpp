#include "apps/disparity_png.hpp"

#include <png.h>

#include <algorithm>
#include <cstring>
#include <vector>

namespace rtfuse::apps {

std::uint16_t kitti_disparity_value(std::uint16_t matcher_value) noexcept {
  if (matcher_value == vision::kInvalidDisparity) return 0;
  constexpr int kKittiPerMatcher = 256 / vision::kDisparityScale;
  const long v = static_cast<long>(matcher_value) * kKittiPerMatcher;
  return static_cast<std::uint16_t>(std::clamp(v, 1L, 65535L));
}

bool write_kitti_disparity_png(const std::string& path, const vision::DisparityImage& disparity, int scale, int width,
                               int height, std::string* error) {
  if (!disparity.valid() || scale < 1 || width <= 0 || height <= 0) {
    *error = path + ": nothing to write (empty disparity map)";
    return false;
  }
  std::vector<std::uint16_t> pixels(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    const std::uint16_t* src = disparity.row(std::min(y / scale, disparity.height - 1));
    std::uint16_t* dst = pixels.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(width);
    for (int x = 0; x < width; ++x) dst[x] = kitti_disparity_value(src[std::min(x / scale, disparity.width - 1)]);
  }
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  // 16-bit "linear" grey: libpng stores the values as they are.
  image.format = PNG_FORMAT_LINEAR_Y;
  if (png_image_write_to_file(&image, path.c_str(), 0, pixels.data(), 0, nullptr) == 0) {
    *error = path + ": cannot write: " + image.message;
    png_image_free(&image);
    return false;
  }
  png_image_free(&image);
  return true;
}

}  // namespace rtfuse::apps
