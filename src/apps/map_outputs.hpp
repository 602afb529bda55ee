#pragma once
// A map's files, as a robot's user takes them away: PREFIX.bt (OctoMap's
// binary tree, for octovis and octomap_server), PREFIX.pgm + PREFIX.yaml
// (map_server's pair, for ROS navigation) and PREFIX.png (the top view with
// a scale, the path and the key figures). A tool's writer: allocates and
// does file I/O, never on the real-time path.
#include <cstdint>
#include <string>
#include <vector>

#include "apps/plot_axes.hpp"
#include "mapping/grid_projection.hpp"
#include "mapping/occupancy_map.hpp"

namespace rtfuse::apps {

struct MapOutputs {
  std::string prefix;                 // PREFIX.bt, .pgm, .yaml, .png
  std::string title;                  // the picture's
  std::vector<DataPoint> path;        // the sensor's positions, metres
  std::vector<std::string> figures;   // key-figure lines for the picture
};

// The grid (spec, cells: mapping/grid_projection.hpp) is the map's
// projection. False with *error naming the file and the cause.
bool write_map_outputs(const mapping::OccupancyMap& map, const mapping::GridSpec& spec, const std::int8_t* cells,
                       const MapOutputs& out, std::string* error);

}  // namespace rtfuse::apps
