#pragma once
// Where the occupancy map keeps its voxels: a fixed pool, sized once, of
// bricks of 8x8x8 voxels found through an open-addressed hash of their
// coordinates, each brick made of eight 4x4x4 sub-bricks. A sub-brick whose
// 64 voxels hold one value (free space seen by a whole scan, a wall's
// inside) is stored as that value in the brick; only the others own a dense
// block of 64 values from a second pool. That is OctoMap's pruning, at a
// fixed granularity and without pointers: OctoMap spends 16 bytes per leaf
// and 80 per inner node, a brick 112 bytes per 512 voxels and a dense block
// 4 bytes a voxel.
//
// A value is a float32 log-odds, or, as a slot in a brick, one of two NaN
// patterns no log-odds can take: "unknown" or "dense block n". Nothing is
// allocated after construction; a full pool refuses (kNone) and the caller
// counts it.
#include <cstdint>
#include <cstring>
#include <memory>

#include "mapping/voxel_key.hpp"

namespace rtfuse::mapping {

inline constexpr std::uint32_t kUnknownBits = 0xFFFFFFFFu;
inline constexpr std::uint32_t kNone = 0xFFFFFFFFu;
inline constexpr std::uint64_t kNoBrick = ~std::uint64_t{0};

inline constexpr int kBrickShift = 3;  // 8 voxels a side
inline constexpr int kSubShift = 2;    // 4 voxels a side
inline constexpr int kSubVoxels = 64;

struct Brick {
  std::uint64_t key;           // brick coordinates, 13 bits each (brick_key_of)
  std::uint32_t sub[8];        // a value, kUnknownBits or dense_slot(block)
  std::uint32_t scan;          // the scan touched[] belongs to
  std::uint32_t reserved;
  std::uint64_t touched[8];    // voxels updated in that scan: touched_word, touched_bit_of
};

// A voxel's bit in Brick::touched: one word a z-slice, x then y in it, so
// the bit comes from a packed key (pack()) in a few shifts and masks.
inline int touched_word(const VoxelKey& k) noexcept { return k.k[2] & 7; }
inline int touched_bit_of(const VoxelKey& k) noexcept { return (k.k[0] & 7) | (k.k[1] & 7) << 3; }

inline std::uint64_t brick_key_of(const VoxelKey& k) noexcept {
  return static_cast<std::uint64_t>(k.k[0] >> kBrickShift) |
         static_cast<std::uint64_t>(k.k[1] >> kBrickShift) << 13 |
         static_cast<std::uint64_t>(k.k[2] >> kBrickShift) << 26;
}
inline int sub_of(const VoxelKey& k) noexcept {
  return (k.k[0] >> kSubShift & 1) | (k.k[1] >> kSubShift & 1) << 1 | (k.k[2] >> kSubShift & 1) << 2;
}
inline int voxel_of(const VoxelKey& k) noexcept { return (k.k[0] & 3) | (k.k[1] & 3) << 2 | (k.k[2] & 3) << 4; }

// A dense block's number in a slot: a NaN with the block number + 1 as payload.
inline constexpr std::uint32_t dense_slot(std::uint32_t block) noexcept { return 0x7F800000u | (block + 1u); }
inline constexpr bool is_dense(std::uint32_t slot) noexcept {
  return (slot & 0xFF800000u) == 0x7F800000u && (slot & 0x007FFFFFu) != 0u;
}
inline constexpr std::uint32_t block_of(std::uint32_t slot) noexcept { return (slot & 0x007FFFFFu) - 1u; }
inline constexpr std::uint32_t kMaxDenseBlocks = 0x007FFFFEu;

struct BrickCapacity {
  std::uint32_t bricks = 0;
  std::uint32_t dense_blocks = 0;
};

// A pool of about `bytes`: an eighth for bricks (with their share of the
// hash table), the rest for dense blocks, the split OctoMap's real scans
// need (about six dense blocks a brick, tests/reference).
BrickCapacity capacity_for_bytes(std::size_t bytes) noexcept;

class BrickStore {
 public:
  explicit BrickStore(BrickCapacity capacity);

  // The brick of a key, or kNone.
  std::uint32_t find(std::uint64_t key) const noexcept {
    for (std::uint32_t h = hash(key);; h = (h + 1) & mask_) {
      const std::uint32_t entry = table_[h];
      if (entry == 0) return kNone;
      if (bricks_[entry - 1].key == key) return entry - 1;
    }
  }
  // The brick of a key, a new all-unknown one if there was none, or kNone
  // when the pool is full.
  std::uint32_t find_or_add(std::uint64_t key) noexcept {
    std::uint32_t h = hash(key);
    for (;; h = (h + 1) & mask_) {
      const std::uint32_t entry = table_[h];
      if (entry == 0) break;
      if (bricks_[entry - 1].key == key) return entry - 1;
    }
    if (used_bricks_ == capacity_.bricks) return kNone;
    const std::uint32_t index = used_bricks_++;
    Brick& b = bricks_[index];
    b.key = key;
    for (std::uint32_t& s : b.sub) s = kUnknownBits;
    b.scan = 0;
    b.reserved = 0;
    std::memset(b.touched, 0, sizeof b.touched);
    table_[h] = index + 1;
    return index;
  }

  // A dense block holding fill in every voxel, or kNone when the pool is full.
  std::uint32_t new_block(std::uint32_t fill) noexcept {
    if (free_count_ == 0) return kNone;
    const std::uint32_t block = free_[--free_count_];
    std::uint32_t* v = block_values(block);
    for (int i = 0; i < kSubVoxels; ++i) v[i] = fill;
    return block;
  }
  void release_block(std::uint32_t block) noexcept { free_[free_count_++] = block; }

  Brick& brick(std::uint32_t index) noexcept { return bricks_[index]; }
  const Brick& brick(std::uint32_t index) const noexcept { return bricks_[index]; }
  std::uint32_t* block_values(std::uint32_t block) noexcept { return &blocks_[std::size_t{block} * kSubVoxels]; }
  const std::uint32_t* block_values(std::uint32_t block) const noexcept {
    return &blocks_[std::size_t{block} * kSubVoxels];
  }

  // The value of voxel v (voxel_of) of sub-brick s of a brick.
  std::uint32_t value_bits(const Brick& b, int s, int v) const noexcept {
    const std::uint32_t slot = b.sub[s];
    return is_dense(slot) ? block_values(block_of(slot))[v] : slot;
  }

  std::uint32_t bricks_used() const noexcept { return used_bricks_; }
  std::uint32_t blocks_used() const noexcept { return capacity_.dense_blocks - free_count_; }
  const BrickCapacity& capacity() const noexcept { return capacity_; }

  // What the stored map occupies: the bricks and dense blocks in use and
  // their share of the hash table (two slots a brick: the table is sized
  // with the pool, at most half full). Comparable with OctoMap's
  // memoryUsage(), which counts the nodes in use.
  std::size_t bytes_used() const noexcept;
  // What the pool reserved at construction.
  std::size_t bytes_reserved() const noexcept;

  // Forgets every voxel (the pool stays).
  void clear() noexcept;
  // Writes every page of the pool once, so the memory is resident from
  // start-up (a daemon's resident size then stays flat while the map grows,
  // and no page fault lands in a keyframe). Keeps the map.
  void prefault() noexcept;

 private:
  std::uint32_t hash(std::uint64_t key) const noexcept {
    return static_cast<std::uint32_t>((key * 0x9E3779B97F4A7C15ull) >> hash_shift_);
  }

  BrickCapacity capacity_;
  std::uint32_t mask_ = 0;
  int hash_shift_ = 64;
  std::uint32_t used_bricks_ = 0;
  std::uint32_t free_count_ = 0;
  std::unique_ptr<Brick[]> bricks_;
  std::unique_ptr<std::uint32_t[]> table_;  // brick index + 1, 0 = empty
  std::unique_ptr<std::uint32_t[]> blocks_;
  std::unique_ptr<std::uint32_t[]> free_;   // free dense blocks, a stack
};

}  // namespace rtfuse::mapping
