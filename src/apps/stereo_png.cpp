#include "apps/stereo_png.hpp"

#include <png.h>

#include <cstddef>
#include <cstring>

#include "apps/rgb_png.hpp"

namespace rtfuse::apps {
namespace {

struct Picture {
  const std::uint8_t* left;
  const std::uint8_t* right;
  int width, height, stride, guide_every_px;
};

// One RGB row of the picture: the two eyes as grey, or a guide line.
void fill_row(const void* context, int y, std::uint8_t* row) noexcept {
  const Picture& p = *static_cast<const Picture*>(context);
  const int n = 2 * p.width;
  if (p.guide_every_px > 0 && y > 0 && y % p.guide_every_px == 0) {
    for (int x = 0; x < n; ++x) std::memcpy(row + 3 * x, kGuideRgb, 3);
    return;
  }
  const std::ptrdiff_t offset = static_cast<std::ptrdiff_t>(y) * p.stride;
  for (int eye = 0; eye < 2; ++eye) {
    const std::uint8_t* src = (eye == 0 ? p.left : p.right) + offset;
    std::uint8_t* dst = row + 3 * eye * p.width;
    for (int x = 0; x < p.width; ++x) dst[3 * x] = dst[3 * x + 1] = dst[3 * x + 2] = src[x];
  }
}

bool fail(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

}  // namespace

bool write_stereo_png(const std::string& path, const std::uint8_t* left, const std::uint8_t* right, int width,
                      int height, int stride, int guide_every_px, std::string* error) {
  const std::string what = "stereo PNG " + path + ": ";
  // Checked before opening, so bad arguments never truncate an existing file.
  if (left == nullptr || right == nullptr) return fail(error, what + "no image (null pixels)");
  if (width <= 0 || height <= 0)
    return fail(error, what + "size " + std::to_string(width) + "x" + std::to_string(height) + " must be positive");
  if (stride < width)
    return fail(error, what + "stride " + std::to_string(stride) + " is less than the width " + std::to_string(width));
  if (width > PNG_USER_WIDTH_MAX / 2 || height > PNG_USER_HEIGHT_MAX)
    return fail(error, what + "pair " + std::to_string(width) + "x" + std::to_string(height) +
                           " exceeds libpng's limits (" + std::to_string(PNG_USER_WIDTH_MAX) + " px per side)");

  const Picture picture{left, right, width, height, stride, guide_every_px};
  return write_rgb_png(path, 2 * width, height, fill_row, &picture, error);
}

}  // namespace rtfuse::apps
