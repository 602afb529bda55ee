#include "mapping/map_server_files.hpp"

#include <cstdio>

#include "mapping/grid_projection.hpp"

namespace rtfuse::mapping {

std::vector<std::uint8_t> map_server_pgm(const std::int8_t* cells, int width, int height) {
  char header[64];
  const int length = std::snprintf(header, sizeof header, "P5\n%d %d\n255\n", width, height);
  std::vector<std::uint8_t> pgm(header, header + length);
  pgm.reserve(pgm.size() + static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int row = height - 1; row >= 0; --row) {
    const std::int8_t* line = cells + static_cast<std::size_t>(row) * static_cast<std::size_t>(width);
    for (int x = 0; x < width; ++x) {
      pgm.push_back(line[x] == kCellOccupied ? 0 : line[x] == kCellFree ? 254 : 205);
    }
  }
  return pgm;
}

std::string map_server_yaml(const std::string& image, double resolution, double origin_x, double origin_y) {
  // map_server reads a pixel p as occupancy (255 - p) / 255: 0 -> 1.0
  // (above 0.65, occupied), 254 -> 0.004 (below 0.196, free), 205 -> 0.196
  // (between: unknown).
  char text[512];
  std::snprintf(text, sizeof text,
                "image: %s\nmode: trinary\nresolution: %.9g\norigin: [%.9g, %.9g, 0.0]\nnegate: 0\n"
                "occupied_thresh: 0.65\nfree_thresh: 0.196\n",
                image.c_str(), resolution, origin_x, origin_y);
  return text;
}

}  // namespace rtfuse::mapping
