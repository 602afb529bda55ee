#pragma once
// The map as OctoMap's binary tree file (.bt), byte for byte what
// OcTree::writeBinary writes for the same map, so octovis, octomap_server
// and every OctoMap user read it as their own.
//
// A .bt holds the tree OctoMap has after writeBinary's toMaxLikelihood()
// and prune(): each leaf only occupied or free, two bits per child (00
// unknown, 01 free leaf, 10 occupied leaf, 11 inner node; children 0-3 in
// the first byte, depth first). That tree is not simply the maximally
// pruned one. OctoMap prunes its log-odds tree as it updates (a node whose
// eight children are leaves of one log-odds becomes a leaf), then, for the
// file, collapses nodes whose children agree in occupancy from the deepest
// level up and stops at the first level where nothing collapses. Both
// steps are computed here from the voxels (see write()).
//
// Not for the loop or a device thread: it walks the whole map and grows
// the output buffer. The sort scratch is sized once, for the pool.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "mapping/occupancy_map.hpp"

namespace rtfuse::mapping {

class OctomapBinaryWriter {
 public:
  explicit OctomapBinaryWriter(std::uint32_t max_bricks);

  // Replaces out with the .bt file of map; returns the tree's node count
  // (the file's "size").
  std::size_t write(const OccupancyMap& map, std::vector<std::uint8_t>& out);

 private:
  struct Summary;
  struct Emit;

  template <class Fetch>
  Summary node(int depth, Emit* emit, Fetch&& fetch);
  Summary range(std::size_t lo, std::size_t hi, int depth, Emit* emit);
  Summary brick(std::uint32_t index, Emit* emit);
  Summary sub_brick(const Brick& b, int s, Emit* emit);
  Summary voxel_group(const Brick& b, int s, int group, Emit* emit);
  Summary voxel(std::uint32_t bits) const;
  Summary combine(const Summary* children, int depth, Emit* emit, std::size_t header);
  std::uint8_t child_code(const Summary& child, int child_depth) const;

  std::uint32_t capacity_;
  std::unique_ptr<std::uint64_t[]> codes_;    // Morton code << 25 | brick, sorted
  const OccupancyMap* map_ = nullptr;
  float occupied_ = 0.0f;
  int keep_inner_to_ = 0;                     // deepest level of the log-odds tree kept as it is
  std::uint32_t prunable_[kTreeDepth + 1] = {};
};

}  // namespace rtfuse::mapping
