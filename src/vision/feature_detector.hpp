#pragma once
// Sparse features for stereo matching: the extrema of the blob and corner
// responses (vision/feature_filters.hpp), found by block non-maximum
// suppression (Neubeck and Van Gool 2006: the extremes of each (n+1)^2 block,
// kept when nothing in their (2n+1)^2 neighbourhood is more extreme), each
// with a 32-byte descriptor of the gradients around it (16 points x du, dv
// in an 11 x 11 window). Four classes never match each other: dark blob,
// bright blob, and the two corner polarities.
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__ARM_NEON)
#include <arm_neon.h>
#endif

#include "vision/plane.hpp"

namespace rtfuse::vision {

enum FeatureClass : std::uint8_t { kBlobMin = 0, kBlobMax = 1, kCornerMin = 2, kCornerMax = 3 };
constexpr int kFeatureClasses = 4;
constexpr int kDescriptorBytes = 32;
// The descriptor reaches 5 pixels from the feature; the filters 2 more.
constexpr int kMinFeatureMargin = 8;

struct Feature {
  std::uint8_t descriptor[kDescriptorBytes];
  std::int32_t u = 0;  // column and row in the responses' pixels
  std::int32_t v = 0;
  std::int16_t value = 0;  // the response at (u, v)
  std::uint8_t cls = 0;    // FeatureClass
};

struct SuppressionParams {
  int n = 3;        // block (n+1)^2, neighbourhood (2n+1)^2; at most 63
  int tau = 50;     // |response| at least this
  int margin = 9;   // no feature closer to the border (>= kMinFeatureMargin)
};

// The features of one image's responses, in block order (rows of blocks
// from the top, left to right, classes in FeatureClass order). At most
// `capacity` are written; *dropped counts the ones that did not fit.
int suppress_non_maxima(const Plane<std::int16_t>& blob, const Plane<std::int16_t>& corner,
                        const SuppressionParams& params, Feature* out, int capacity, int* dropped) noexcept;
// The same without vector instructions: what the vector version must equal.
int suppress_non_maxima_plain(const Plane<std::int16_t>& blob, const Plane<std::int16_t>& corner,
                              const SuppressionParams& params, Feature* out, int capacity, int* dropped) noexcept;

// Upper bound on what suppress_non_maxima can return for a width x height
// image: four per block. Sizing the feature arrays with it means nothing is
// ever dropped.
int max_features(int width, int height, const SuppressionParams& params) noexcept;

// Fills each feature's descriptor from the gradient bytes (features at
// least kMinFeatureMargin from the border).
void describe(const Plane<std::uint8_t>& du, const Plane<std::uint8_t>& dv, Feature* features, int count) noexcept;

// The matching cost written out, for any architecture (and to check the
// vector versions against).
inline int descriptor_sad_plain(const std::uint8_t* a, const std::uint8_t* b) noexcept {
  int sum = 0;
  for (int i = 0; i < kDescriptorBytes; ++i) sum += a[i] > b[i] ? a[i] - b[i] : b[i] - a[i];
  return sum;
}

// Sum of absolute differences of two descriptors: the matching cost. An
// integer sum, so the SSE2 (psadbw), NEON (vabd + pairwise adds) and plain
// versions give the same number.
inline int descriptor_sad(const std::uint8_t* a, const std::uint8_t* b) noexcept {
#if defined(__SSE2__)
  const __m128i a0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(a));
  const __m128i a1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(a + 16));
  const __m128i b0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(b));
  const __m128i b1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + 16));
  const __m128i s = _mm_add_epi64(_mm_sad_epu8(a0, b0), _mm_sad_epu8(a1, b1));
  return _mm_cvtsi128_si32(s) + _mm_cvtsi128_si32(_mm_srli_si128(s, 8));
#elif defined(__ARM_NEON)
  const uint8x16_t d0 = vabdq_u8(vld1q_u8(a), vld1q_u8(b));
  const uint8x16_t d1 = vabdq_u8(vld1q_u8(a + 16), vld1q_u8(b + 16));
  const uint16x8_t s = vaddq_u16(vpaddlq_u8(d0), vpaddlq_u8(d1));
  return static_cast<int>(vaddvq_u16(s));
#else
  return descriptor_sad_plain(a, b);
#endif
}

}  // namespace rtfuse::vision
