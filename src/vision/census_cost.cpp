#include "vision/census_cost.hpp"

#include <cstdint>

#include "vision/simd_u8.hpp"

namespace rtfuse::vision {
namespace {
namespace lanes {  // the build's baseline: SSE2, NEON or plain
#include "vision/census_cost_kernels.hpp"
}  // namespace lanes
}  // namespace

void census_cost_row(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width,
                     int disparities, std::uint8_t* cost) noexcept {
  lanes::cost_row<simd::NativeU8>(left, right_reversed, width, disparities, cost);
}

void census_cost_row_portable(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width,
                              int disparities, std::uint8_t* cost) noexcept {
  lanes::cost_row<simd::PlainU8>(left, right_reversed, width, disparities, cost);
}

}  // namespace rtfuse::vision
