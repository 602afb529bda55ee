#pragma once
// Eight signed 16-bit lanes for the integer image loops: SSE2 on x86-64,
// NEON on aarch64, and a plain array everywhere. The loops take the backend
// as a template parameter so a test can run both on the same input and
// compare: integer lanes have one right answer, so the outputs must match
// bit for bit on every architecture.
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace rtfuse::vision::simd {

// The definition the vector backends must agree with.
struct PlainI16 {
  static constexpr int kLanes = 8;
  struct V {
    std::int16_t x[8];
  };
  static V load(const std::int16_t* p) noexcept {
    V r;
    for (int i = 0; i < 8; ++i) r.x[i] = p[i];
    return r;
  }
  static void store(std::int16_t* p, V a) noexcept {
    for (int i = 0; i < 8; ++i) p[i] = a.x[i];
  }
  static V splat(int a) noexcept {
    V r;
    for (auto& x : r.x) x = static_cast<std::int16_t>(a);
    return r;
  }
  static V max(V a, V b) noexcept {
    for (int i = 0; i < 8; ++i) a.x[i] = a.x[i] > b.x[i] ? a.x[i] : b.x[i];
    return a;
  }
  static V min(V a, V b) noexcept {
    for (int i = 0; i < 8; ++i) a.x[i] = a.x[i] < b.x[i] ? a.x[i] : b.x[i];
    return a;
  }
  // All ones where a > b, else zero.
  static V gt(V a, V b) noexcept {
    for (int i = 0; i < 8; ++i) a.x[i] = static_cast<std::int16_t>(a.x[i] > b.x[i] ? -1 : 0);
    return a;
  }
  // mask ? a : b, lane by lane (mask lanes all ones or zero).
  static V select(V mask, V a, V b) noexcept {
    for (int i = 0; i < 8; ++i) a.x[i] = mask.x[i] != 0 ? a.x[i] : b.x[i];
    return a;
  }
  // Bit i set where mask lane i is set.
  static unsigned bits(V mask) noexcept {
    unsigned r = 0;
    for (int i = 0; i < 8; ++i) r |= mask.x[i] != 0 ? 1u << i : 0u;
    return r;
  }
  // Wrapping (two's complement) sums and differences, as the vector units do.
  static V add(V a, V b) noexcept {
    for (int i = 0; i < 8; ++i) a.x[i] = static_cast<std::int16_t>(static_cast<std::uint16_t>(a.x[i]) + static_cast<std::uint16_t>(b.x[i]));
    return a;
  }
  static V sub(V a, V b) noexcept {
    for (int i = 0; i < 8; ++i) a.x[i] = static_cast<std::int16_t>(static_cast<std::uint16_t>(a.x[i]) - static_cast<std::uint16_t>(b.x[i]));
    return a;
  }
  // Eight bytes, zero-extended.
  static V load_u8(const std::uint8_t* p) noexcept {
    V r;
    for (int i = 0; i < 8; ++i) r.x[i] = p[i];
    return r;
  }
  // The least lane.
  static int hmin(V a) noexcept {
    int m = a.x[0];
    for (int i = 1; i < 8; ++i) m = a.x[i] < m ? a.x[i] : m;
    return m;
  }
  static V bit_and(V a, V b) noexcept {
    for (int i = 0; i < 8; ++i) a.x[i] = static_cast<std::int16_t>(a.x[i] & b.x[i]);
    return a;
  }
  // Each lane's bits moved n (0..15) places up, the top ones dropped.
  static V shl(V a, int n) noexcept {
    for (int i = 0; i < 8; ++i) a.x[i] = static_cast<std::int16_t>(static_cast<std::uint16_t>(static_cast<std::uint16_t>(a.x[i]) << n));
    return a;
  }
};

#if defined(__SSE2__)
struct NativeI16 {
  static constexpr int kLanes = 8;
  using V = __m128i;
  static V load(const std::int16_t* p) noexcept { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }
  static void store(std::int16_t* p, V a) noexcept { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), a); }
  static V splat(int a) noexcept { return _mm_set1_epi16(static_cast<short>(a)); }
  static V max(V a, V b) noexcept { return _mm_max_epi16(a, b); }
  static V min(V a, V b) noexcept { return _mm_min_epi16(a, b); }
  static V gt(V a, V b) noexcept { return _mm_cmpgt_epi16(a, b); }
  static V select(V mask, V a, V b) noexcept { return _mm_or_si128(_mm_and_si128(mask, a), _mm_andnot_si128(mask, b)); }
  static unsigned bits(V mask) noexcept {
    return static_cast<unsigned>(_mm_movemask_epi8(_mm_packs_epi16(mask, _mm_setzero_si128()))) & 0xffu;
  }
  static V add(V a, V b) noexcept { return _mm_add_epi16(a, b); }
  static V sub(V a, V b) noexcept { return _mm_sub_epi16(a, b); }
  static V load_u8(const std::uint8_t* p) noexcept {
    return _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), _mm_setzero_si128());
  }
  static int hmin(V a) noexcept {
    a = _mm_min_epi16(a, _mm_shuffle_epi32(a, _MM_SHUFFLE(1, 0, 3, 2)));
    a = _mm_min_epi16(a, _mm_shuffle_epi32(a, _MM_SHUFFLE(2, 3, 0, 1)));
    a = _mm_min_epi16(a, _mm_shufflelo_epi16(a, _MM_SHUFFLE(2, 3, 0, 1)));
    return static_cast<std::int16_t>(_mm_cvtsi128_si32(a));
  }
  static V bit_and(V a, V b) noexcept { return _mm_and_si128(a, b); }
  static V shl(V a, int n) noexcept { return _mm_sll_epi16(a, _mm_cvtsi32_si128(n)); }
};
constexpr bool kNativeIsVector = true;
#elif defined(__ARM_NEON)
struct NativeI16 {
  static constexpr int kLanes = 8;
  using V = int16x8_t;
  static V load(const std::int16_t* p) noexcept { return vld1q_s16(p); }
  static void store(std::int16_t* p, V a) noexcept { vst1q_s16(p, a); }
  static V splat(int a) noexcept { return vdupq_n_s16(static_cast<std::int16_t>(a)); }
  static V max(V a, V b) noexcept { return vmaxq_s16(a, b); }
  static V min(V a, V b) noexcept { return vminq_s16(a, b); }
  static V gt(V a, V b) noexcept { return vreinterpretq_s16_u16(vcgtq_s16(a, b)); }
  static V select(V mask, V a, V b) noexcept { return vbslq_s16(vreinterpretq_u16_s16(mask), a, b); }
  static unsigned bits(V mask) noexcept {
    static const std::uint16_t kBit[8] = {1, 2, 4, 8, 16, 32, 64, 128};
    return vaddvq_u16(vandq_u16(vreinterpretq_u16_s16(mask), vld1q_u16(kBit)));
  }
  static V add(V a, V b) noexcept { return vaddq_s16(a, b); }
  static V sub(V a, V b) noexcept { return vsubq_s16(a, b); }
  static V load_u8(const std::uint8_t* p) noexcept { return vreinterpretq_s16_u16(vmovl_u8(vld1_u8(p))); }
  static int hmin(V a) noexcept { return vminvq_s16(a); }
  static V bit_and(V a, V b) noexcept { return vandq_s16(a, b); }
  static V shl(V a, int n) noexcept { return vshlq_s16(a, vdupq_n_s16(static_cast<std::int16_t>(n))); }
};
constexpr bool kNativeIsVector = true;
#else
using NativeI16 = PlainI16;
constexpr bool kNativeIsVector = false;
#endif

}  // namespace rtfuse::vision::simd
