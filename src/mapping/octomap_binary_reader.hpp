#pragma once
// Reading OctoMap's binary tree files (.bt) into the map: what octovis,
// octomap_server's map saver and OcTree::writeBinary write. Leaves are
// occupied or free only (a .bt keeps the maximum-likelihood tree), so they
// load as OctoMap's readBinary loads them: the clamping thresholds' log-odds.
// A file that is not a .bt, is cut short, names another tree type, holds a
// node below the finest depth or a count its header does not state is an
// error naming the file, the byte and what was wrong; a file the pool
// cannot hold is an error saying so. Not for the loop: it may fill the
// whole pool.
#include <cstddef>
#include <cstdint>
#include <string>

#include "mapping/occupancy_map.hpp"

namespace rtfuse::mapping {

struct OctomapBinaryHeader {
  std::string id;           // "OcTree"
  double resolution = 0.0;  // metres
  std::size_t size = 0;     // nodes, as the header states
  std::size_t data_offset = 0;  // where the tree's bytes start
};

// The header of the file's bytes; false with *error ("NAME: what").
bool read_octomap_binary_header(const std::uint8_t* data, std::size_t size, const std::string& name,
                                OctomapBinaryHeader* header, std::string* error);

// The file's tree into map (cleared first; its resolution must be the
// file's). False with *error; the map then holds what was read before.
bool read_octomap_binary(const std::uint8_t* data, std::size_t size, const std::string& name, OccupancyMap& map,
                         std::string* error);

}  // namespace rtfuse::mapping
