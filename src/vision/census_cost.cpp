#include "vision/census_cost.hpp"

#include <cstdint>

#include "vision/simd_avx2.hpp"
#include "vision/simd_u8.hpp"

namespace rtfuse::vision {
namespace {
namespace lanes {  // the build's baseline: SSE2, NEON or plain
#include "vision/census_cost_kernels.hpp"
}  // namespace lanes
#if RTFUSE_SIMD_AVX2
RTFUSE_AVX2_BEGIN
namespace avx2 {
#include "vision/census_cost_kernels.hpp"
}  // namespace avx2
RTFUSE_AVX2_END
#endif
}  // namespace

void census_cost_row(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width,
                     int disparities, std::uint8_t* cost) noexcept {
  lanes::cost_row<simd::NativeU8>(left, right_reversed, width, disparities, cost);
}

void census_cost_row_portable(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width,
                              int disparities, std::uint8_t* cost) noexcept {
  lanes::cost_row<simd::PlainU8>(left, right_reversed, width, disparities, cost);
}

#if RTFUSE_SIMD_AVX2
bool census_cost_row_avx2(const std::uint8_t* const* left, const std::uint8_t* const* right_reversed, int width,
                          int disparities, std::uint8_t* cost) noexcept {
  if (!simd::cpu_has_avx2() || disparities % simd::Avx2U8::kLanes != 0) return false;
  avx2::cost_row<simd::Avx2U8>(left, right_reversed, width, disparities, cost);
  return true;
}
#else
bool census_cost_row_avx2(const std::uint8_t* const*, const std::uint8_t* const*, int, int, std::uint8_t*) noexcept {
  return false;
}
#endif

}  // namespace rtfuse::vision
