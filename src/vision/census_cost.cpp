#include "vision/census_cost.hpp"

#include "vision/simd_u8.hpp"

namespace rtfuse::vision {
namespace {

template <class B>
void cost_row(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width, int disparities,
              std::uint8_t* cost) noexcept {
  for (int x = 0; x < width; ++x) {
    typename B::V l[kCensusPlanes];
    for (int g = 0; g < kCensusPlanes; ++g) l[g] = B::splat(left[g][x]);
    // Right column x - d is reversed column width - 1 - x + d: the
    // disparities run forwards through memory.
    const int j0 = width - 1 - x;
    std::uint8_t* out = cost + static_cast<std::ptrdiff_t>(x) * disparities;
    for (int d = 0; d < disparities; d += 16) {
      // The eight planes' counts add up to at most 62: no byte overflows.
      typename B::V acc = B::xor_popcount(l[0], B::load(right_reversed[0] + j0 + d));
      for (int g = 1; g < kCensusPlanes; ++g) acc = B::add(acc, B::xor_popcount(l[g], B::load(right_reversed[g] + j0 + d)));
      B::store(out + d, acc);
    }
    for (int d = x + 1; d < disparities; ++d) out[d] = kOutsideCost;
  }
}

}  // namespace

void census_cost_row(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width,
                     int disparities, std::uint8_t* cost) noexcept {
  cost_row<simd::NativeU8>(left, right_reversed, width, disparities, cost);
}

void census_cost_row_portable(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width,
                              int disparities, std::uint8_t* cost) noexcept {
  cost_row<simd::PlainU8>(left, right_reversed, width, disparities, cost);
}

}  // namespace rtfuse::vision
