#pragma once
// A map as ROS's map_server (and nav2's map_server) loads it: a YAML file
// naming an image, its resolution and origin, and how pixels read
// (negate, occupied_thresh, free_thresh, mode), and the image, here a PGM
// (binary P5 or plain P2, 8 bits), the format the mapper writes
// (mapping/map_server_files.hpp). Cells come out in nav_msgs/OccupancyGrid's
// convention: -1 unknown, 0..100, row-major from the lowest y (the image's
// bottom row), as map_server's loadMapFromFile makes them.
//
// Outside input: every refusal names the file, the line where there is one,
// the key, and what would do.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace rtfuse::apps {

struct PgmImage {
  int width = 0;
  int height = 0;
  int max_value = 255;
  std::vector<std::uint8_t> pixels;  // row-major from the image's top row
};

// The PGM in data[0..size); "" or why not, starting with name.
std::string parse_pgm(const std::uint8_t* data, std::size_t size, const std::string& name, PgmImage* out);

enum class MapMode { kTrinary, kScale, kRaw };

struct MapServerYaml {
  std::string image;  // as written: relative to the YAML's folder unless absolute
  double resolution = 0.0;
  double origin_x = 0.0, origin_y = 0.0, origin_yaw = 0.0;
  bool negate = false;
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
  MapMode mode = MapMode::kTrinary;
};

// The YAML's text; "" or why not, starting with name (and the line).
std::string parse_map_yaml(const std::string& text, const std::string& name, MapServerYaml* out);

struct OccupancyGridMap {
  int width = 0;
  int height = 0;
  double resolution = 0.0;
  double origin_x = 0.0, origin_y = 0.0, origin_yaw = 0.0;
  std::vector<std::int8_t> cells;  // -1, 0..100; row 0 is the lowest y
};

// The cells of an image read as the YAML says (map_server's rules).
OccupancyGridMap occupancy_of(const MapServerYaml& yaml, const PgmImage& image);

// Loads the YAML at path and its image; "" or why not.
std::string load_map_server(const std::string& yaml_path, OccupancyGridMap* out);

}  // namespace rtfuse::apps
