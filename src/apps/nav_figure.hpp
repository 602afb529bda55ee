#pragma once
// What the navigator did, as a picture a person can read on its own: the
// costmap it planned on (obstacles black, the inscribed zone dark red,
// inflation fading to white, unknown grey), the true obstacles' outlines,
// the path it was last following, the trajectory the robot truly drove and
// the goals it was sent, with a legend and the run's figures beside them.
// A tool's writer (allocates, does file I/O); never on the real-time path.
#include <cstdint>
#include <string>
#include <vector>

#include "apps/plot_axes.hpp"

namespace rtfuse::apps {

struct NavFigure {
  std::string title;
  const std::uint8_t* costs = nullptr;  // costmap_2d's values, row 0 the lowest y
  int width = 0, height = 0;
  double resolution = 0.05;             // m per cell
  double origin_x = 0.0, origin_y = 0.0;  // the lower-left corner of cell (0, 0)
  struct Box {
    double x0, y0, x1, y1;
  };
  std::vector<Box> obstacles;           // the world's truth, when known
  std::vector<DataPoint> path;          // the last path followed
  std::vector<DataPoint> driven;        // where the robot truly went
  std::vector<DataPoint> goals;         // in the order sent
  std::vector<std::string> figures;     // key-figure lines ("# " heads a block)
};

// False and *error naming the path and the cause.
bool write_nav_png(const NavFigure& figure, const std::string& path, std::string* error);

}  // namespace rtfuse::apps
