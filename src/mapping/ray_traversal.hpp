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

// Calls visit(const VoxelKey&) for each voxel from origin towards end, end's
// voxel excluded. False (nothing visited) when either point is outside the
// map. The number of voxels is bounded by the segment's length over the
// resolution (at most three steps per voxel length).
template <class Visit>
bool traverse_ray(const VoxelGrid& grid, const MapPoint& origin, const MapPoint& end, Visit&& visit) {
  VoxelKey key_origin, key_end;
  if (!grid.key_of(origin, key_origin) || !grid.key_of(end, key_end)) return false;
  if (key_origin == key_end) return true;
  visit(key_origin);

  const float dir[3] = {end.x - origin.x, end.y - origin.y, end.z - origin.z};
  const float o[3] = {origin.x, origin.y, origin.z};
  const float norm_sq = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
  const float length = static_cast<float>(std::sqrt(static_cast<double>(norm_sq)));
  float d[3] = {dir[0] / length, dir[1] / length, dir[2] / length};

  const double resolution = grid.resolution();
  int step[3];
  double t_max[3];
  double t_delta[3];
  VoxelKey current = key_origin;
  for (int i = 0; i < 3; ++i) {
    step[i] = d[i] > 0.0f ? 1 : (d[i] < 0.0f ? -1 : 0);
    if (step[i] != 0) {
      double border = grid.centre(current.k[i]);
      border += static_cast<float>(step[i] * resolution * 0.5);
      t_max[i] = (border - static_cast<double>(o[i])) / static_cast<double>(d[i]);
      t_delta[i] = resolution / static_cast<double>(std::fabs(d[i]));
    } else {
      t_max[i] = std::numeric_limits<double>::max();
      t_delta[i] = std::numeric_limits<double>::max();
    }
  }

  const double limit = static_cast<double>(length);
  if (t_max[0] < 0.0 || t_max[1] < 0.0 || t_max[2] < 0.0) {
    // An origin a rounding away from its voxel's far border: OctoMap's loop
    // as written, for negative distances order differently as integers.
    detail::traverse_exact(t_max, t_delta, step, current, key_end, limit, visit);
    return true;
  }
  // OctoMap's loop without its branches: which axis steps next is a coin
  // toss for the branch predictor, and a mispredicted branch per voxel was
  // most of the traversal's time. Non-negative doubles order as their bit
  // patterns do, so the comparisons are integer ones feeding conditional
  // moves, and each axis's next distance is summed ahead (OctoMap's same
  // sum, tMax + tDelta), off the path from one step to the next.
  const double d0 = t_delta[0], d1 = t_delta[1], d2 = t_delta[2];
  double a0 = t_max[0] + 0.0, a1 = t_max[1] + 0.0, a2 = t_max[2] + 0.0;  // + 0.0: -0.0 becomes +0.0
  double b0 = a0 + d0, b1 = a1 + d1, b2 = a2 + d2;
  std::uint64_t t0 = detail::bits_of(a0), t1 = detail::bits_of(a1), t2 = detail::bits_of(a2);
  std::uint64_t n0 = detail::bits_of(b0), n1 = detail::bits_of(b1), n2 = detail::bits_of(b2);
  double c0 = b0 + d0, c1 = b1 + d1, c2 = b2 + d2;  // the sums two steps ahead
  const std::uint64_t end_packed = pack(key_end);
  const std::uint64_t limit_bits = detail::bits_of(limit);
  for (;;) {
    const bool lt01 = t0 < t1;
    const bool s0 = lt01 & (t0 < t2);
    const bool s1 = !lt01 & (t1 < t2);
    const bool s2 = !(s0 | s1);
    const std::uint64_t m0 = detail::bits_of(c0), m1 = detail::bits_of(c1), m2 = detail::bits_of(c2);
    t0 = s0 ? n0 : t0;
    t1 = s1 ? n1 : t1;
    t2 = s2 ? n2 : t2;
    n0 = s0 ? m0 : n0;
    n1 = s1 ? m1 : n1;
    n2 = s2 ? m2 : n2;
    c0 = s0 ? c0 + d0 : c0;
    c1 = s1 ? c1 + d1 : c1;
    c2 = s2 ? c2 + d2 : c2;
    current.k[0] = static_cast<std::uint16_t>(current.k[0] + (s0 ? step[0] : 0));
    current.k[1] = static_cast<std::uint16_t>(current.k[1] + (s1 ? step[1] : 0));
    current.k[2] = static_cast<std::uint16_t>(current.k[2] + (s2 ? step[2] : 0));
    if (pack(current) == end_packed) break;
    if (std::min(std::min(t0, t1), t2) > limit_bits) break;
    visit(current);
  }
  return true;
}

}  // namespace rtfuse::mapping
