#pragma once
// Thirty-two unsigned 8-bit and sixteen signed 16-bit lanes on AVX2, for
// the dense matcher's hot loops (semi_global_kernels.hpp,
// census_cost_kernels.hpp) on an x86-64 CPU that has AVX2. The build's
// baseline stays SSE2, so a binary runs on any x86-64: AVX2 is chosen at
// run time (cpu_has_avx2()), and only code compiled between
// RTFUSE_AVX2_BEGIN and RTFUSE_AVX2_END may contain its instructions.
//
// Why a region and not a translation unit built with -mavx2: in such a
// unit every inline function it instantiates from a shared header (the
// standard library's, Plane's) is compiled for AVX2 too, and the linker
// keeps one copy of each for the whole program, possibly that one, for
// code that runs without the check. The region marks only the functions
// defined inside it (GCC's target pragma, clang's attribute pragma);
// templates defined elsewhere and used inside keep the baseline. Inside,
// the kernels are re-included in a namespace of their own
// (semi_global_matcher.cpp), so the same source is compiled once per
// instruction set. Lambdas in a region are covered by both compilers.
//
// Integer lanes have one right answer: these give the bytes of the plain
// definitions (simd_u8.hpp, simd_i16.hpp), which the tests check.
#include <cstdint>

#if defined(__x86_64__) && defined(__SSE2__) && (defined(__GNUC__) || defined(__clang__))
#define RTFUSE_SIMD_AVX2 1
#else
#define RTFUSE_SIMD_AVX2 0
#endif

#if RTFUSE_SIMD_AVX2
#include <immintrin.h>

// Every function defined between the two is compiled for AVX2 (and the
// SSE4.1 and SSSE3 it implies). Nothing may be #included in between: a
// header first included there would be compiled for AVX2 everywhere.
#if defined(__clang__)
#define RTFUSE_AVX2_BEGIN _Pragma("clang attribute push(__attribute__((target(\"avx2\"))), apply_to = function)")
#define RTFUSE_AVX2_END _Pragma("clang attribute pop")
#else
#define RTFUSE_AVX2_BEGIN _Pragma("GCC push_options") _Pragma("GCC target(\"avx2\")")
#define RTFUSE_AVX2_END _Pragma("GCC pop_options")
#endif

namespace rtfuse::vision::simd {

// Whether this CPU and OS run AVX2 (the OS saves the 256-bit registers).
inline bool cpu_has_avx2() noexcept { return __builtin_cpu_supports("avx2") != 0; }

RTFUSE_AVX2_BEGIN

struct Avx2I16 {
  static constexpr int kLanes = 16;
  using V = __m256i;
  static V load(const std::int16_t* p) noexcept { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)); }
  static void store(std::int16_t* p, V a) noexcept { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), a); }
  static V splat(int a) noexcept { return _mm256_set1_epi16(static_cast<short>(a)); }
  static V max(V a, V b) noexcept { return _mm256_max_epi16(a, b); }
  static V min(V a, V b) noexcept { return _mm256_min_epi16(a, b); }
  static V gt(V a, V b) noexcept { return _mm256_cmpgt_epi16(a, b); }
  static V select(V mask, V a, V b) noexcept { return _mm256_blendv_epi8(b, a, mask); }
  static V add(V a, V b) noexcept { return _mm256_add_epi16(a, b); }
  static V sub(V a, V b) noexcept { return _mm256_sub_epi16(a, b); }
  // SSE4.1's minpos finds the least unsigned 16-bit lane in one step;
  // flipping the top bit maps signed order onto unsigned order.
  static int hmin(V a) noexcept {
    const __m128i flip = _mm_set1_epi16(static_cast<short>(0x8000));
    const __m128i m = _mm_min_epi16(_mm256_castsi256_si128(a), _mm256_extracti128_si256(a, 1));
    const int least = _mm_cvtsi128_si32(_mm_minpos_epu16(_mm_xor_si128(m, flip))) & 0xffff;
    return static_cast<std::int16_t>(least ^ 0x8000);
  }
  static V bit_and(V a, V b) noexcept { return _mm256_and_si256(a, b); }
  static V shl(V a, int n) noexcept { return _mm256_sll_epi16(a, _mm_cvtsi32_si128(n)); }
};

struct Avx2U8 {
  static constexpr int kLanes = 32;
  using V = __m256i;
  static V load(const std::uint8_t* p) noexcept { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)); }
  static void store(std::uint8_t* p, V a) noexcept { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), a); }
  static V splat(std::uint8_t a) noexcept { return _mm256_set1_epi8(static_cast<char>(a)); }
  static V add(V a, V b) noexcept { return _mm256_add_epi8(a, b); }
  static V sub(V a, V b) noexcept { return _mm256_sub_epi8(a, b); }
  static V adds(V a, V b) noexcept { return _mm256_adds_epu8(a, b); }
  static V min(V a, V b) noexcept { return _mm256_min_epu8(a, b); }
  // Pairs of bytes to 16-bit lanes (the odd byte of each is then zero),
  // then SSE4.1's minpos.
  static int hmin(V a) noexcept {
    __m128i m = _mm_min_epu8(_mm256_castsi256_si128(a), _mm256_extracti128_si256(a, 1));
    m = _mm_min_epu8(m, _mm_srli_epi16(m, 8));
    return _mm_cvtsi128_si32(_mm_minpos_epu16(m)) & 0xff;
  }
  // AVX2's byte alignment works within each 128-bit half: the half that
  // crosses over is put beside it first.
  static V shift_in_before(V a, V before) noexcept {
    return _mm256_alignr_epi8(a, _mm256_permute2x128_si256(before, a, 0x21), 15);
  }
  static V shift_in_after(V a, V after) noexcept {
    return _mm256_alignr_epi8(_mm256_permute2x128_si256(a, after, 0x21), a, 1);
  }
  using Wide = Avx2I16;
  static Wide::V widen_lo(V a) noexcept { return _mm256_cvtepu8_epi16(_mm256_castsi256_si128(a)); }
  static Wide::V widen_hi(V a) noexcept { return _mm256_cvtepu8_epi16(_mm256_extracti128_si256(a, 1)); }
  // With a byte shuffle, each nibble's count is looked up (SSE2 has none,
  // hence its bit slicing); counts of up to 31 bits fit a byte.
  static V xor_popcount4(V a0, V b0, V a1, V b1, V a2, V b2, V a3, V b3) noexcept {
    return _mm256_add_epi8(_mm256_add_epi8(xor_popcount(a0, b0), xor_popcount(a1, b1)),
                           _mm256_add_epi8(xor_popcount(a2, b2), xor_popcount(a3, b3)));
  }
  static V xor_popcount(V a, V b) noexcept {
    const __m256i counts = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4,  //
                                            0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
    const __m256i m4 = _mm256_set1_epi8(0x0f);
    const __m256i v = _mm256_xor_si256(a, b);
    return _mm256_add_epi8(_mm256_shuffle_epi8(counts, _mm256_and_si256(v, m4)),
                           _mm256_shuffle_epi8(counts, _mm256_and_si256(_mm256_srli_epi16(v, 4), m4)));
  }
};

RTFUSE_AVX2_END

}  // namespace rtfuse::vision::simd

#endif  // RTFUSE_SIMD_AVX2
