#pragma once
// A dense disparity map as the matcher writes it: one unsigned 16-bit value
// per matched pixel, the disparity in pixels of the matcher's INPUT images
// times kDisparityScale (4 fractional bits, OpenCV's StereoMatcher scale),
// or kInvalidDisparity where there is no estimate. With a downscale of 2 the
// map has half the input's width and height and its pixel (u, v) stands for
// the input pixels 2u..2u+1 x 2v..2v+1 (centre 2u + 0.5, 2v + 0.5); its
// values are still input pixels, so they pair with the input's intrinsics.
#include <cstdint>

#include "vision/plane.hpp"

namespace rtfuse::vision {

constexpr int kDisparityFractionBits = 4;
constexpr int kDisparityScale = 1 << kDisparityFractionBits;
// Not a disparity any range allows (the largest is 4095 * 16 + 15).
constexpr std::uint16_t kInvalidDisparity = 0xFFFF;

// The caller's output rows: width x height values, stride in values.
struct DisparityImage {
  std::uint16_t* data = nullptr;
  int width = 0;
  int height = 0;
  int stride = 0;

  std::uint16_t* row(int v) const noexcept { return data + static_cast<std::ptrdiff_t>(v) * stride; }
  std::uint16_t at(int u, int v) const noexcept { return row(v)[u]; }
  bool valid() const noexcept { return data != nullptr && width > 0 && height > 0 && stride >= width; }
};

inline DisparityImage view_of(Plane<std::uint16_t>& p) noexcept {
  return DisparityImage{p.row(0), p.width(), p.height(), p.stride()};
}

}  // namespace rtfuse::vision
