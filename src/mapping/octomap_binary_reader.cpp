#include "mapping/octomap_binary_reader.hpp"

#include <cmath>
#include <cstdlib>
#include <string_view>

namespace rtfuse::mapping {

namespace {

constexpr std::string_view kFirstLine = "# Octomap OcTree binary file";

bool fail(std::string* error, const std::string& text) {
  if (error != nullptr) *error = text;
  return false;
}

struct Reader {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t pos;
  const std::string& name;
  OccupancyMap& map;
  float occupied_value, free_value;
  std::size_t nodes = 1;  // the root
  std::string* error;

  // The node at `depth` whose cube starts at `corner`: its two bytes, then
  // its inner children's subtrees in order (OctoMap's writeBinaryNode).
  bool node(const VoxelKey& corner, int depth) {
    if (pos + 2 > size) {
      return fail(error, name + ": cut short at byte " + std::to_string(pos) + ": a node at depth " +
                             std::to_string(depth) + " needs two bytes");
    }
    const unsigned codes = static_cast<unsigned>(data[pos]) | static_cast<unsigned>(data[pos + 1]) << 8;
    const std::size_t at = pos;
    pos += 2;
    const int child_bits = kTreeDepth - depth - 1;  // the child cube: 2^child_bits voxels a side
    unsigned inner = 0;
    for (int c = 0; c < 8; ++c) {
      const unsigned code = codes >> (2 * c) & 3u;
      if (code == 0) continue;
      ++nodes;
      VoxelKey k = corner;
      k.k[0] = static_cast<std::uint16_t>(k.k[0] + ((c & 1) << child_bits));
      k.k[1] = static_cast<std::uint16_t>(k.k[1] + ((c >> 1 & 1) << child_bits));
      k.k[2] = static_cast<std::uint16_t>(k.k[2] + ((c >> 2 & 1) << child_bits));
      if (code == 3) {
        if (depth + 1 >= kTreeDepth) {
          return fail(error, name + ": byte " + std::to_string(at) + ": a node at depth " +
                                 std::to_string(depth + 1) + " has children; the tree ends at depth " +
                                 std::to_string(kTreeDepth));
        }
        inner |= 1u << c;
        continue;
      }
      // 01 free, 10 occupied, as OctoMap's readBinaryNode reads the bits.
      if (!map.fill_cube(k, depth + 1, code == 2 ? occupied_value : free_value)) {
        return fail(error, name + ": the map's pool (" + std::to_string(map.store().capacity().bricks) +
                               " bricks, " + std::to_string(map.store().capacity().dense_blocks) +
                               " blocks) cannot hold the file; give it more memory");
      }
    }
    for (int c = 0; c < 8; ++c) {
      if (!(inner >> c & 1u)) continue;
      VoxelKey k = corner;
      k.k[0] = static_cast<std::uint16_t>(k.k[0] + ((c & 1) << child_bits));
      k.k[1] = static_cast<std::uint16_t>(k.k[1] + ((c >> 1 & 1) << child_bits));
      k.k[2] = static_cast<std::uint16_t>(k.k[2] + ((c >> 2 & 1) << child_bits));
      if (!node(k, depth + 1)) return false;
    }
    return true;
  }
};

}  // namespace

bool read_octomap_binary_header(const std::uint8_t* data, std::size_t size, const std::string& name,
                                OctomapBinaryHeader* header, std::string* error) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (text.substr(0, kFirstLine.size()) != kFirstLine) {
    return fail(error, name + ": not an OctoMap binary tree (.bt): the first line is not \"" +
                           std::string(kFirstLine) + "\"");
  }
  OctomapBinaryHeader h;
  bool have_res = false, have_size = false;
  std::size_t pos = text.find('\n');
  int line = 1;
  while (pos != std::string_view::npos && pos + 1 <= text.size()) {
    const std::size_t start = pos + 1;
    pos = text.find('\n', start);
    ++line;
    const std::string_view l = text.substr(start, pos == std::string_view::npos ? text.size() - start : pos - start);
    const std::string where = name + ":" + std::to_string(line) + ": ";
    if (l.empty() || l[0] == '#') continue;
    const std::size_t space = l.find_first_of(" \t\r");
    const std::string_view key = l.substr(0, space);
    std::string value(space == std::string_view::npos ? std::string_view{} : l.substr(space + 1));
    while (!value.empty() && (value.back() == '\r' || value.back() == ' ' || value.back() == '\t')) value.pop_back();
    while (!value.empty() && (value.front() == ' ' || value.front() == '\t')) value.erase(0, 1);
    if (key == "data" || key == "data\r") {
      if (pos == std::string_view::npos) return fail(error, where + "\"data\" is the last byte: no tree follows");
      h.data_offset = pos + 1;
      if (h.id != "OcTree") {
        return fail(error, name + ": the tree is \"" + h.id + "\"; only OcTree (occupancy) files are read");
      }
      if (!have_res) return fail(error, name + ": no \"res\" line before \"data\"");
      if (!have_size) return fail(error, name + ": no \"size\" line before \"data\"");
      *header = h;
      return true;
    }
    char* end = nullptr;
    if (key == "id") {
      h.id = value;
    } else if (key == "res") {
      const double r = std::strtod(value.c_str(), &end);
      if (value.empty() || *end != '\0' || !(r >= 0.001 && r <= 10.0)) {
        return fail(error, where + "res \"" + value + "\": expected a resolution of 0.001 to 10 m");
      }
      h.resolution = r;
      have_res = true;
    } else if (key == "size") {
      const unsigned long long n = std::strtoull(value.c_str(), &end, 10);
      if (value.empty() || *end != '\0' || value[0] == '-') {
        return fail(error, where + "size \"" + value + "\": expected a count of nodes");
      }
      h.size = static_cast<std::size_t>(n);
      have_size = true;
    }
    // Other keywords: skipped, as OctoMap skips them.
  }
  return fail(error, name + ": the header has no \"data\" line: cut short, or not a .bt");
}

bool read_octomap_binary(const std::uint8_t* data, std::size_t size, const std::string& name, OccupancyMap& map,
                         std::string* error) {
  OctomapBinaryHeader h;
  if (!read_octomap_binary_header(data, size, name, &h, error)) return false;
  if (std::fabs(h.resolution - map.grid().resolution()) > 1e-9 * h.resolution) {
    return fail(error, name + ": resolution " + std::to_string(h.resolution) + " m, the map's is " +
                           std::to_string(map.grid().resolution()) + " m");
  }
  map.clear();
  if (h.size == 0) {
    if (h.data_offset != size) return fail(error, name + ": size 0 in the header, but a tree follows");
    return true;
  }
  Reader r{data, size, h.data_offset, name, map, map.log_odds().clamp_max, map.log_odds().clamp_min, 1, error};
  if (!r.node(VoxelKey{{0, 0, 0}}, 0)) return false;
  if (r.nodes != h.size) {
    return fail(error, name + ": the header says " + std::to_string(h.size) + " nodes, the tree holds " +
                           std::to_string(r.nodes));
  }
  if (r.pos != size) {
    return fail(error, name + ": " + std::to_string(size - r.pos) + " bytes after the tree (from byte " +
                           std::to_string(r.pos) + ")");
  }
  return true;
}

}  // namespace rtfuse::mapping
