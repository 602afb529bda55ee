#pragma once
// The voxels one scan's rays visited near the sensor, one bit each, in a
// 256-voxel cube around the origin: the "already seen in this scan" test
// of the ray loop as one add, one compare and one bit, where the brick
// table costs a hash and its megabytes of slots. Most of a scan's visits
// are voxels an earlier ray of it already visited (6 M visits for 0.3 M
// voxels on OctoMap's scan.dat at 0.1 m within 10 m), so this test is the
// loop's second half. The visited voxels are updated afterwards brick by
// brick (OccupancyMap): a 4 x 4 x 4 sub-brick the scan freed whole keeps
// one value instead of taking a dense block and giving it back.
//
// The cube is laid out as the map's bricks (eight 64-bit z-slices of x, y
// bits), so a window brick is a map brick's touched mask. Keys are shifted
// by a multiple of 8 per axis that puts the origin's voxel at 121 to 128 in
// the cube's 256, so the cube holds at least 121 voxels on every side of it
// (6 m at 0.05 m, 12 m at 0.1 m); a voxel outside says so and takes the
// brick table instead. Whether a key is inside is decided exactly (the
// high byte of each shifted axis), never assumed from the range.
#include <cstddef>
#include <cstdint>
#include <memory>

#include "mapping/brick_store.hpp"
#include "mapping/voxel_key.hpp"

namespace rtfuse::mapping {

class ScanWindow {
 public:
  static constexpr int kBricksPerAxis = 32;  // 256 voxels
  static constexpr std::size_t kWords = std::size_t{kBricksPerAxis} * kBricksPerAxis * kBricksPerAxis * 8;

  ScanWindow() : bits_(new std::uint64_t[kWords]()), summary_(new std::uint64_t[kSummaryWords]()) {}

  // Centres the cube on the origin's voxel for one scan (until drain());
  // an origin within 512 voxels of the key space's edge gets no cube
  // (every key is outside), so a shifted axis can never carry into the
  // next one unnoticed.
  void begin(const VoxelKey& origin) noexcept {
    shift_ = 0;
    tag_ = kNever;
    for (int axis = 0; axis < 3; ++axis) {
      const unsigned o = origin.k[axis];
      if (o < 512u || o > 65024u) return;
    }
    std::uint64_t tag = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const unsigned o = origin.k[axis];
      const unsigned s = (128u - (o & 0xFFu)) & 0xF8u;
      shift_ |= std::uint64_t{s} << (16 * axis);
      tag |= std::uint64_t{(o + s) & 0xFF00u} << (16 * axis);
    }
    tag_ = tag;
  }

  // The per-scan state the ray loop needs, as a value of its own: held in
  // registers there (the window's members would be reloaded after every
  // store to the bits, which may alias them).
  class Probe {
   public:
    // Marks a voxel (a packed key, ray_traversal.hpp's pack()) visited;
    // false when it lies outside the cube. A key whose shifted axis carried
    // has that axis's high byte below 2 and cannot match the tag.
    [[gnu::always_inline]] bool visit(std::uint64_t packed) const noexcept {
      const std::uint64_t t = packed + shift_;
      if ((t & kHighBytes) != tag_) return false;
      const std::size_t word = static_cast<std::size_t>((t >> 32 & 7) | (t & 0xF8) | (t >> 11 & 0x1F00) |
                                                        (t >> 22 & 0x3E000));
      const std::uint64_t bit = std::uint64_t{1} << ((t & 7) | (t >> 13 & 0x38));
      std::uint64_t& w = bits_[word];
      if ((w & bit) == 0) {
        w |= bit;
        summary_[word >> 9] |= std::uint64_t{1} << (word >> 3 & 63);
      }
      return true;
    }

    // For a vector form of the same test (ray_batch.cpp): visit()'s terms.
    std::uint64_t shift() const noexcept { return shift_; }
    std::uint64_t tag() const noexcept { return tag_; }
    const std::uint64_t* bits() const noexcept { return bits_; }

   private:
    friend class ScanWindow;
    std::uint64_t shift_;
    std::uint64_t tag_;
    std::uint64_t* bits_;
    std::uint64_t* summary_;
  };

  Probe probe() noexcept {
    Probe p;
    p.shift_ = shift_;
    p.tag_ = tag_;
    p.bits_ = bits_.get();
    p.summary_ = summary_.get();
    return p;
  }

  // visit(brick_key (brick_key_of), const std::uint64_t visited[8]) for each
  // brick of the cube with a visited voxel, in the cube's order; leaves the
  // cube empty for the next scan.
  template <class Visit>
  void drain(Visit&& visit_brick) noexcept {
    for (std::size_t s = 0; s < kSummaryWords; ++s) {
      std::uint64_t pending = summary_[s];
      summary_[s] = 0;
      while (pending != 0) {
        const std::size_t brick = s * 64 + static_cast<std::size_t>(__builtin_ctzll(pending));
        pending &= pending - 1;
        std::uint64_t* words = &bits_[brick * 8];
        visit_brick(brick_key_of_window(brick), static_cast<const std::uint64_t*>(words));
        for (int z = 0; z < 8; ++z) words[z] = 0;
      }
    }
    shift_ = 0;
    tag_ = kNever;
  }

  // The high byte of each axis: a shifted key is inside when these equal the tag.
  static constexpr std::uint64_t kHighBytes = 0x0000FF00FF00FF00ull;

 private:
  static constexpr std::size_t kSummaryWords = kWords / 8 / 64;
  static constexpr std::uint64_t kNever = 1;  // no key masked by kHighBytes equals it

  // The map's brick (brick_key_of) of a brick of the cube: its first
  // voxel's key, unshifted.
  std::uint64_t brick_key_of_window(std::size_t brick) const noexcept {
    VoxelKey first;
    for (int axis = 0; axis < 3; ++axis) {
      const std::uint64_t low = (brick >> (5 * axis) & 31) << 3;
      const std::uint64_t high = tag_ >> (16 * axis) & 0xFF00;
      const std::uint64_t s = shift_ >> (16 * axis) & 0xFF;
      first.k[axis] = static_cast<std::uint16_t>((high | low) - s);
    }
    return brick_key_of(first);
  }

  std::unique_ptr<std::uint64_t[]> bits_;     // word (z & 7 | brick << 3), bit x & 7 | (y & 7) << 3
  std::unique_ptr<std::uint64_t[]> summary_;  // one bit a brick with a visited voxel
  std::uint64_t shift_ = 0;
  std::uint64_t tag_ = kNever;
};

}  // namespace rtfuse::mapping
