#pragma once
// The 2-D grid as the map_server pair ROS navigation loads (and nav2's
// map_saver writes): a binary PGM, occupied black (0), free white (254),
// unknown grey (205), its first row the grid's highest y; and a YAML with
// the image's name, the resolution, the origin of the lower-left pixel,
// trinary mode and the thresholds those three shades fall on.
#include <cstdint>
#include <string>
#include <vector>

namespace rtfuse::mapping {

std::vector<std::uint8_t> map_server_pgm(const std::int8_t* cells, int width, int height);

std::string map_server_yaml(const std::string& image, double resolution, double origin_x, double origin_y);

}  // namespace rtfuse::mapping
