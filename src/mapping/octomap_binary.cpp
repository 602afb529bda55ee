#include "mapping/octomap_binary.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace rtfuse::mapping {

namespace {

constexpr int kIndexBits = 25;  // bricks a sort key can name
constexpr int kBrickDepth = kTreeDepth - kBrickShift;  // 13: a brick is a node of this depth

// Interleaves a brick's coordinates so that sorted codes list the bricks in
// the order OctoMap's depth-first walk meets them: at each level the child
// index is x + 2y + 4z of that level's bit.
std::uint64_t morton(std::uint64_t brick_key) {
  std::uint64_t code = 0;
  for (int bit = 12; bit >= 0; --bit) {
    const std::uint64_t x = brick_key >> bit & 1, y = brick_key >> (13 + bit) & 1, z = brick_key >> (26 + bit) & 1;
    code = code << 3 | x | y << 1 | z << 2;
  }
  return code;
}

}  // namespace

// What the file needs to know of a node's voxels.
struct OctomapBinaryWriter::Summary {
  bool any = false;         // some voxel known: the node exists
  bool all = false;         // every voxel known
  bool lo_uniform = false;  // all known, one log-odds: a leaf of OctoMap's pruned tree
  bool ml_uniform = false;  // all known, all occupied or all free
  bool ml_occupied = false;
  std::uint32_t lo_bits = 0;
};

struct OctomapBinaryWriter::Emit {
  std::vector<std::uint8_t>& out;
  std::size_t nodes;
};

OctomapBinaryWriter::OctomapBinaryWriter(std::uint32_t max_bricks) : capacity_(max_bricks) {
  if (max_bricks > (1u << kIndexBits)) {
    throw std::invalid_argument(".bt writer: " + std::to_string(max_bricks) + " bricks exceed the " +
                                std::to_string(1u << kIndexBits) + " it can sort");
  }
  codes_.reset(new std::uint64_t[max_bricks == 0 ? 1 : max_bricks]);
}

OctomapBinaryWriter::Summary OctomapBinaryWriter::voxel(std::uint32_t bits) const {
  Summary s;
  if (bits == kUnknownBits) return s;
  s.any = s.all = s.lo_uniform = s.ml_uniform = true;
  s.lo_bits = bits;
  s.ml_occupied = OccupancyMap::float_of(bits) >= occupied_;
  return s;
}

std::uint8_t OctomapBinaryWriter::child_code(const Summary& child, int child_depth) const {
  if (!child.any) return 0;
  const bool leaf = child.lo_uniform || (child.ml_uniform && child_depth > keep_inner_to_);
  if (!leaf) return 3;
  return child.ml_occupied ? 2 : 1;
}

OctomapBinaryWriter::Summary OctomapBinaryWriter::combine(const Summary* c, int depth, Emit* emit,
                                                          std::size_t header) {
  Summary s;
  s.all = s.lo_uniform = s.ml_uniform = true;
  for (int i = 0; i < 8; ++i) {
    s.any |= c[i].any;
    s.all &= c[i].all;
    s.lo_uniform &= c[i].lo_uniform && c[i].lo_bits == c[0].lo_bits;
    s.ml_uniform &= c[i].ml_uniform && c[i].ml_occupied == c[0].ml_occupied;
  }
  s.lo_uniform &= s.all;
  s.ml_uniform &= s.all;
  s.lo_bits = c[0].lo_bits;
  s.ml_occupied = c[0].ml_occupied;
  if (emit == nullptr) {
    // An inner node of OctoMap's log-odds tree that the file's pruning
    // would collapse, were it to reach this level.
    if (depth >= 1 && !s.lo_uniform && s.ml_uniform) ++prunable_[depth];
  } else {
    std::uint8_t first = 0, second = 0;
    for (int i = 0; i < 4; ++i) {
      first = static_cast<std::uint8_t>(first | child_code(c[i], depth + 1) << (2 * i));
      second = static_cast<std::uint8_t>(second | child_code(c[i + 4], depth + 1) << (2 * i));
    }
    emit->out[header] = first;
    emit->out[header + 1] = second;
  }
  return s;
}

// A node from its eight children, in file order: fetch(c) gives child c's
// summary, having appended the child's own subtree when emitting. A child
// that turns out to be a leaf or unknown has its subtree taken back off.
template <class Fetch>
OctomapBinaryWriter::Summary OctomapBinaryWriter::node(int depth, Emit* emit, Fetch&& fetch) {
  std::size_t header = 0;
  if (emit) {
    header = emit->out.size();
    emit->out.push_back(0);
    emit->out.push_back(0);
  }
  Summary children[8];
  for (int c = 0; c < 8; ++c) {
    const std::size_t mark = emit ? emit->out.size() : 0;
    const std::size_t nodes = emit ? emit->nodes : 0;
    children[c] = fetch(c);
    if (emit) {
      const std::uint8_t code = child_code(children[c], depth + 1);
      if (code != 3) {
        emit->out.resize(mark);
        emit->nodes = nodes;
      }
      if (code != 0) ++emit->nodes;
    }
  }
  return combine(children, depth, emit, header);
}

OctomapBinaryWriter::Summary OctomapBinaryWriter::voxel_group(const Brick& b, int s, int group, Emit* emit) {
  // group: the depth-15 node (2x2x2 voxels) of a sub-brick, bit 1 of x, y, z.
  const int gx = group & 1, gy = group >> 1 & 1, gz = group >> 2 & 1;
  const auto at = [&](int c) {
    const int v = (gx << 1 | (c & 1)) | (gy << 1 | (c >> 1 & 1)) << 2 | (gz << 1 | (c >> 2 & 1)) << 4;
    return voxel(map_->store().value_bits(b, s, v));
  };
  return node(kTreeDepth - 1, emit, at);
}

OctomapBinaryWriter::Summary OctomapBinaryWriter::sub_brick(const Brick& b, int s, Emit* emit) {
  if (!is_dense(b.sub[s])) return voxel(b.sub[s]);  // unknown, or one value throughout
  return node(kTreeDepth - 2, emit, [&](int c) { return voxel_group(b, s, c, emit); });
}

OctomapBinaryWriter::Summary OctomapBinaryWriter::brick(std::uint32_t index, Emit* emit) {
  const Brick& b = map_->store().brick(index);
  return node(kBrickDepth, emit, [&](int c) { return sub_brick(b, c, emit); });
}

OctomapBinaryWriter::Summary OctomapBinaryWriter::range(std::size_t lo, std::size_t hi, int depth, Emit* emit) {
  if (lo == hi) return Summary{};
  if (depth == kBrickDepth) {
    return brick(static_cast<std::uint32_t>(codes_[lo] & ((std::uint64_t{1} << kIndexBits) - 1)), emit);
  }
  // The children's ranges: the sorted codes grouped by this level's digit.
  std::size_t bounds[9];
  const int shift = kIndexBits + 3 * (kBrickDepth - 1 - depth);
  std::size_t i = lo;
  for (int c = 0; c < 8; ++c) {
    bounds[c] = i;
    while (i < hi && static_cast<int>(codes_[i] >> shift & 7) == c) ++i;
  }
  bounds[8] = hi;
  return node(depth, emit, [&](int c) { return range(bounds[c], bounds[c + 1], depth + 1, emit); });
}

std::size_t OctomapBinaryWriter::write(const OccupancyMap& map, std::vector<std::uint8_t>& out) {
  map_ = &map;
  occupied_ = map.log_odds().occupied;
  const BrickStore& store = map.store();
  if (store.bricks_used() > capacity_) {
    throw std::invalid_argument(".bt writer: the map has more bricks than the writer was made for");
  }
  std::size_t n = 0;
  for (std::uint32_t i = 0; i < store.bricks_used(); ++i) {
    codes_[n++] = morton(store.brick(i).key) << kIndexBits | i;
  }
  std::sort(codes_.get(), codes_.get() + n);

  // Pass 1: which levels the file's pruning reaches. OctoMap's prune()
  // goes from the deepest level up and stops at the first level where no
  // node collapses; nodes above it keep the log-odds tree's shape.
  std::fill(std::begin(prunable_), std::end(prunable_), 0u);
  keep_inner_to_ = kTreeDepth;  // pass 1 classifies nothing
  const Summary root = range(0, n, 0, nullptr);
  keep_inner_to_ = 0;
  for (int depth = kTreeDepth - 1; depth > 0; --depth) {
    if (prunable_[depth] == 0) {
      keep_inner_to_ = depth;
      break;
    }
  }

  // Pass 2: the nodes, depth first.
  out.clear();
  Emit emit{out, 0};
  if (root.any) {
    range(0, n, 0, &emit);
    emit.nodes += 1;  // the root
  }
  char header[256];
  const int length = std::snprintf(header, sizeof header,
                                   "# Octomap OcTree binary file\n"
                                   "# (feel free to add / change comments, but leave the first line as it is!)\n"
                                   "#\nid OcTree\nsize %zu\nres %g\ndata\n",
                                   emit.nodes, map.grid().resolution());
  out.insert(out.begin(), header, header + length);
  return emit.nodes;
}

}  // namespace rtfuse::mapping
