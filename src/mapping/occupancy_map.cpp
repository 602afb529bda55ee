#include "mapping/occupancy_map.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "mapping/ray_batch.hpp"
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
      begin_brick(cached_);
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
        // Counted once: the voxel is done for this scan, so a hit lost here
        // is not freed by a ray later in it either.
        touched |= touched_bit;
        ++dropped_;
        return;
      }
      slot = b.sub[s] = dense_slot(block);
    }
    touched |= touched_bit;
    add(map_.store_.block_values(block_of(slot))[v], delta, 1);
    ++counter;
  }

  // The voxels of a brick the scan's cube visited (ScanWindow), freed but
  // for those the hits took: a sub-brick freed whole that holds one value
  // gets the new value as one, the others a dense block as update() does.
  void free_brick(std::uint64_t brick_key, const std::uint64_t* visited, std::uint32_t& counter) noexcept {
    const std::uint32_t index = map_.store_.find_or_add(brick_key);
    if (index == kNone) {
      for (int z = 0; z < 8; ++z) dropped_ += static_cast<std::uint32_t>(__builtin_popcountll(visited[z]));
      return;
    }
    Brick& b = begin_brick(index);
    std::uint64_t frees[8];
    for (int z = 0; z < 8; ++z) {
      frees[z] = visited[z] & ~b.touched[z];
      b.touched[z] |= visited[z];
    }
    const float miss = map_.log_odds_.miss;
    for (int s = 0; s < 8; ++s) {
      // The sub-brick's 4 x 4 corner of each of its four z-slices.
      const std::uint64_t quadrant = std::uint64_t{0x0F0F0F0F} << ((s & 1) * 4 + (s >> 1 & 1) * 32);
      const std::uint64_t* slices = &frees[(s >> 2) * 4];
      const std::uint64_t q0 = slices[0] & quadrant, q1 = slices[1] & quadrant, q2 = slices[2] & quadrant,
                          q3 = slices[3] & quadrant;
      if ((q0 | q1 | q2 | q3) == 0) continue;
      std::uint32_t slot = b.sub[s];
      if (!is_dense(slot) && (q0 & q1 & q2 & q3) == quadrant) {
        add(b.sub[s], miss, kSubVoxels);
        counter += kSubVoxels;
        continue;
      }
      const std::uint32_t count = static_cast<std::uint32_t>(__builtin_popcountll(q0) + __builtin_popcountll(q1) +
                                                             __builtin_popcountll(q2) + __builtin_popcountll(q3));
      if (!is_dense(slot)) {
        const std::uint32_t block = map_.store_.new_block(slot);
        if (block == kNone) {
          dropped_ += count;
          continue;
        }
        slot = b.sub[s] = dense_slot(block);
      }
      std::uint32_t* values = map_.store_.block_values(block_of(slot));
      const std::uint64_t q[4] = {q0, q1, q2, q3};
      for (int j = 0; j < 4; ++j) {
        for (std::uint64_t m = q[j]; m != 0; m &= m - 1) {
          const int bit = __builtin_ctzll(m);  // x & 7 | (y & 7) << 3
          add(values[(bit & 3) | (bit >> 3 & 3) << 2 | j << 4], miss, 1);
        }
      }
      counter += count;
    }
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
  // A brick this scan writes: its mask of updated voxels starts empty (a
  // stamp says whether it already belongs to this scan) and it joins the
  // list of the scan's bricks.
  Brick& begin_brick(std::uint32_t index) noexcept {
    Brick& b = map_.store_.brick(index);
    if (b.scan != map_.scan_) {
      b.scan = map_.scan_;
      std::memset(b.touched, 0, sizeof b.touched);
      map_.touched_[map_.touched_count_++] = index;
    }
    return b;
  }

  // OctoMap's updateNodeLogOdds on a stored value (a voxel's, or a uniform
  // sub-brick's standing for `voxels` of them): add, then clamp.
  void add(std::uint32_t& cell, float delta, std::uint32_t voxels) noexcept {
    const bool was_known = cell != kUnknownBits;
    float value = was_known ? float_of(cell) : 0.0f;
    const bool was_occupied = was_known && value >= map_.log_odds_.occupied;
    value += delta;
    if (value < map_.log_odds_.clamp_min) {
      value = map_.log_odds_.clamp_min;
    } else if (value > map_.log_odds_.clamp_max) {
      value = map_.log_odds_.clamp_max;
    }
    std::memcpy(&cell, &value, sizeof cell);
    map_.known_ += was_known ? 0 : voxels;
    const bool occupied = value >= map_.log_odds_.occupied;
    if (occupied != was_occupied) {
      if (occupied) {
        map_.occupied_ += voxels;
      } else {
        map_.occupied_ -= voxels;
      }
    }
  }

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

  VoxelKey origin_key;
  if (grid_.key_of(origin, origin_key)) window_.begin(origin_key);
  const ScanWindow::Probe window = window_.probe();

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
      window.visit(pack(key));  // so that no ray frees it
    } else {
      ++result.outside;
    }
  }

  // Voxels beyond the window (rays without a range limit) are applied at
  // once. Most of them too were visited by an earlier ray of the scan, and
  // a ray changes brick every seven voxels or so, at a coin toss, mostly to
  // one an earlier ray used. So such a visit is checked against a small
  // direct-mapped table of the scan's bricks (any 8 x 8 x 4 of them fit),
  // with no branch on a brick change; only a miss or a new voxel takes the
  // call and the brick hash table, whose slots are spread over megabytes.
  std::uint64_t recent_base[kRecentBricks];
  const std::uint64_t* recent_touched[kRecentBricks];
  for (int i = 0; i < kRecentBricks; ++i) {
    recent_base[i] = ~std::uint64_t{0};
    recent_touched[i] = nullptr;
  }
  const auto check = [&](std::uint64_t packed) {
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
  // The rays' loop only collects their voxels; the checks run over them in
  // a loop of their own. Together in one loop they had more live values
  // than registers, and every step paid spills.
  constexpr std::size_t kKeyBuffer = 2048;
  std::uint64_t keys[kKeyBuffer];
  std::size_t pending = 0;
  const auto flush = [&]() {
    const ScanWindow::Probe near = window;  // in registers: the stores below may not alias a local
    for (std::size_t k = 0; k < pending; ++k) {
      const std::uint64_t key = keys[k];
      if (!near.visit(key)) check(key);
    }
    pending = 0;
  };
  const auto free = [&](std::uint64_t packed) __attribute__((always_inline)) {
    keys[pending] = packed;
    if (++pending == kKeyBuffer) flush();
  };
  // kFast rays go four at a time through the AVX2 lanes where there are
  // some (ray_batch.hpp); a lane whose ray ends takes the next one.
  const bool batch = ray_batch_available();
  RayState lanes[4] = {};
  unsigned live = 0;
  const auto cast = [&](const MapPoint& end) -> bool {
    return traverse_ray_with(grid_, origin, end, free, [&](const RayState& state) {
      if (!batch) {
        run_ray(state, free);
        return;
      }
      const int lane = __builtin_ctz(~live & 15u);
      lanes[lane] = state;
      live |= 1u << lane;
      while (live == 15u) {
        if (pending + 4 > kKeyBuffer) flush();
        pending += step_rays4(lanes, live, window, keys + pending, kKeyBuffer - pending);
      }
    });
  };
  const float range = static_cast<float>(max_range);
  for (std::size_t i = 0; i < count; ++i) {
    const MapPoint& p = points[i];
    if (!is_finite(p)) continue;
    const Offset d = offset_of(p, origin);
    if (pending > kKeyBuffer / 2) flush();
    if (!limited || d.length <= max_range) {
      cast(p);
      continue;
    }
    ++result.beyond_range;
    // OctoMap's (p - origin).normalized() * (float)max_range + origin.
    const float length = static_cast<float>(d.length);
    const MapPoint end{origin.x + (d.x / length) * range, origin.y + (d.y / length) * range,
                       origin.z + (d.z / length) * range};
    if (!cast(end)) ++result.outside;
  }
  while (live != 0) {
    if (pending + 4 > kKeyBuffer) flush();
    pending += step_rays4(lanes, live, window, keys + pending, kKeyBuffer - pending);
  }
  flush();
  window_.drain([&](std::uint64_t brick_key, const std::uint64_t* visited) {
    writer.free_brick(brick_key, visited, result.frees);
  });
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
