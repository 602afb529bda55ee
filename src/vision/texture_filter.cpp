#include "vision/texture_filter.hpp"

#include <algorithm>
#include <cstdlib>

namespace rtfuse::vision {

TextureFilter::TextureFilter(int max_width, int max_height, const TextureParams& params)
    : params_(params), max_width_(std::max(max_width, 1)), max_height_(std::max(max_height, 1)) {
  params_.window_width = std::max(1, params_.window_width | 1);
  params_.window_height = std::max(1, params_.window_height | 1);
  sums_.reset(new std::uint32_t[static_cast<std::size_t>(max_width_ + 1) * static_cast<std::size_t>(max_height_ + 1)]);
}

int TextureFilter::apply(const GreyView& left, int downscale, const DisparityImage& disparity) noexcept {
  if (!left.valid() || !disparity.valid() || downscale < 1 || left.width > max_width_ ||
      left.height > max_height_ || disparity.width * downscale > left.width ||
      disparity.height * downscale > left.height) {
    return -1;
  }
  if (params_.min_mean_gradient <= 0) return 0;
  const int w = left.width, h = left.height;
  const std::size_t stride = static_cast<std::size_t>(w) + 1;
  std::uint32_t* s = sums_.get();
  // s[(y + 1) * stride + (x + 1)]: the sum of |I(i + 1, j) - I(i, j)| over
  // i <= x, j <= y (the last column's difference is 0).
  std::fill(s, s + stride, 0u);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* row = left.row(y);
    std::uint32_t* out = s + static_cast<std::size_t>(y + 1) * stride;
    const std::uint32_t* above = out - stride;
    out[0] = 0;
    std::uint32_t run = 0;
    for (int x = 0; x < w; ++x) {
      run += x + 1 < w ? static_cast<std::uint32_t>(std::abs(row[x + 1] - row[x])) : 0u;
      out[x + 1] = above[x + 1] + run;
    }
  }
  const int rx = params_.window_width / 2, ry = params_.window_height / 2;
  int taken = 0;
  for (int v = 0; v < disparity.height; ++v) {
    std::uint16_t* d = disparity.row(v);
    const int cy = v * downscale + downscale / 2;
    const int y0 = std::max(cy - ry, 0), y1 = std::min(cy + ry, h - 1);
    for (int u = 0; u < disparity.width; ++u) {
      if (d[u] == kInvalidDisparity) continue;
      const int cx = u * downscale + downscale / 2;
      const int x0 = std::max(cx - rx, 0), x1 = std::min(cx + rx, w - 1);
      const std::uint32_t sum = s[static_cast<std::size_t>(y1 + 1) * stride + (x1 + 1)] -
                                s[static_cast<std::size_t>(y0) * stride + (x1 + 1)] -
                                s[static_cast<std::size_t>(y1 + 1) * stride + x0] +
                                s[static_cast<std::size_t>(y0) * stride + x0];
      const std::uint32_t n = static_cast<std::uint32_t>((x1 - x0 + 1) * (y1 - y0 + 1));
      if (sum < static_cast<std::uint32_t>(params_.min_mean_gradient) * n) {
        d[u] = kInvalidDisparity;
        ++taken;
      }
    }
  }
  return taken;
}

}  // namespace rtfuse::vision
