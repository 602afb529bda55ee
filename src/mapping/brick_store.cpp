#include "mapping/brick_store.hpp"

#include <stdexcept>
#include <string>

namespace rtfuse::mapping {

BrickCapacity capacity_for_bytes(std::size_t bytes) noexcept {
  const std::size_t brick_bytes = sizeof(Brick) + 4 * sizeof(std::uint32_t);  // table at most half full
  const std::size_t block_bytes = (kSubVoxels + 1) * sizeof(std::uint32_t);   // values and a free-list slot
  std::size_t bricks = bytes / 8 / brick_bytes;
  std::size_t blocks = (bytes - bytes / 8) / block_bytes;
  if (bricks < 1) bricks = 1;
  if (bricks > (1u << 30)) bricks = 1u << 30;
  if (blocks > kMaxDenseBlocks) blocks = kMaxDenseBlocks;
  return BrickCapacity{static_cast<std::uint32_t>(bricks), static_cast<std::uint32_t>(blocks)};
}

BrickStore::BrickStore(BrickCapacity capacity) : capacity_(capacity) {
  if (capacity.bricks == 0 || capacity.bricks > (1u << 30)) {
    throw std::invalid_argument("occupancy map: brick pool of " + std::to_string(capacity.bricks) +
                                " bricks; it must hold 1 to 2^30");
  }
  if (capacity.dense_blocks > kMaxDenseBlocks) {
    throw std::invalid_argument("occupancy map: dense block pool of " + std::to_string(capacity.dense_blocks) +
                                " blocks exceeds " + std::to_string(kMaxDenseBlocks));
  }
  // At most half full, so a probe ends after a step or two.
  std::uint32_t slots = 2;
  int bits = 1;
  while (slots < 2u * capacity.bricks) {
    slots <<= 1;
    ++bits;
  }
  mask_ = slots - 1;
  hash_shift_ = 64 - bits;
  bricks_.reset(new Brick[capacity.bricks]);
  table_.reset(new std::uint32_t[slots]());
  blocks_.reset(new std::uint32_t[std::size_t{capacity.dense_blocks} * kSubVoxels]);
  free_.reset(new std::uint32_t[capacity.dense_blocks == 0 ? 1 : capacity.dense_blocks]);
  clear();
}

void BrickStore::prefault() noexcept {
  // Bricks and blocks not handed out yet hold nothing: zeroing them is free
  // of effect but for the pages it makes resident.
  std::memset(static_cast<void*>(bricks_.get() + used_bricks_), 0,
              std::size_t{capacity_.bricks - used_bricks_} * sizeof(Brick));
  for (std::uint32_t i = 0; i < free_count_; ++i) {
    std::memset(block_values(free_[i]), 0, kSubVoxels * sizeof(std::uint32_t));
  }
}

void BrickStore::clear() noexcept {
  std::memset(table_.get(), 0, (std::size_t{mask_} + 1) * sizeof(std::uint32_t));
  used_bricks_ = 0;
  // Handed out from block 0 up, so the same inserts use the same blocks.
  free_count_ = capacity_.dense_blocks;
  for (std::uint32_t i = 0; i < free_count_; ++i) free_[i] = free_count_ - 1 - i;
}

std::size_t BrickStore::bytes_used() const noexcept {
  return std::size_t{used_bricks_} * (sizeof(Brick) + 2 * sizeof(std::uint32_t)) +
         std::size_t{blocks_used()} * kSubVoxels * sizeof(std::uint32_t);
}

std::size_t BrickStore::bytes_reserved() const noexcept {
  return std::size_t{capacity_.bricks} * sizeof(Brick) +
         std::size_t{capacity_.dense_blocks} * (kSubVoxels + 1) * sizeof(std::uint32_t) +
         (std::size_t{mask_} + 1) * sizeof(std::uint32_t);
}

}  // namespace rtfuse::mapping
