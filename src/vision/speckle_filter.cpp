#include "vision/speckle_filter.hpp"

#include <cstdlib>
#include <cstring>

namespace rtfuse::vision {

SpeckleFilter::SpeckleFilter(int max_pixels)
    : max_pixels_(max_pixels > 0 ? max_pixels : 0),
      labels_(new std::int32_t[static_cast<std::size_t>(max_pixels_) + 1]()),
      stack_(new std::int32_t[static_cast<std::size_t>(max_pixels_) + 1]()),
      small_(new std::uint8_t[static_cast<std::size_t>(max_pixels_) + 2]()) {}

int SpeckleFilter::filter(std::int16_t* disp, int width, int height, int stride, int max_size,
                          int max_diff) noexcept {
  if (width <= 0 || height <= 0 || static_cast<long long>(width) * height > max_pixels_ || max_size <= 0) return 0;
  std::int32_t* labels = labels_.get();
  std::memset(labels, 0, sizeof(std::int32_t) * static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  int next_label = 0, removed = 0;
  for (int y = 0; y < height; ++y) {
    std::int16_t* row = disp + static_cast<std::ptrdiff_t>(y) * stride;
    for (int x = 0; x < width; ++x) {
      const int i = y * width + x;
      if (row[x] < 0) continue;
      if (labels[i] != 0) {
        if (small_[labels[i]] != 0) {
          row[x] = -1;
          ++removed;
        }
        continue;
      }
      // A new region: flood it, counting its pixels.
      const int label = ++next_label;
      labels[i] = label;
      int top = 0, count = 0;
      stack_[top++] = i;
      while (top > 0) {
        const int p = stack_[--top];
        ++count;
        // One division per region pixel; the neighbours' values are found
        // from its row (a division per neighbour cost more than the fill).
        const int py = p / width, px = p - py * width;
        const std::int16_t* at = disp + static_cast<std::ptrdiff_t>(py) * stride + px;
        const int v = *at;
        auto visit = [&](int q, const std::int16_t* value) {
          if (labels[q] != 0) return;
          const int vq = *value;
          if (vq < 0 || std::abs(vq - v) > max_diff) return;
          labels[q] = label;
          stack_[top++] = q;
        };
        if (px > 0) visit(p - 1, at - 1);
        if (px + 1 < width) visit(p + 1, at + 1);
        if (py > 0) visit(p - width, at - stride);
        if (py + 1 < height) visit(p + width, at + stride);
      }
      small_[label] = count <= max_size ? 1 : 0;
      if (small_[label] != 0) {
        row[x] = -1;
        ++removed;
      }
    }
  }
  return removed;
}

}  // namespace rtfuse::vision
