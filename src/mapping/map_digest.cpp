#include "mapping/map_digest.hpp"

#include "core/xxh64.hpp"

namespace rtfuse::mapping {

std::uint64_t map_digest(const OccupancyMap& map) noexcept {
  const BrickStore& store = map.store();
  std::uint64_t sum = 0;
  std::uint32_t values[8 * kSubVoxels];
  for (std::uint32_t i = 0; i < store.bricks_used(); ++i) {
    const Brick& b = store.brick(i);
    bool any = false;
    for (int s = 0; s < 8; ++s) {
      for (int v = 0; v < kSubVoxels; ++v) {
        values[s * kSubVoxels + v] = store.value_bits(b, s, v);
        any |= values[s * kSubVoxels + v] != kUnknownBits;
      }
    }
    if (!any) continue;  // a brick made but never written (a full pool)
    // Little-endian words on both architectures the digest is compared on.
    Xxh64 h(b.key);
    h.update(values, sizeof values);
    sum += h.digest();
  }
  return sum;
}

}  // namespace rtfuse::mapping
