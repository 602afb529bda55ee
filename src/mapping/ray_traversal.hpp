#pragma once
// The voxels a ray crosses, exactly as OctoMap's computeRayKeys finds them:
// Amanatides & Woo's 3-D DDA in OctoMap's mix of precisions (a float
// direction normalised by a float length, double step distances, the voxel
// border shifted by a float half-voxel). The voxel of the origin comes
// first, the voxel of the end point is left out, and a ray whose rounding
// makes it miss the end voxel stops once it is longer than the segment:
// all as OctoMap, because equality of the maps is decided here. Any change
// of an operation's precision or order changes which voxels border rays
// cross.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "mapping/map_point.hpp"
#include "mapping/voxel_key.hpp"

namespace rtfuse::mapping {

inline std::uint64_t pack(const VoxelKey& k) noexcept {
  return static_cast<std::uint64_t>(k.k[0]) | static_cast<std::uint64_t>(k.k[1]) << 16 |
         static_cast<std::uint64_t>(k.k[2]) << 32;
}

namespace detail {

inline std::uint64_t bits_of(double x) noexcept {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}
inline double double_of(std::uint64_t b) noexcept {
  double x;
  std::memcpy(&x, &b, sizeof x);
  return x;
}

// OctoMap's incremental phase, verbatim in effect.
template <class Visit>
void traverse_exact(double* t_max, const double* t_delta, const int* step, VoxelKey current, const VoxelKey& key_end,
                    double limit, Visit& visit) {
  for (;;) {
    int dim;
    if (t_max[0] < t_max[1]) {
      dim = t_max[0] < t_max[2] ? 0 : 2;
    } else {
      dim = t_max[1] < t_max[2] ? 1 : 2;
    }
    current.k[dim] = static_cast<std::uint16_t>(current.k[dim] + step[dim]);
    t_max[dim] += t_delta[dim];
    if (current == key_end) return;
    if (std::min(std::min(t_max[0], t_max[1]), t_max[2]) > limit) return;
    visit(current);
  }
}

}  // namespace detail

inline VoxelKey unpack(std::uint64_t packed) noexcept {
  VoxelKey k;
  k.k[0] = static_cast<std::uint16_t>(packed);
  k.k[1] = static_cast<std::uint16_t>(packed >> 16);
  k.k[2] = static_cast<std::uint16_t>(packed >> 32);
  return k;
}

namespace detail {

// The step of the axis chosen (choose()): each axis moves its distance to
// the next sum (t = n), the next to the one after (n = ahead, the bits of
// the sum two steps ahead), sets key_step to its step of the packed key,
// and returns its delta as the addend for the sum ahead (else +0.0). Axis
// 0 steps when lt & lt01, axis 1 when lt & !lt01, axis 2 when !lt.
// On x86-64 these selects are inline asm, one flag test feeding an axis's
// four conditional moves: GCC turns plain ?: of which axis steps back into
// branches, a coin toss the predictor loses about every other voxel.
// Elsewhere plain C.
struct AxisStep {
  std::uint64_t& t;
  std::uint64_t& n;
  std::uint64_t ahead;
  std::uint64_t delta;
  std::uint64_t key;
};

// The moves of a stepping axis, under the flags the caller's test left.
#define RTFUSE_RAY_MOVES(cc) \
  "\n\tcmov" cc " %1, %0\n\tcmov" cc " %6, %1\n\tcmov" cc " %7, %2\n\tcmov" cc " %8, %3"
#define RTFUSE_RAY_OPERANDS                                      \
  : "+r"(a.t), "+r"(a.n), "+r"(add), "+r"(key_step)              \
  : "q"(lt), "q"(lt01), "r"(a.ahead), "rm"(a.delta), "rm"(a.key) \
  : "cc"

inline std::uint64_t step_axis(bool steps, AxisStep a, std::uint64_t& key_step) noexcept {
  if (!steps) return 0;
  a.t = a.n;
  a.n = a.ahead;
  key_step = a.key;
  return a.delta;
}

inline std::uint64_t advance0(AxisStep a, bool lt, bool lt01, std::uint64_t& key_step) noexcept {
#if defined(__x86_64__) && defined(__GNUC__)
  std::uint64_t add = 0;
  __asm__("testb %5, %4" RTFUSE_RAY_MOVES("ne") RTFUSE_RAY_OPERANDS);
  return add;
#else
  return step_axis(lt && lt01, a, key_step);
#endif
}
inline std::uint64_t advance1(AxisStep a, bool lt, bool lt01, std::uint64_t& key_step) noexcept {
#if defined(__x86_64__) && defined(__GNUC__)
  std::uint64_t add = 0;
  __asm__("cmpb %5, %4" RTFUSE_RAY_MOVES("a") RTFUSE_RAY_OPERANDS);  // lt > lt01, as bytes 0 and 1
  return add;
#else
  return step_axis(lt && !lt01, a, key_step);
#endif
}
inline std::uint64_t advance2(AxisStep a, bool lt, bool lt01, std::uint64_t& key_step) noexcept {
#if defined(__x86_64__) && defined(__GNUC__)
  std::uint64_t add = 0;
  __asm__("testb %4, %4" RTFUSE_RAY_MOVES("e") RTFUSE_RAY_OPERANDS);
  return add;
#else
  (void)lt01;
  return step_axis(!lt, a, key_step);
#endif
}
#undef RTFUSE_RAY_OPERANDS
#undef RTFUSE_RAY_MOVES

// The axis OctoMap steps next, t0 < t1 ? (t0 < t2 ? 0 : 2) : (t1 < t2 ? 1
// : 2), as the smaller of t0, t1 (ties to t1) against t2 (ties to t2):
// lt01 = t0 < t1, lt = min01 < t2; returns the smallest distance.
inline std::uint64_t choose(std::uint64_t t0, std::uint64_t t1, std::uint64_t t2, bool& lt01, bool& lt) noexcept {
#if defined(__x86_64__) && defined(__GNUC__)
  std::uint64_t m01 = t1, m = t2;
  __asm__("cmpq %5, %4\n\tcmovb %4, %0\n\tsetb %2\n\tcmpq %6, %0\n\tcmovb %0, %1\n\tsetb %3"
          : "+&r"(m01), "+&r"(m), "=&q"(lt01), "=&q"(lt)
          : "r"(t0), "r"(t1), "r"(t2)
          : "cc");
  return m;
#else
  lt01 = t0 < t1;
  const std::uint64_t m01 = lt01 ? t0 : t1;
  lt = m01 < t2;
  return lt ? m01 : t2;
#endif
}

// Keys this close to the map's edge could step out of their 16 bits, which
// the packed key (one 64-bit word, stepped by one add) would carry into the
// next axis; OctoMap's loop as written takes those rays.
inline bool near_edge(const VoxelKey& k) noexcept {
  for (int i = 0; i < 3; ++i) {
    if (k.k[i] < 2 || k.k[i] > 65533) return true;
  }
  return false;
}

}  // namespace detail

// A ray set up for the branch-free loop below (detail::choose's terms):
// per axis the distance to the next border crossed (t), the one after (n)
// as double bits, the sum two ahead (c), the step's distance (dd, bits) and
// its step of the packed key (k); the packed key now and at the end, and
// the segment's length (bits). ray_batch.hpp runs four of these at once.
struct RayState {
  std::uint64_t t[3];
  std::uint64_t n[3];
  double c[3];
  std::uint64_t dd[3];
  std::uint64_t k[3];
  std::uint64_t current;
  std::uint64_t end;
  std::uint64_t limit;
};

enum class RayStart : std::uint8_t {
  kOutside,  // an end outside the map: nothing to visit
  kEmpty,    // both ends in one voxel: nothing to visit
  kExact,    // the origin's voxel, then OctoMap's loop as written (traverse_exact)
  kFast,     // the origin's voxel, then the loop over a RayState
};

namespace detail {

struct RaySetup {
  VoxelKey key_origin;
  VoxelKey key_end;
  int step[3];
  double t_max[3];
  double t_delta[3];
  double limit;
};

// OctoMap's set-up of computeRayKeys, in its precisions.
inline RayStart set_up_ray(const VoxelGrid& grid, const MapPoint& origin, const MapPoint& end, RaySetup& r) noexcept {
  if (!grid.key_of(origin, r.key_origin) || !grid.key_of(end, r.key_end)) return RayStart::kOutside;
  if (r.key_origin == r.key_end) return RayStart::kEmpty;

  const float dir[3] = {end.x - origin.x, end.y - origin.y, end.z - origin.z};
  const float o[3] = {origin.x, origin.y, origin.z};
  const float norm_sq = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
  const float length = static_cast<float>(std::sqrt(static_cast<double>(norm_sq)));
  float d[3] = {dir[0] / length, dir[1] / length, dir[2] / length};

  const double resolution = grid.resolution();
  for (int i = 0; i < 3; ++i) {
    r.step[i] = d[i] > 0.0f ? 1 : (d[i] < 0.0f ? -1 : 0);
    if (r.step[i] != 0) {
      double border = grid.centre(r.key_origin.k[i]);
      border += static_cast<float>(r.step[i] * resolution * 0.5);
      r.t_max[i] = (border - static_cast<double>(o[i])) / static_cast<double>(d[i]);
      r.t_delta[i] = resolution / static_cast<double>(std::fabs(d[i]));
    } else {
      r.t_max[i] = std::numeric_limits<double>::max();
      r.t_delta[i] = std::numeric_limits<double>::max();
    }
  }
  r.limit = static_cast<double>(length);
  // An origin a rounding away from its voxel's far border (negative
  // distances order differently as integers), or a ray at the map's edge:
  // OctoMap's loop as written.
  if (r.t_max[0] < 0.0 || r.t_max[1] < 0.0 || r.t_max[2] < 0.0 || near_edge(r.key_origin) ||
      near_edge(r.key_end)) {
    return RayStart::kExact;
  }
  return RayStart::kFast;
}

// OctoMap's loop without its branches: which axis steps next is a coin
// toss for the branch predictor, and a mispredicted branch per voxel was
// most of the traversal's time. Non-negative doubles order as their bit
// patterns do, so the comparisons are integer ones feeding conditional
// moves, and each axis's next distance is summed ahead (OctoMap's same
// sum, tMax + tDelta), off the path from one step to the next. An axis
// that does not step adds +0.0, which leaves a non-negative sum as it is.
inline RayState fast_state(const RaySetup& r) noexcept {
  RayState s;
  for (int i = 0; i < 3; ++i) {
    const double a = r.t_max[i] + 0.0;  // + 0.0: -0.0 becomes +0.0
    const double b = a + r.t_delta[i];
    s.t[i] = bits_of(a);
    s.n[i] = bits_of(b);
    s.c[i] = b + r.t_delta[i];  // the sum two steps ahead
    s.dd[i] = bits_of(r.t_delta[i]);
  }
  // A step is one add to the packed key (no field leaves its 16 bits: near_edge).
  s.k[0] = static_cast<std::uint64_t>(static_cast<std::int64_t>(r.step[0]));
  s.k[1] = static_cast<std::uint64_t>(static_cast<std::int64_t>(r.step[1]) * 65536);
  s.k[2] = static_cast<std::uint64_t>(static_cast<std::int64_t>(r.step[2]) * 65536 * 65536);
  s.current = pack(r.key_origin);
  s.end = pack(r.key_end);
  s.limit = bits_of(r.limit);
  return s;
}

}  // namespace detail

// Sets up a ray from origin towards end: what it is, and for kFast its
// state. For kExact and kFast the origin's voxel (pack(key_origin)) is the
// first voxel visited.
inline RayStart start_ray(const VoxelGrid& grid, const MapPoint& origin, const MapPoint& end, RayState& state,
                          detail::RaySetup& setup) noexcept {
  const RayStart kind = detail::set_up_ray(grid, origin, end, setup);
  if (kind == RayStart::kFast) state = detail::fast_state(setup);
  return kind;
}

// The voxels after the origin's of a kFast ray, end's voxel excluded.
template <class Visit>
void run_ray(RayState s, Visit& visit) {
  std::uint64_t t0 = s.t[0], t1 = s.t[1], t2 = s.t[2];
  std::uint64_t n0 = s.n[0], n1 = s.n[1], n2 = s.n[2];
  double c0 = s.c[0], c1 = s.c[1], c2 = s.c[2];
  const std::uint64_t dd0 = s.dd[0], dd1 = s.dd[1], dd2 = s.dd[2];
  const std::uint64_t k0 = s.k[0], k1 = s.k[1], k2 = s.k[2];
  std::uint64_t current = s.current;
  const std::uint64_t end_packed = s.end;
  const std::uint64_t limit_bits = s.limit;
  bool lt01, lt;
  detail::choose(t0, t1, t2, lt01, lt);
  for (;;) {
    std::uint64_t key_step = 0;
    c0 += detail::double_of(detail::advance0({t0, n0, detail::bits_of(c0), dd0, k0}, lt, lt01, key_step));
    c1 += detail::double_of(detail::advance1({t1, n1, detail::bits_of(c1), dd1, k1}, lt, lt01, key_step));
    c2 += detail::double_of(detail::advance2({t2, n2, detail::bits_of(c2), dd2, k2}, lt, lt01, key_step));
    current += key_step;
    if (current == end_packed) break;
    // min(tMax) > length, the minimum being the one the next step takes.
    if (detail::choose(t0, t1, t2, lt01, lt) > limit_bits) break;
    visit(current);
  }
}

// As traverse_ray_packed, but a kFast ray's voxels after the origin's are
// left to run(const RayState&) (run_ray, or another stepper that gives the
// same voxels).
template <class Visit, class Run>
bool traverse_ray_with(const VoxelGrid& grid, const MapPoint& origin, const MapPoint& end, Visit& visit, Run&& run) {
  detail::RaySetup setup;
  RayState state{};
  const RayStart kind = start_ray(grid, origin, end, state, setup);
  if (kind == RayStart::kOutside) return false;
  if (kind == RayStart::kEmpty) return true;
  visit(pack(setup.key_origin));
  if (kind == RayStart::kExact) {
    auto visit_key = [&](const VoxelKey& k) { visit(pack(k)); };
    detail::traverse_exact(setup.t_max, setup.t_delta, setup.step, setup.key_origin, setup.key_end, setup.limit,
                           visit_key);
    return true;
  }
  run(state);
  return true;
}

// Calls visit(std::uint64_t packed_key) (pack()) for each voxel from origin
// towards end, end's voxel excluded. False (nothing visited) when either
// point is outside the map. The number of voxels is bounded by the
// segment's length over the resolution (at most three steps per voxel
// length).
template <class Visit>
bool traverse_ray_packed(const VoxelGrid& grid, const MapPoint& origin, const MapPoint& end, Visit&& visit) {
  return traverse_ray_with(grid, origin, end, visit, [&](const RayState& state) { run_ray(state, visit); });
}

// As traverse_ray_packed, calling visit(const VoxelKey&).
template <class Visit>
bool traverse_ray(const VoxelGrid& grid, const MapPoint& origin, const MapPoint& end, Visit&& visit) {
  return traverse_ray_packed(grid, origin, end, [&](std::uint64_t packed) { visit(unpack(packed)); });
}

}  // namespace rtfuse::mapping
