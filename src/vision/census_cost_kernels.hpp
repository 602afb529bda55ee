// The census cost loop (census_cost.hpp), written once over a lane
// backend B (simd_u8.hpp, simd_avx2.hpp) and compiled once per
// instruction set: deliberately no include guard and no includes. The
// includer puts it inside a namespace of its own per instruction set,
// the AVX2 one between RTFUSE_AVX2_BEGIN and RTFUSE_AVX2_END
// (simd_avx2.hpp says why), after including <cstdint> and
// vision/census_cost.hpp.

static_assert(kCensusPlanes == 4, "the cost loop counts four planes at once");

// One row of costs, cost[x * disparities + d] (census_cost_row's
// contract); disparities a multiple of B::kLanes.
template <class B>
inline void cost_row(const std::uint8_t* const* left, const std::uint8_t* const* right_planes, int width,
                     int disparities, std::uint8_t* cost) noexcept {
  // Local copies: the cost stores could alias the caller's pointer array,
  // which would reload every pointer at every step.
  const std::uint8_t* right_reversed[kCensusPlanes];
  for (int g = 0; g < kCensusPlanes; ++g) right_reversed[g] = right_planes[g];
  for (int x = 0; x < width; ++x) {
    typename B::V l[kCensusPlanes];
    for (int g = 0; g < kCensusPlanes; ++g) l[g] = B::splat(left[g][x]);
    // Right column x - d is reversed column width - 1 - x + d: the
    // disparities run forwards through memory.
    const int j0 = width - 1 - x;
    std::uint8_t* out = cost + static_cast<std::ptrdiff_t>(x) * disparities;
    for (int d = 0; d < disparities; d += B::kLanes) {
      B::store(out + d, B::xor_popcount4(l[0], B::load(right_reversed[0] + j0 + d), l[1],
                                         B::load(right_reversed[1] + j0 + d), l[2], B::load(right_reversed[2] + j0 + d),
                                         l[3], B::load(right_reversed[3] + j0 + d)));
    }
    for (int d = x + 1; d < disparities; ++d) out[d] = kOutsideCost;
  }
}
