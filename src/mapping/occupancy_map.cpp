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
    std::uint64_t& touched = b.touched[touched_word(key)];
    const std::uint64_t touched_bit = std::uint64_t{1} << touched_bit_of(key);
    if (touched & touched_bit) return;
    const int s = sub_of(key);
    const int v = voxel_of(key);
    std::uint32_t slot = b.sub[s];
    if (!is_dense(slot)) {
      const std::uint32_t block = map_.store_.new_block(slot);
      if (block == kNone) {
        ++dropped_;
        return;
      }
      slot = b.sub[s] = dense_slot(block);
    }
    touched |= touched_bit;
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

  // A brick's touched mask and the packed keys (pack()) of its voxels with
  // the low three bits of every axis cleared; base never matches a key
  // when there is no brick.
  struct TouchedBrick {
    std::uint64_t base;
    const std::uint64_t* touched;
  };
  static constexpr std::uint64_t kBrickBits = 0x0000FFF8FFF8FFF8ull;

  // A free voxel of a ray whose brick the recent table missed or whose bit
  // is not set: the update, and the brick for the table. Out of line so
  // the ray loop keeps its registers.
  [[gnu::noinline]] TouchedBrick free_slow(std::uint64_t packed, std::uint32_t& counter) noexcept {
    update(unpack(packed), map_.log_odds_.miss, counter);
    if (cached_key_ == kNoBrick) return TouchedBrick{~std::uint64_t{0}, nullptr};
    return TouchedBrick{packed & kBrickBits, map_.store_.brick(cached_).touched};
  }

  std::uint32_t dropped() const noexcept { return dropped_; }

 private:
  OccupancyMap& map_;
  std::uint64_t cached_key_ = kNoBrick;
  std::uint32_t cached_ = kNone;
  std::uint32_t dropped_ = 0;
};

namespace {

constexpr int kRecentBricks = 256;

// The recent-brick slot of a packed key: the brick coordinates' low bits
// (x and y three, z two) gathered by one multiply into the top byte; the
// other partial products stay below bit 49.
inline std::size_t recent_slot(std::uint64_t packed) noexcept {
  constexpr std::uint64_t kLowBrickBits = std::uint64_t{7} << 3 | std::uint64_t{7} << 19 | std::uint64_t{3} << 35;
  constexpr std::uint64_t kGather = std::uint64_t{1} << 53 | std::uint64_t{1} << 40 | std::uint64_t{1} << 27;
  return static_cast<std::size_t>(((packed & kLowBrickBits) * kGather) >> 56);
}

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

  // Most voxels of a ray were freed by an earlier ray of the scan (6 M
  // visits for 0.3 M voxels on scan.dat at 0.1 m within 10 m), and a ray
  // changes brick every seven voxels or so, at a coin toss, mostly to one
  // an earlier ray used. So a visit is checked against a small
  // direct-mapped table of the scan's bricks (any 8 x 8 x 4 of them fit),
  // with no branch on a brick change; only a miss or a new voxel takes the
  // call and the brick hash table, whose slots are spread over megabytes.
  std::uint64_t recent_base[kRecentBricks];
  const std::uint64_t* recent_touched[kRecentBricks];
  for (int i = 0; i < kRecentBricks; ++i) {
    recent_base[i] = ~std::uint64_t{0};
    recent_touched[i] = nullptr;
  }
  const auto free = [&](std::uint64_t packed) __attribute__((always_inline)) {
    const std::uint64_t base = packed & ScanWriter::kBrickBits;
    const std::size_t slot = recent_slot(packed);
    if (recent_base[slot] == base &&
        (recent_touched[slot][packed >> 32 & 7] >> ((packed & 7) | (packed >> 13 & 0x38)) & 1) != 0) {
      return;
    }
    const ScanWriter::TouchedBrick brick = writer.free_slow(packed, result.frees);
    recent_base[slot] = brick.base;
    recent_touched[slot] = brick.touched;
  };
  const float range = static_cast<float>(max_range);
  for (std::size_t i = 0; i < count; ++i) {
    const MapPoint& p = points[i];
    if (!is_finite(p)) continue;
    const Offset d = offset_of(p, origin);
    if (!limited || d.length <= max_range) {
      traverse_ray_packed(grid_, origin, p, free);
      continue;
    }
    ++result.beyond_range;
    // OctoMap's (p - origin).normalized() * (float)max_range + origin.
    const float length = static_cast<float>(d.length);
    const MapPoint end{origin.x + (d.x / length) * range, origin.y + (d.y / length) * range,
                       origin.z + (d.z / length) * range};
    if (!traverse_ray_packed(grid_, origin, end, free)) ++result.outside;
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
      if (!is_dense(b.sub[s])) continue;
      // The sub-brick's 4 x 4 x 4 corner of the brick's z-slices.
      const std::uint64_t quadrant = std::uint64_t{0x0F0F0F0F} << ((s & 1) * 4 + (s >> 1 & 1) * 32);
      const std::uint64_t* slices = &b.touched[(s >> 2) * 4];
      if (((slices[0] | slices[1] | slices[2] | slices[3]) & quadrant) == 0) continue;
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
}

}  // namespace rtfuse::mapping
