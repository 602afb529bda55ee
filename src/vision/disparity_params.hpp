#pragma once
// What the dense stereo matcher (semi_global_matcher.hpp) is asked to do.
// The defaults are the usual census-SGM values (Hirschmueller 2008 for the
// scheme; P1 = 10, P2 = 120 of common implementations on the 0..62 scale of
// a full 9x7 census, halved for the 0..31 of the centre-symmetric one used
// here) and OpenCV StereoSGBM's usual post-processing (uniqueness 10 %,
// left-right tolerance 1 px, speckles of 100 px within 2 px), so the
// matcher is not tuned to any one data set.
#include <cstdint>

namespace rtfuse::vision {

struct DisparityParams {
  // Disparities searched, 0 .. disparities - 1, in pixels of the images
  // given to the matcher. disparities / downscale must be a positive
  // multiple of 16 (the vector width of the aggregation), at most 1024.
  int disparities = 64;
  // 1: match at full resolution; 2: halve both images first (2x2 mean) and
  // match at half resolution, disparities still reported in input pixels.
  int downscale = 1;
  // Aggregation paths: 4 (rows and columns both ways) or 8 (the diagonals
  // too). 4 by default: on Middlebury within a point of 8's accuracy and
  // better than OpenCV's SGBM either way, on the simulator's pairs as
  // accurate, and a quarter less time (docs/performance.md).
  int paths = 4;
  // Penalties for a one-step disparity change and for a larger jump between
  // neighbours along a path, on the census cost's scale (0..31);
  // 0 <= p1 <= p2 <= 96 (two paths' costs add up in a byte).
  int p1 = 5;
  int p2 = 60;
  // A winner is kept only when every disparity more than one step away
  // costs at least this many percent more (0: off).
  int uniqueness_percent = 10;
  // Left and right disparities (matched pixels) may differ by this much;
  // negative: no left-right check.
  int lr_max_diff = 1;
  // Connected regions of at most this many matched pixels, neighbours within
  // speckle_range pixels, are marked invalid (0: no speckle filter).
  int speckle_window = 100;
  int speckle_range = 2;
};

}  // namespace rtfuse::vision
