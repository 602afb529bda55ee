#include "sim/mip_texture.hpp"

#include <utility>

namespace rtfuse::sim {

MipTexture::MipTexture(int width, int height, std::vector<std::uint8_t> level0) : texels_(std::move(level0)) {
  if (width <= 0 || height <= 0 || texels_.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    texels_.assign(1, 0);
    width = height = 1;
  }
  level_[0] = Level{width, height, 0, 1.0f, static_cast<float>(width - 1), static_cast<float>(height - 1)};
  level_count_ = 1;
  while (level_count_ < kMaxLevels && (level_[level_count_ - 1].width > 1 || level_[level_count_ - 1].height > 1)) {
    const Level src = level_[level_count_ - 1];
    Level dst;
    dst.width = src.width > 1 ? (src.width + 1) / 2 : 1;
    dst.height = src.height > 1 ? (src.height + 1) / 2 : 1;
    dst.offset = texels_.size();
    dst.scale = src.scale * 0.5f;
    dst.max_x = static_cast<float>(dst.width - 1);
    dst.max_y = static_cast<float>(dst.height - 1);
    texels_.resize(dst.offset + static_cast<std::size_t>(dst.width) * static_cast<std::size_t>(dst.height));
    // 2 x 2 box filter; an odd last row or column is averaged with itself.
    for (int y = 0; y < dst.height; ++y) {
      const int y0 = 2 * y;
      const int y1 = y0 + 1 < src.height ? y0 + 1 : y0;
      for (int x = 0; x < dst.width; ++x) {
        const int x0 = 2 * x;
        const int x1 = x0 + 1 < src.width ? x0 + 1 : x0;
        const int sum = texel(level_count_ - 1, x0, y0) + texel(level_count_ - 1, x1, y0) +
                        texel(level_count_ - 1, x0, y1) + texel(level_count_ - 1, x1, y1);
        texels_[dst.offset + static_cast<std::size_t>(y) * static_cast<std::size_t>(dst.width) +
                static_cast<std::size_t>(x)] = static_cast<std::uint8_t>((sum + 2) / 4);
      }
    }
    level_[level_count_++] = dst;
  }
}

}  // namespace rtfuse::sim
