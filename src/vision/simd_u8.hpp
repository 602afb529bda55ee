#pragma once
// Sixteen unsigned 8-bit lanes for the census and aggregation loops
// (census_transform.cpp, census_cost.cpp, semi_global_matcher.cpp): SSE2 on x86-64, NEON on aarch64, a plain array
// everywhere, as simd_i16.hpp does for 16-bit lanes. Integer lanes have one
// right answer, so every backend gives the same bytes.
#include <cstdint>

#include "vision/simd_i16.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace rtfuse::vision::simd {

// The definition the vector backends must agree with.
struct PlainU8 {
  struct V {
    std::uint8_t x[16];
  };
  static V load(const std::uint8_t* p) noexcept {
    V r;
    for (int i = 0; i < 16; ++i) r.x[i] = p[i];
    return r;
  }
  static void store(std::uint8_t* p, V a) noexcept {
    for (int i = 0; i < 16; ++i) p[i] = a.x[i];
  }
  static V splat(std::uint8_t a) noexcept {
    V r;
    for (auto& x : r.x) x = a;
    return r;
  }
  static V add(V a, V b) noexcept {
    for (int i = 0; i < 16; ++i) a.x[i] = static_cast<std::uint8_t>(a.x[i] + b.x[i]);
    return a;
  }
  static V bit_or(V a, V b) noexcept {
    for (int i = 0; i < 16; ++i) a.x[i] = static_cast<std::uint8_t>(a.x[i] | b.x[i]);
    return a;
  }
  // bit where a < b, else 0.
  static V bit_if_less(V a, V b, std::uint8_t bit) noexcept {
    for (int i = 0; i < 16; ++i) a.x[i] = a.x[i] < b.x[i] ? bit : 0;
    return a;
  }
  static V sub(V a, V b) noexcept {
    for (int i = 0; i < 16; ++i) a.x[i] = static_cast<std::uint8_t>(a.x[i] - b.x[i]);
    return a;
  }
  // Saturating at 255.
  static V adds(V a, V b) noexcept {
    for (int i = 0; i < 16; ++i) a.x[i] = static_cast<std::uint8_t>(a.x[i] + b.x[i] > 255 ? 255 : a.x[i] + b.x[i]);
    return a;
  }
  static V min(V a, V b) noexcept {
    for (int i = 0; i < 16; ++i) a.x[i] = a.x[i] < b.x[i] ? a.x[i] : b.x[i];
    return a;
  }
  static int hmin(V a) noexcept {
    int m = a.x[0];
    for (int i = 1; i < 16; ++i) m = a.x[i] < m ? a.x[i] : m;
    return m;
  }
  // Lanes 0..7 and 8..15 as 16-bit lanes, zero-extended.
  using Wide = PlainI16;
  static Wide::V widen_lo(V a) noexcept {
    Wide::V r;
    for (int i = 0; i < 8; ++i) r.x[i] = a.x[i];
    return r;
  }
  static Wide::V widen_hi(V a) noexcept {
    Wide::V r;
    for (int i = 0; i < 8; ++i) r.x[i] = a.x[8 + i];
    return r;
  }
  // The number of bits set in a ^ b, per byte.
  static V xor_popcount(V a, V b) noexcept {
    for (int i = 0; i < 16; ++i) {
      unsigned v = static_cast<unsigned>(a.x[i] ^ b.x[i]), n = 0;
      for (; v != 0; v &= v - 1) ++n;
      a.x[i] = static_cast<std::uint8_t>(n);
    }
    return a;
  }
};

#if defined(__SSE2__)
struct NativeU8 {
  using V = __m128i;
  static V load(const std::uint8_t* p) noexcept { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }
  static void store(std::uint8_t* p, V a) noexcept { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), a); }
  static V splat(std::uint8_t a) noexcept { return _mm_set1_epi8(static_cast<char>(a)); }
  static V add(V a, V b) noexcept { return _mm_add_epi8(a, b); }
  static V bit_or(V a, V b) noexcept { return _mm_or_si128(a, b); }
  static V sub(V a, V b) noexcept { return _mm_sub_epi8(a, b); }
  static V adds(V a, V b) noexcept { return _mm_adds_epu8(a, b); }
  static V min(V a, V b) noexcept { return _mm_min_epu8(a, b); }
  static int hmin(V a) noexcept {
    a = _mm_min_epu8(a, _mm_srli_si128(a, 8));
    a = _mm_min_epu8(a, _mm_srli_si128(a, 4));
    a = _mm_min_epu8(a, _mm_srli_si128(a, 2));
    a = _mm_min_epu8(a, _mm_srli_si128(a, 1));
    return _mm_cvtsi128_si32(a) & 0xff;
  }
  using Wide = NativeI16;
  static Wide::V widen_lo(V a) noexcept { return _mm_unpacklo_epi8(a, _mm_setzero_si128()); }
  static Wide::V widen_hi(V a) noexcept { return _mm_unpackhi_epi8(a, _mm_setzero_si128()); }
  // SSE2 compares signed bytes only: flipping the top bit orders unsigned ones.
  static V bit_if_less(V a, V b, std::uint8_t bit) noexcept {
    const __m128i flip = _mm_set1_epi8(static_cast<char>(0x80));
    return _mm_and_si128(_mm_cmplt_epi8(_mm_xor_si128(a, flip), _mm_xor_si128(b, flip)),
                         _mm_set1_epi8(static_cast<char>(bit)));
  }
  // No byte shuffle to look counts up in: the bit-slicing count.
  static V xor_popcount(V a, V b) noexcept {
    const __m128i m1 = _mm_set1_epi8(0x55), m2 = _mm_set1_epi8(0x33), m4 = _mm_set1_epi8(0x0f);
    __m128i v = _mm_xor_si128(a, b);
    v = _mm_sub_epi8(v, _mm_and_si128(_mm_srli_epi16(v, 1), m1));
    v = _mm_add_epi8(_mm_and_si128(v, m2), _mm_and_si128(_mm_srli_epi16(v, 2), m2));
    return _mm_and_si128(_mm_add_epi8(v, _mm_srli_epi16(v, 4)), m4);
  }
};
#elif defined(__ARM_NEON)
struct NativeU8 {
  using V = uint8x16_t;
  static V load(const std::uint8_t* p) noexcept { return vld1q_u8(p); }
  static void store(std::uint8_t* p, V a) noexcept { vst1q_u8(p, a); }
  static V splat(std::uint8_t a) noexcept { return vdupq_n_u8(a); }
  static V add(V a, V b) noexcept { return vaddq_u8(a, b); }
  static V bit_or(V a, V b) noexcept { return vorrq_u8(a, b); }
  static V sub(V a, V b) noexcept { return vsubq_u8(a, b); }
  static V adds(V a, V b) noexcept { return vqaddq_u8(a, b); }
  static V min(V a, V b) noexcept { return vminq_u8(a, b); }
  static int hmin(V a) noexcept { return vminvq_u8(a); }
  using Wide = NativeI16;
  static Wide::V widen_lo(V a) noexcept { return vreinterpretq_s16_u16(vmovl_u8(vget_low_u8(a))); }
  static Wide::V widen_hi(V a) noexcept { return vreinterpretq_s16_u16(vmovl_u8(vget_high_u8(a))); }
  static V bit_if_less(V a, V b, std::uint8_t bit) noexcept { return vandq_u8(vcltq_u8(a, b), vdupq_n_u8(bit)); }
  static V xor_popcount(V a, V b) noexcept { return vcntq_u8(veorq_u8(a, b)); }
};
#else
using NativeU8 = PlainU8;
#endif

}  // namespace rtfuse::vision::simd
