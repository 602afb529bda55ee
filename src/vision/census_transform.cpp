#include "vision/census_transform.hpp"

#include <algorithm>

#include "vision/simd_u8.hpp"

namespace rtfuse::vision {
namespace {

struct CensusOffset {
  int dx, dy;
};

// The window's first half, row-major up to the centre: bit k compares
// offset k with its mirror image -offset k.
struct CensusOffsets {
  CensusOffset at[kCensusBits];
  constexpr CensusOffsets() : at{} {
    int k = 0;
    for (int dy = -kCensusHalfHeight; dy <= kCensusHalfHeight; ++dy) {
      for (int dx = -kCensusHalfWidth; dx <= kCensusHalfWidth; ++dx) {
        if (dy > 0 || (dy == 0 && dx >= 0)) continue;
        at[k++] = CensusOffset{dx, dy};
      }
    }
  }
};
constexpr CensusOffsets kCensusOffsets{};

template <class B>
void census_rows(const GreyView& img, Plane<std::uint8_t>* planes) noexcept {
  const int w = img.width, h = img.height;
  for (int y = 0; y < h; ++y) {
    // Rows outside the image repeat the nearest one.
    const std::uint8_t* rows[2 * kCensusHalfHeight + 1];
    for (int dy = -kCensusHalfHeight; dy <= kCensusHalfHeight; ++dy) {
      rows[dy + kCensusHalfHeight] = img.row(std::clamp(y + dy, 0, h - 1));
    }
    const int x0 = std::min(kCensusHalfWidth, w), x1 = std::max(x0, w - kCensusHalfWidth);
    for (int g = 0; g < kCensusPlanes; ++g) {
      std::uint8_t* out = planes[g].row(y);
      const int k0 = 8 * g, n = std::min(kCensusBits, k0 + 8) - k0;
      const std::uint8_t* src[8];
      const std::uint8_t* mirror[8];
      int dxs[8];
      for (int k = 0; k < n; ++k) {
        src[k] = rows[kCensusOffsets.at[k0 + k].dy + kCensusHalfHeight];
        mirror[k] = rows[kCensusHalfHeight - kCensusOffsets.at[k0 + k].dy];
        dxs[k] = kCensusOffsets.at[k0 + k].dx;
      }
      // Interior, 16 pixels a step; the last step overlaps the one before
      // rather than running past the row.
      if (x1 - x0 >= 16) {
        for (int x = x0;; x += 16) {
          if (x > x1 - 16) x = x1 - 16;
          typename B::V byte = B::bit_if_less(B::load(src[0] + x + dxs[0]), B::load(mirror[0] + x - dxs[0]), 1);
          for (int k = 1; k < n; ++k) {
            byte = B::bit_or(byte, B::bit_if_less(B::load(src[k] + x + dxs[k]), B::load(mirror[k] + x - dxs[k]),
                                                  static_cast<std::uint8_t>(1u << k)));
          }
          B::store(out + x, byte);
          if (x == x1 - 16) break;
        }
      }
      // The side columns (and a row too short for a vector), clamped.
      auto clamped = [&](int x) {
        unsigned byte = 0;
        for (int k = 0; k < n; ++k) {
          byte |= (src[k][std::clamp(x + dxs[k], 0, w - 1)] < mirror[k][std::clamp(x - dxs[k], 0, w - 1)] ? 1u : 0u)
                  << k;
        }
        out[x] = static_cast<std::uint8_t>(byte);
      };
      for (int x = 0; x < x0; ++x) clamped(x);
      if (x1 - x0 < 16) {
        for (int x = x0; x < x1; ++x) clamped(x);
      }
      for (int x = x1; x < w; ++x) clamped(x);
    }
  }
}

}  // namespace

void census_transform_9x7(const GreyView& img, Plane<std::uint8_t>* planes) noexcept {
  census_rows<simd::NativeU8>(img, planes);
}

void census_transform_9x7_portable(const GreyView& img, Plane<std::uint8_t>* planes) noexcept {
  census_rows<simd::PlainU8>(img, planes);
}

}  // namespace rtfuse::vision
