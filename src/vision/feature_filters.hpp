#pragma once
// The integer filters of sparse stereo matching (the VISO2 family of
// features, Geiger et al. 2011):
//
//   halve       2x2 mean, truncated: detection runs at half resolution;
//   sobel5x5    horizontal and vertical gradients, [1 4 6 4 1] smoothing
//               across and [-1 -2 0 2 1] (right minus left, down minus up)
//               along, stored as (g >> 7) + 128 in a byte: the descriptors;
//   blob5x5     the 5x5 mask -1 on the outer ring, +1 on the inner ring, 8
//               at the centre (2 box3 - box5 + 7 centre): bright and dark
//               spots;
//   corner5x5   the separable mask [-1 -1 0 1 1]^T [1 1 0 -1 -1]: corners.
//
// Everything is integer, so every architecture and every vectorisation
// gives the same bytes. Pixels within 2 of the border, where a 5x5 window
// does not fit, are neutral (gradient byte 128, response 0). The row
// buffers are sized once, for the largest image the filters will see.
#include <cstdint>
#include <memory>

#include "vision/plane.hpp"

namespace rtfuse::vision {

class FeatureFilters {
 public:
  // For images at most max_width wide (allocates the row buffers).
  explicit FeatureFilters(int max_width);

  // dst must be src.width / 2 x src.height / 2 (odd last column or row dropped).
  static void halve(const GreyView& src, Plane<std::uint8_t>& dst) noexcept;
  // du, dv as large as src.
  void sobel5x5(const GreyView& src, Plane<std::uint8_t>& du, Plane<std::uint8_t>& dv) noexcept;
  // The sobel5x5 bytes of the window [u0, u0 + du.width()) x [v0, v0 +
  // du.height()) of src, written to du, dv from their (0, 0): the same bytes
  // as the whole image's, for the few places that need full-resolution
  // gradients. The window must stay 2 pixels inside src and be at most 60
  // pixels wide.
  static void sobel5x5_window(const GreyView& src, int u0, int v0, Plane<std::uint8_t>& du,
                              Plane<std::uint8_t>& dv) noexcept;
  // blob, corner as large as src; values within +-4080 and +-2040.
  void blob_corner5x5(const GreyView& src, Plane<std::int16_t>& blob, Plane<std::int16_t>& corner) noexcept;

 private:
  int max_width_;
  // Per column, the five rows around the output row combined vertically.
  // Every sum fits 16 bits (at most 16 x 255 = 4080 before the horizontal
  // pass, 12240 after), so the loops run eight lanes wide.
  std::unique_ptr<std::int16_t[]> smooth_, diff_, box3_, box5_, corner_;
};

}  // namespace rtfuse::vision
