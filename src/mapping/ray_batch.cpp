#include "mapping/ray_batch.hpp"

#include <cstddef>
#include <cstring>

#include "vision/simd_avx2.hpp"

namespace rtfuse::mapping {

#if RTFUSE_SIMD_AVX2

bool ray_batch_available() noexcept { return vision::simd::cpu_has_avx2(); }

RTFUSE_AVX2_BEGIN

namespace {

struct Lanes {
  __m256i t[3], n[3], c[3], dd[3], k[3];
  __m256i current, end, limit;
};

__m256i gather(const RayState* r, std::size_t offset) noexcept {
  const auto at = [&](int i) {
    std::uint64_t v;
    std::memcpy(&v, reinterpret_cast<const unsigned char*>(&r[i]) + offset, sizeof v);
    return static_cast<long long>(v);
  };
  return _mm256_set_epi64x(at(3), at(2), at(1), at(0));
}

void scatter(RayState* r, std::size_t offset, __m256i v) noexcept {
  alignas(32) std::uint64_t lanes[4];
  _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), v);
  for (int i = 0; i < 4; ++i) std::memcpy(reinterpret_cast<unsigned char*>(&r[i]) + offset, &lanes[i], sizeof lanes[i]);
}

// The selects. blendv takes b where the mask's lane is set.
inline __m256i pick(__m256i mask, __m256i b, __m256i a) noexcept { return _mm256_blendv_epi8(a, b, mask); }

// The emitted lanes to the front, as 32-bit halves: for each 4-bit mask of
// lanes, the permutation and how many.
struct Compaction {
  int index[16][8];
  int count[16];
};
constexpr Compaction make_compaction() {
  Compaction c{};
  for (int m = 0; m < 16; ++m) {
    int n = 0;
    for (int lane = 0; lane < 4; ++lane) {
      if ((m >> lane & 1) == 0) continue;
      c.index[m][2 * n] = 2 * lane;
      c.index[m][2 * n + 1] = 2 * lane + 1;
      ++n;
    }
    for (int k = 2 * n; k < 8; ++k) c.index[m][k] = k;
    c.count[m] = n;
  }
  return c;
}
constexpr Compaction kCompaction = make_compaction();

}  // namespace

std::size_t step_rays4(RayState* rays, unsigned& live, const ScanWindow::Probe& window, std::uint64_t* out,
                       std::size_t capacity) noexcept {
  Lanes s;
  for (int i = 0; i < 3; ++i) {
    s.t[i] = gather(rays, offsetof(RayState, t) + i * sizeof(std::uint64_t));
    s.n[i] = gather(rays, offsetof(RayState, n) + i * sizeof(std::uint64_t));
    s.c[i] = gather(rays, offsetof(RayState, c) + i * sizeof(double));
    s.dd[i] = gather(rays, offsetof(RayState, dd) + i * sizeof(std::uint64_t));
    s.k[i] = gather(rays, offsetof(RayState, k) + i * sizeof(std::uint64_t));
  }
  s.current = gather(rays, offsetof(RayState, current));
  s.end = gather(rays, offsetof(RayState, end));
  s.limit = gather(rays, offsetof(RayState, limit));
  const __m256i lane_bits = _mm256_set_epi64x(8, 4, 2, 1);
  // ScanWindow::Probe::visit's test, without the marking.
  const __m256i shift = _mm256_set1_epi64x(static_cast<long long>(window.shift()));
  const __m256i tag = _mm256_set1_epi64x(static_cast<long long>(window.tag()));
  const __m256i high = _mm256_set1_epi64x(static_cast<long long>(ScanWindow::kHighBytes));
  const long long* const bits = reinterpret_cast<const long long*>(window.bits());
  const __m256i one = _mm256_set1_epi64x(1);
  __m256i active = _mm256_cmpeq_epi64(_mm256_and_si256(_mm256_set1_epi64x(live), lane_bits), lane_bits);
  const unsigned started = live;

  // detail::choose: lt01 = t0 < t1, lt = min(t0, t1) (ties to t1) < t2.
  // The distances are non-negative doubles (or +inf), whose bits order as
  // signed 64-bit integers do.
  __m256i lt01 = _mm256_cmpgt_epi64(s.t[1], s.t[0]);
  __m256i lt = _mm256_cmpgt_epi64(s.t[2], pick(lt01, s.t[0], s.t[1]));
  std::size_t written = 0;
  while (written + 4 <= capacity) {
    // detail::advance0..2: the stepping axis moves t to n, n to the sum
    // ahead, and adds its delta to that sum; the others add +0.0.
    const __m256i step0 = _mm256_and_si256(lt, lt01);
    const __m256i step1 = _mm256_andnot_si256(lt01, lt);
    s.t[0] = pick(step0, s.n[0], s.t[0]);
    s.n[0] = pick(step0, s.c[0], s.n[0]);
    s.c[0] = _mm256_castpd_si256(_mm256_add_pd(_mm256_castsi256_pd(s.c[0]),
                                               _mm256_castsi256_pd(_mm256_and_si256(step0, s.dd[0]))));
    s.t[1] = pick(step1, s.n[1], s.t[1]);
    s.n[1] = pick(step1, s.c[1], s.n[1]);
    s.c[1] = _mm256_castpd_si256(_mm256_add_pd(_mm256_castsi256_pd(s.c[1]),
                                               _mm256_castsi256_pd(_mm256_and_si256(step1, s.dd[1]))));
    s.t[2] = pick(lt, s.t[2], s.n[2]);
    s.n[2] = pick(lt, s.n[2], s.c[2]);
    s.c[2] = _mm256_castpd_si256(_mm256_add_pd(_mm256_castsi256_pd(s.c[2]),
                                               _mm256_castsi256_pd(_mm256_andnot_si256(lt, s.dd[2]))));
    const __m256i key_step = _mm256_or_si256(_mm256_or_si256(_mm256_and_si256(step0, s.k[0]), _mm256_and_si256(step1, s.k[1])),
                                             _mm256_andnot_si256(lt, s.k[2]));
    s.current = _mm256_add_epi64(s.current, key_step);
    // The next step's choice, whose smallest distance is the limit test.
    lt01 = _mm256_cmpgt_epi64(s.t[1], s.t[0]);
    const __m256i m01 = pick(lt01, s.t[0], s.t[1]);
    lt = _mm256_cmpgt_epi64(s.t[2], m01);
    const __m256i smallest = pick(lt, m01, s.t[2]);
    const __m256i ended = _mm256_or_si256(_mm256_cmpeq_epi64(s.current, s.end), _mm256_cmpgt_epi64(smallest, s.limit));
    active = _mm256_andnot_si256(ended, active);
    const __m256i t = _mm256_add_epi64(s.current, shift);
    const __m256i inside = _mm256_and_si256(_mm256_cmpeq_epi64(_mm256_and_si256(t, high), tag), active);
    const __m256i word = _mm256_or_si256(
        _mm256_or_si256(_mm256_and_si256(_mm256_srli_epi64(t, 32), _mm256_set1_epi64x(7)),
                        _mm256_and_si256(t, _mm256_set1_epi64x(0xF8))),
        _mm256_or_si256(_mm256_and_si256(_mm256_srli_epi64(t, 11), _mm256_set1_epi64x(0x1F00)),
                        _mm256_and_si256(_mm256_srli_epi64(t, 22), _mm256_set1_epi64x(0x3E000))));
    const __m256i bit = _mm256_sllv_epi64(
        one, _mm256_or_si256(_mm256_and_si256(t, _mm256_set1_epi64x(7)),
                             _mm256_and_si256(_mm256_srli_epi64(t, 13), _mm256_set1_epi64x(0x38))));
    const __m256i words = _mm256_mask_i64gather_epi64(_mm256_setzero_si256(), bits, word, inside, 8);
    const __m256i seen = _mm256_and_si256(_mm256_cmpeq_epi64(_mm256_and_si256(words, bit), bit), inside);
    const int emit = _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_andnot_si256(seen, active)));
    const __m256i order = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(kCompaction.index[emit]));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + written), _mm256_permutevar8x32_epi32(s.current, order));
    written += static_cast<std::size_t>(kCompaction.count[emit]);
    live = static_cast<unsigned>(_mm256_movemask_pd(_mm256_castsi256_pd(active)));
    if (live != started) break;
  }
  for (int i = 0; i < 3; ++i) {
    scatter(rays, offsetof(RayState, t) + i * sizeof(std::uint64_t), s.t[i]);
    scatter(rays, offsetof(RayState, n) + i * sizeof(std::uint64_t), s.n[i]);
    scatter(rays, offsetof(RayState, c) + i * sizeof(double), s.c[i]);
  }
  scatter(rays, offsetof(RayState, current), s.current);
  return written;
}

RTFUSE_AVX2_END

#else

bool ray_batch_available() noexcept { return false; }

std::size_t step_rays4(RayState*, unsigned& live, const ScanWindow::Probe&, std::uint64_t*, std::size_t) noexcept {
  live = 0;
  return 0;
}

#endif

}  // namespace rtfuse::mapping
