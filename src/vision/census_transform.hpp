#pragma once
// The centre-symmetric census transform of a grey image over a 9 x 7
// window (Zabih and Woodfill 1994; the centre-symmetric variant of
// Spangenberg et al. 2013): per pixel, one bit for each of the 31 pairs of
// pixels mirrored about the centre, set where the first (upper, or left on
// the centre row) is darker than its mirror. Matching on these bits (their
// Hamming distance) depends only on the order of the grey levels, so a gain
// or offset between the eyes, or a smooth vignette, changes nothing; 9 x 7
// is the window of most census-SGM implementations (wider than tall:
// rectified eyes differ along rows, where more context separates
// lookalikes). Against the full census (62 bits, each neighbour against
// the centre) it halves the cost loop's work for about a point of bad
// pixels on Middlebury.
//
// The bits are stored as four byte planes (plane g holds bits 8g..8g+7 of
// every pixel; the last plane has 7), so the cost loop XORs and counts 16
// pixels' bytes in one vector operation. Outside the image the nearest
// pixel is repeated; the kCensusHalfWidth columns and kCensusHalfHeight rows at each side are
// therefore less reliable and the matcher marks them invalid.
#include <cstdint>

#include "vision/plane.hpp"

namespace rtfuse::vision {

constexpr int kCensusHalfWidth = 4;   // 9 columns
constexpr int kCensusHalfHeight = 3;  // 7 rows
constexpr int kCensusBits = ((2 * kCensusHalfWidth + 1) * (2 * kCensusHalfHeight + 1) - 1) / 2;  // 31
constexpr int kCensusPlanes = (kCensusBits + 7) / 8;  // 4

// Writes the census of img into planes[0..kCensusPlanes), each at least
// img.width x img.height (their own strides). Integer only: every machine
// writes the same bytes.
void census_transform_9x7(const GreyView& img, Plane<std::uint8_t>* planes) noexcept;
// The same with plain code, for the test that the vector versions agree.
void census_transform_9x7_portable(const GreyView& img, Plane<std::uint8_t>* planes) noexcept;

}  // namespace rtfuse::vision
