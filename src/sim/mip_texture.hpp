#pragma once
// A grey texture with its prefiltered coarser levels (a mip chain), for the
// simulated camera. Level k holds 2^k x 2^k box-filtered texels of level 0;
// a surface seen so far away that one pixel covers many texels is sampled
// from the level whose texels are about a pixel wide, so it shows its mean
// and not an aliased, flickering pick of single texels.
//
// Built once at start-up; sampling is const, allocation-free and uses only
// + - * / and comparisons on floats, so it gives the same bits everywhere.
#include <cstdint>
#include <cstring>
#include <vector>

namespace rtfuse::sim {

class MipTexture {
 public:
  static constexpr int kMaxLevels = 16;

  MipTexture() = default;
  // level0: width * height texels, row-major. Builds every level down to 1 x 1.
  MipTexture(int width, int height, std::vector<std::uint8_t> level0);

  int levels() const noexcept { return level_count_; }
  int width(int level = 0) const noexcept { return level_[level].width; }
  int height(int level = 0) const noexcept { return level_[level].height; }
  std::uint8_t texel(int level, int x, int y) const noexcept {
    const Level& l = level_[level];
    return texels_[l.offset + static_cast<std::size_t>(y) * static_cast<std::size_t>(l.width) +
                   static_cast<std::size_t>(x)];
  }

  // Bilinear at (u, v) in level-0 texel units (texel i spans [i, i + 1)),
  // clamped to the edge.
  float sample(int level, float u, float v) const noexcept {
    const Level& l = level_[level];
    // Texel centres sit at i + 0.5: shift so that integer coordinates hit them.
    float x = u * l.scale - 0.5f;
    float y = v * l.scale - 0.5f;
    x = x < 0.0f ? 0.0f : (x > l.max_x ? l.max_x : x);
    y = y < 0.0f ? 0.0f : (y > l.max_y ? l.max_y : y);
    const int x0 = static_cast<int>(x);  // x >= 0: truncation is floor
    const int y0 = static_cast<int>(y);
    const float fx = x - static_cast<float>(x0);
    const float fy = y - static_cast<float>(y0);
    const std::size_t dx = x0 < l.width - 1 ? 1 : 0;
    const std::size_t dy = y0 < l.height - 1 ? static_cast<std::size_t>(l.width) : 0;
    const std::uint8_t* p = texels_.data() + l.offset +
                            static_cast<std::size_t>(y0) * static_cast<std::size_t>(l.width) +
                            static_cast<std::size_t>(x0);
    const float a = p[0];
    const float b = p[dx];
    const float c = p[dy];
    const float d = p[dy + dx];
    const float top = a + fx * (b - a);
    const float bottom = c + fx * (d - c);
    return top + fy * (bottom - top);
  }
  // Trilinear: lod is log2 of the pixel's footprint in level-0 texels
  // (<= 0: level 0; past the last level: the last one).
  float sample_lod(float u, float v, float lod) const noexcept {
    if (!(lod > 0.0f)) return sample(0, u, v);
    const int k = static_cast<int>(lod);
    if (k >= level_count_ - 1) return sample(level_count_ - 1, u, v);
    const float f = lod - static_cast<float>(k);
    const float fine = sample(k, u, v);
    const float coarse = sample(k + 1, u, v);
    return fine + f * (coarse - fine);
  }

 private:
  struct Level {
    int width = 0;
    int height = 0;
    std::size_t offset = 0;
    float scale = 1.0f;  // level texels per level-0 texel
    float max_x = 0.0f;  // width - 1, height - 1
    float max_y = 0.0f;
  };
  std::vector<std::uint8_t> texels_;
  Level level_[kMaxLevels];
  int level_count_ = 0;
};

// log2(x) for x > 0, exact at powers of two and linear in between (the
// float's exponent and mantissa read as a fixed-point number): a
// deterministic, libm-free level of detail. Off by at most 0.09.
inline float approx_log2(float x) noexcept {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &x, sizeof bits);
  return static_cast<float>(static_cast<std::int32_t>(bits)) * (1.0f / 8388608.0f) - 127.0f;
}

}  // namespace rtfuse::sim
