#pragma once
// The matching cost of the dense stereo matcher: the Hamming distance
// between the left pixel's census and the right pixel's d columns to the
// left (census_transform.hpp), 0..31, one byte per disparity.
#include <cstdint>

#include "vision/census_transform.hpp"

namespace rtfuse::vision {

// The cost given to disparities that would look left of the right image:
// as bad as a match can be, so the aggregation's paths see no evidence there.
constexpr std::uint8_t kOutsideCost = kCensusBits;

// For each x of one row: cost[x * disparities + d], d in [0, disparities),
// of left census byte planes against right ones. right_reversed[g][j] must
// be the right row's plane g at column width - 1 - j, readable for j up to
// width + disparities + 15 (the tail's values do not matter: those costs are
// kOutsideCost). cost must be readable and writable for 16 bytes past the
// row's last value. disparities is a multiple of 8.
void census_cost_row(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width,
                     int disparities, std::uint8_t* cost) noexcept;

// The same with plain code, for the test that the vector versions agree.
void census_cost_row_portable(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width,
                              int disparities, std::uint8_t* cost) noexcept;

// The same with AVX2's 32 lanes (simd_avx2.hpp), where this CPU has AVX2
// and disparities is a multiple of 32; false, and nothing written,
// otherwise (and on every other architecture).
bool census_cost_row_avx2(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width,
                          int disparities, std::uint8_t* cost) noexcept;

}  // namespace rtfuse::vision
