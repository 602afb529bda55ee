#pragma once
// Removes speckles from a disparity map: 4-connected regions whose
// neighbouring values differ by at most max_diff are measured, and those of
// at most max_size pixels are marked invalid (OpenCV's filterSpeckles
// semantics). Small islands in a disparity map are nearly always
// mismatches (a repeated texture, a reflection); real surfaces are larger.
// The labels and the flood-fill stack are sized at construction.
#include <cstdint>
#include <memory>

namespace rtfuse::vision {

class SpeckleFilter {
 public:
  // For maps of at most max_pixels pixels.
  explicit SpeckleFilter(int max_pixels);

  // disp: width x height values, rows stride apart; invalid values are
  // negative and stay so. Returns the number of pixels it invalidated.
  int filter(std::int16_t* disp, int width, int height, int stride, int max_size, int max_diff) noexcept;

 private:
  int max_pixels_;
  std::unique_ptr<std::int32_t[]> labels_;  // per pixel: 0 = not yet seen
  std::unique_ptr<std::int32_t[]> stack_;   // pixels to visit
  std::unique_ptr<std::uint8_t[]> small_;   // per label: the region is a speckle
};

}  // namespace rtfuse::vision
