#pragma once
// Sixteen unsigned 8-bit lanes for the census and aggregation loops
// (census_transform.cpp, census_cost_kernels.hpp, semi_global_kernels.hpp):
// SSE2 on x86-64, NEON on aarch64, a plain array everywhere, as
// simd_i16.hpp does for 16-bit lanes (simd_avx2.hpp: AVX2's 32, chosen at
// run time). Integer lanes have one right answer, so every backend gives
// the same bytes.
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
  static constexpr int kLanes = 16;
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
  // The sixteen bytes one place earlier in memory: before's last, then
  // a's first fifteen.
  static V shift_in_before(V a, V before) noexcept {
    V r;
    r.x[0] = before.x[15];
    for (int i = 1; i < 16; ++i) r.x[i] = a.x[i - 1];
    return r;
  }
  // One place later: a's last fifteen, then after's first.
  static V shift_in_after(V a, V after) noexcept {
    V r;
    for (int i = 0; i < 15; ++i) r.x[i] = a.x[i + 1];
    r.x[15] = after.x[0];
    return r;
  }
  // The first and the last half of the lanes as 16-bit lanes, zero-extended.
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
  // The bits set in a0 ^ b0, a1 ^ b1, a2 ^ b2 and a3 ^ b3 together, per
  // byte; the last pair's top bits must be clear (the census's 31 bits).
  static V xor_popcount4(V a0, V b0, V a1, V b1, V a2, V b2, V a3, V b3) noexcept {
    return add(add(xor_popcount(a0, b0), xor_popcount(a1, b1)), add(xor_popcount(a2, b2), xor_popcount(a3, b3)));
  }
};

#if defined(__SSE2__)
struct NativeU8 {
  static constexpr int kLanes = 16;
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
  static V shift_in_before(V a, V before) noexcept {
    return _mm_or_si128(_mm_slli_si128(a, 1), _mm_srli_si128(before, 15));
  }
  static V shift_in_after(V a, V after) noexcept {
    return _mm_or_si128(_mm_srli_si128(a, 1), _mm_slli_si128(after, 15));
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
  // Four counts share the last step: per nibble a count is at most 4, and
  // a3 ^ b3's top nibble (three bits) at most 3, so two pairs' nibbles add
  // up without a carry (at most 8), and the four high nibbles too (at most
  // 15) once the low ones (up to 16) are masked off.
  static V xor_popcount4(V a0, V b0, V a1, V b1, V a2, V b2, V a3, V b3) noexcept {
    const __m128i m4 = _mm_set1_epi8(0x0f), m4_high = _mm_set1_epi8(static_cast<char>(0xf0));
    const __m128i n01 = _mm_add_epi8(nibble_counts(_mm_xor_si128(a0, b0)), nibble_counts(_mm_xor_si128(a1, b1)));
    const __m128i n23 = _mm_add_epi8(nibble_counts(_mm_xor_si128(a2, b2)), nibble_counts(_mm_xor_si128(a3, b3)));
    const __m128i high = _mm_add_epi8(_mm_and_si128(n01, m4_high), _mm_and_si128(n23, m4_high));
    const __m128i low = _mm_add_epi8(_mm_and_si128(n01, m4), _mm_and_si128(n23, m4));
    return _mm_add_epi8(_mm_and_si128(_mm_srli_epi16(high, 4), m4), low);
  }
  // Each nibble's bit count (0..4).
  static V nibble_counts(V v) noexcept {
    const __m128i m1 = _mm_set1_epi8(0x55), m2 = _mm_set1_epi8(0x33);
    v = _mm_sub_epi8(v, _mm_and_si128(_mm_srli_epi16(v, 1), m1));
    return _mm_add_epi8(_mm_and_si128(v, m2), _mm_and_si128(_mm_srli_epi16(v, 2), m2));
  }
};
#elif defined(__ARM_NEON)
struct NativeU8 {
  static constexpr int kLanes = 16;
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
  static V shift_in_before(V a, V before) noexcept { return vextq_u8(before, a, 15); }
  static V shift_in_after(V a, V after) noexcept { return vextq_u8(a, after, 1); }
  using Wide = NativeI16;
  static Wide::V widen_lo(V a) noexcept { return vreinterpretq_s16_u16(vmovl_u8(vget_low_u8(a))); }
  static Wide::V widen_hi(V a) noexcept { return vreinterpretq_s16_u16(vmovl_u8(vget_high_u8(a))); }
  static V bit_if_less(V a, V b, std::uint8_t bit) noexcept { return vandq_u8(vcltq_u8(a, b), vdupq_n_u8(bit)); }
  static V xor_popcount(V a, V b) noexcept { return vcntq_u8(veorq_u8(a, b)); }
  static V xor_popcount4(V a0, V b0, V a1, V b1, V a2, V b2, V a3, V b3) noexcept {
    return vaddq_u8(vaddq_u8(xor_popcount(a0, b0), xor_popcount(a1, b1)),
                    vaddq_u8(xor_popcount(a2, b2), xor_popcount(a3, b3)));
  }
};
#else
using NativeU8 = PlainU8;
#endif

}  // namespace rtfuse::vision::simd
