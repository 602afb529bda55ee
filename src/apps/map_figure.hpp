#pragma once
// The 2-D occupancy grid as a picture a person can read on its own: the top
// view in metres (equal scale, 1-2-5 ticks), occupied cells black, free
// white, unknown grey (map_server's shades), the sensor's path over it,
// a legend and the map's key figures beside it. A tool's writer
// (allocates, does file I/O); never on the real-time path.
#include <cstdint>
#include <string>
#include <vector>

#include "apps/plot_axes.hpp"

namespace rtfuse::apps {

struct MapFigure {
  std::string title;
  const std::int8_t* cells = nullptr;  // row 0 the lowest y (mapping/grid_projection.hpp)
  int width = 0, height = 0;
  double resolution = 0.05;            // m per cell
  double origin_x = 0.0, origin_y = 0.0;  // the lower-left corner of cell (0, 0)
  std::vector<DataPoint> path;         // the sensor's positions, metres
  std::vector<std::string> figures;    // key-figure lines ("# " heads a block)
};

// False and *error naming the path and the cause.
bool write_map_png(const MapFigure& figure, const std::string& path, std::string* error);

}  // namespace rtfuse::apps
