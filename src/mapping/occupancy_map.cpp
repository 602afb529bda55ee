#include "mapping/occupancy_map.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "mapping/ray_traversal.hpp"

namespace rtfuse::mapping {

OccupancyMap::OccupancyMap(const OccupancyParams& params, BrickCapacity capacity)
    : params_(params), log_odds_(log_odds_of(params)), grid_(params.resolution), store_(capacity) {
  const std::string fault = check(params);
  if (!fault.empty()) throw std::invalid_argument("occupancy map: " + fault);
  touched_.reset(new std::uint32_t[capacity.bricks]);
}

void OccupancyMap::clear() noexcept {
  store_.clear();
  touched_count_ = 0;
  scan_ = 0;
  scans_ = known_ = occupied_ = dropped_ = 0;
}

bool OccupancyMap::log_odds(const VoxelKey& key, float& value) const noexcept {
  const std::uint32_t index = store_.find(brick_key_of(key));
  if (index == kNone) return false;
  const std::uint32_t bits = store_.value_bits(store_.brick(index), sub_of(key), voxel_of(key));
  if (bits == kUnknownBits) return false;
  value = float_of(bits);
  return true;
}

// Applies one scan's updates, remembering the last brick: consecutive voxels
// of a ray mostly share one, so most updates skip the hash.
class OccupancyMap::ScanWriter {
 public:
  explicit ScanWriter(OccupancyMap& map) noexcept : map_(map) {}

  // Inlined into the ray loop: a call per voxel cost a tenth of the scan.
  [[gnu::always_inline]] void update(const VoxelKey& key, float delta, std::uint32_t& counter) noexcept {
    const std::uint64_t brick_key = brick_key_of(key);
    if (brick_key != cached_key_) {
      cached_key_ = brick_key;
      cached_ = map_.store_.find_or_add(brick_key);
      if (cached_ == kNone) {
        cached_key_ = kNoBrick;
        ++dropped_;
        return;
      }
      Brick& b = map_.store_.brick(cached_);
      if (b.scan != map_.scan_) {
        b.scan = map_.scan_;
        std::memset(b.touched, 0, sizeof b.touched);
        map_.touched_[map_.touched_count_++] = cached_;
      }
    }
    Brick& b = map_.store_.brick(cached_);
    const int s = sub_of(key);
    const int v = voxel_of(key);
    const std::uint64_t bit = std::uint64_t{1} << v;
    if (b.touched[s] & bit) return;
    std::uint32_t slot = b.sub[s];
    if (!is_dense(slot)) {
      const std::uint32_t block = map_.store_.new_block(slot);
      if (block == kNone) {
        ++dropped_;
        return;
      }
      slot = b.sub[s] = dense_slot(block);
    }
    b.touched[s] |= bit;
    std::uint32_t& cell = map_.store_.block_values(block_of(slot))[v];
    const bool was_known = cell != kUnknownBits;
    float value = was_known ? float_of(cell) : 0.0f;
    const bool was_occupied = was_known && value >= map_.log_odds_.occupied;
    // OctoMap's updateNodeLogOdds: add, then clamp.
    value += delta;
    if (value < map_.log_odds_.clamp_min) {
      value = map_.log_odds_.clamp_min;
    } else if (value > map_.log_odds_.clamp_max) {
      value = map_.log_odds_.clamp_max;
    }
    std::memcpy(&cell, &value, sizeof cell);
    map_.known_ += was_known ? 0 : 1;
    const bool occupied = value >= map_.log_odds_.occupied;
    if (occupied != was_occupied) {
      if (occupied) {
        ++map_.occupied_;
      } else {
        --map_.occupied_;
      }
    }
    ++counter;
  }

  std::uint32_t dropped() const noexcept { return dropped_; }

 private:
  OccupancyMap& map_;
  std::uint64_t cached_key_ = kNoBrick;
  std::uint32_t cached_ = kNone;
  std::uint32_t dropped_ = 0;
};

namespace {

struct Offset {
  float x, y, z;
  double length;
};

// p - origin and its length as OctoMap's Vector3 computes them (float
// components, a float sum of squares, a double root).
Offset offset_of(const MapPoint& p, const MapPoint& origin) noexcept {
  Offset d{p.x - origin.x, p.y - origin.y, p.z - origin.z, 0.0};
  d.length = std::sqrt(static_cast<double>(d.x * d.x + d.y * d.y + d.z * d.z));
  return d;
}

}  // namespace

ScanResult OccupancyMap::insert_scan(const MapPoint* points, std::size_t count, const MapPoint& origin,
                                     double max_range) {
  ScanResult result;
  result.points = static_cast<std::uint32_t>(count);
  if (++scan_ == 0) {
    // 2^32 scans later: forget the stamps so an old one cannot match.
    for (std::uint32_t i = 0; i < store_.bricks_used(); ++i) store_.brick(i).scan = 0;
    scan_ = 1;
  }
  ++scans_;
  touched_count_ = 0;
  ScanWriter writer(*this);
  const bool limited = max_range >= 0.0;
  if (!is_finite(origin)) {
    // A pose that is not a pose (a NaN from upstream): the whole scan is
    // refused, so no ray is cast from nowhere.
    result.rejected = result.points;
    return result;
  }

  // Hits first, so the rays below find them marked and leave them alone.
  for (std::size_t i = 0; i < count; ++i) {
    const MapPoint& p = points[i];
    if (!is_finite(p)) {
      ++result.rejected;
      continue;
    }
    if (limited && !(offset_of(p, origin).length <= max_range)) continue;
    VoxelKey key;
    if (grid_.key_of(p, key)) {
      writer.update(key, log_odds_.hit, result.hits);
    } else {
      ++result.outside;
    }
  }

  const auto free = [&](const VoxelKey& key) __attribute__((always_inline)) {
    writer.update(key, log_odds_.miss, result.frees);
  };
  const float range = static_cast<float>(max_range);
  for (std::size_t i = 0; i < count; ++i) {
    const MapPoint& p = points[i];
    if (!is_finite(p)) continue;
    const Offset d = offset_of(p, origin);
    if (!limited || d.length <= max_range) {
      traverse_ray(grid_, origin, p, free);
      continue;
    }
    ++result.beyond_range;
    // OctoMap's (p - origin).normalized() * (float)max_range + origin.
    const float length = static_cast<float>(d.length);
    const MapPoint end{origin.x + (d.x / length) * range, origin.y + (d.y / length) * range,
                       origin.z + (d.z / length) * range};
    if (!traverse_ray(grid_, origin, end, free)) ++result.outside;
  }

  result.dropped = writer.dropped();
  dropped_ += result.dropped;
  compact_touched();
  return result;
}

// A sub-brick the scan left holding one known value gives its block back:
// the free space of one scan is mostly such sub-bricks.
void OccupancyMap::compact_touched() noexcept {
  for (std::uint32_t t = 0; t < touched_count_; ++t) {
    Brick& b = store_.brick(touched_[t]);
    for (int s = 0; s < 8; ++s) {
      if (b.touched[s] == 0 || !is_dense(b.sub[s])) continue;
      const std::uint32_t block = block_of(b.sub[s]);
      const std::uint32_t* v = store_.block_values(block);
      const std::uint32_t first = v[0];
      if (first == kUnknownBits) continue;
      bool uniform = true;
      for (int i = 1; i < kSubVoxels && uniform; ++i) uniform = v[i] == first;
      if (!uniform) continue;
      b.sub[s] = first;
      store_.release_block(block);
    }
  }
  touched_count_ = 0;
}

}  // namespace rtfuse::mapping
