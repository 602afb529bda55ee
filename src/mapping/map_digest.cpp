#include "mapping/map_digest.hpp"

#include "core/xxh64.hpp"

namespace rtfuse::mapping {

namespace {

// A brick's share of the digest: 0 for a brick made but never written (a
// full pool), so it counts as absent.
std::uint64_t brick_digest(const BrickStore& store, const Brick& b) noexcept {
  std::uint32_t values[8 * kSubVoxels];
  bool any = false;
  for (int s = 0; s < 8; ++s) {
    for (int v = 0; v < kSubVoxels; ++v) {
      values[s * kSubVoxels + v] = store.value_bits(b, s, v);
      any |= values[s * kSubVoxels + v] != kUnknownBits;
    }
  }
  if (!any) return 0;
  // Little-endian words on both architectures the digest is compared on.
  Xxh64 h(b.key);
  h.update(values, sizeof values);
  return h.digest();
}

}  // namespace

std::uint64_t map_digest(const OccupancyMap& map) noexcept {
  const BrickStore& store = map.store();
  std::uint64_t sum = 0;
  for (std::uint32_t i = 0; i < store.bricks_used(); ++i) sum += brick_digest(store, store.brick(i));
  return sum;
}

MapDigest::MapDigest(const OccupancyMap& map)
    : brick_digest_(new std::uint64_t[map.store().capacity().bricks]()),
      dirty_(new std::uint32_t[map.store().capacity().bricks]),
      is_dirty_(new std::uint8_t[map.store().capacity().bricks]()) {
  rebuild(map);
}

void MapDigest::note_scan(const OccupancyMap& map) noexcept {
  const std::uint32_t* bricks = map.scan_bricks();
  for (std::uint32_t i = 0; i < map.scan_brick_count(); ++i) {
    const std::uint32_t b = bricks[i];
    if (is_dirty_[b]) continue;
    is_dirty_[b] = 1;
    dirty_[dirty_count_++] = b;
  }
}

std::uint64_t MapDigest::refresh(const OccupancyMap& map) noexcept {
  const BrickStore& store = map.store();
  for (std::uint32_t i = 0; i < dirty_count_; ++i) {
    const std::uint32_t b = dirty_[i];
    is_dirty_[b] = 0;
    // Bricks are made in index order and never moved: one not seen yet
    // starts from nothing.
    while (bricks_ <= b) brick_digest_[bricks_++] = 0;
    const std::uint64_t now = brick_digest(store, store.brick(b));
    sum_ += now - brick_digest_[b];
    brick_digest_[b] = now;
  }
  dirty_count_ = 0;
  return sum_;
}

void MapDigest::rebuild(const OccupancyMap& map) noexcept {
  for (std::uint32_t i = 0; i < dirty_count_; ++i) is_dirty_[dirty_[i]] = 0;
  dirty_count_ = 0;
  bricks_ = 0;
  sum_ = 0;
  for (std::uint32_t i = 0; i < map.store().bricks_used(); ++i) {
    is_dirty_[i] = 1;
    dirty_[dirty_count_++] = i;
  }
  refresh(map);
}

}  // namespace rtfuse::mapping
