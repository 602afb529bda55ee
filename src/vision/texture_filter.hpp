#pragma once
// Takes back the disparities of pixels whose neighbourhood has too little
// horizontal texture to be matched: a plain wall, the sky, a blank floor.
// Semi-global aggregation fills such regions from their edges, and there
// its answer is a guess: on the simulator's plain wall, a guess that put
// obstacles in the middle of free space for the mapper. What stereo can
// measure is horizontal change, so the measure is the mean absolute
// difference of horizontal neighbours over a window (OpenCV's block
// matcher has a texture threshold for the same reason; its SGBM has none).
//
// Integers only, so both architectures drop the same pixels. The summed
// table is sized at construction; apply() allocates nothing.
#include <cstdint>
#include <memory>

#include "vision/disparity_image.hpp"
#include "vision/plane.hpp"

namespace rtfuse::vision {

struct TextureParams {
  int window_width = 9;    // odd, input pixels
  int window_height = 7;   // odd
  // A pixel keeps its disparity when the window's mean |I(x+1, y) - I(x, y)|
  // is at least this many grey levels (0: keep all). Sensor noise of sigma
  // s alone gives about 1.13 s.
  int min_mean_gradient = 4;
};

class TextureFilter {
 public:
  // For left images of at most max_width x max_height.
  TextureFilter(int max_width, int max_height, const TextureParams& params = {});

  // Marks invalid the pixels of disparity (the matcher's output for left at
  // this downscale: pixel (u, v) stands for the input's block at
  // (downscale u, downscale v)) whose window in left lacks texture. Returns
  // how many valid disparities it took back; -1 (nothing done) when the
  // sizes do not fit.
  int apply(const GreyView& left, int downscale, const DisparityImage& disparity) noexcept;

  const TextureParams& params() const noexcept { return params_; }

 private:
  TextureParams params_;
  int max_width_, max_height_;
  std::unique_ptr<std::uint32_t[]> sums_;  // (w + 1) x (h + 1) summed |horizontal difference|
};

}  // namespace rtfuse::vision
