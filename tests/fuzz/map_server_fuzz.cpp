// rtfuse-plan's inputs: the map_server YAML and the PGM it names
// (apps/map_server_map.hpp), and the start/goal pairs (apps/plan_pairs.hpp).
// The first byte picks the parser (0 PGM, 1 YAML, 2 pairs, modulo 3).
// Property: refused with a reason naming the file, or a result that holds
// together: a YAML's resolution positive and finite, its thresholds in
// order; a PGM's pixels as many as its size says, none above its maximum;
// the cells made of them within nav_msgs/OccupancyGrid's -1..100 in every
// mode; a pair for each row, its line within the file.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include <stdexcept>

#include "apps/map_server_map.hpp"
#include "apps/plan_pairs.hpp"
#include "fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rtfuse::apps;
  if (size == 0) return 0;
  const int which = data[0] % 3;
  ++data;
  --size;
  if (which == 2) {
    std::size_t lines = 1;
    for (std::size_t i = 0; i < size; ++i) lines += data[i] == '\n';
    try {
      for (const PlanPair& p : parse_plan_pairs(std::string_view(reinterpret_cast<const char*>(data), size), "pairs.txt")) {
        FUZZ_CHECK(p.line >= 1 && p.line <= lines, "a pair's line is in the file");
      }
    } catch (const std::runtime_error& e) {
      FUZZ_CHECK(std::string(e.what()).rfind("pairs.txt:", 0) == 0, "the error names the file and line");
    }
    return 0;
  }
  if (which == 1) {
    MapServerYaml yaml;
    const std::string error = parse_map_yaml(std::string(reinterpret_cast<const char*>(data), size), "map.yaml", &yaml);
    if (!error.empty()) {
      FUZZ_CHECK(error.rfind("map.yaml", 0) == 0, "the error names the file");
      return 0;
    }
    FUZZ_CHECK(std::isfinite(yaml.resolution) && yaml.resolution > 0.0, "a usable resolution");
    FUZZ_CHECK(yaml.free_thresh >= 0.0 && yaml.free_thresh < yaml.occupied_thresh && yaml.occupied_thresh <= 1.0,
               "thresholds in order");
    FUZZ_CHECK(!yaml.image.empty(), "an image named");
    return 0;
  }
  PgmImage image;
  const std::string error = parse_pgm(data, size, "map.pgm", &image);
  if (!error.empty()) {
    FUZZ_CHECK(error.rfind("map.pgm", 0) == 0, "the error names the file");
    return 0;
  }
  FUZZ_CHECK(image.pixels.size() == static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height),
             "as many pixels as the size says");
  for (std::uint8_t p : image.pixels) FUZZ_CHECK(p <= image.max_value, "no pixel above the maximum");
  if (image.pixels.size() > (1u << 20)) return 0;  // bounded work a run
  MapServerYaml yaml;
  yaml.resolution = 0.05;
  for (MapMode mode : {MapMode::kTrinary, MapMode::kScale, MapMode::kRaw}) {
    yaml.mode = mode;
    const OccupancyGridMap map = occupancy_of(yaml, image);
    FUZZ_CHECK(map.cells.size() == image.pixels.size(), "a cell a pixel");
    for (std::int8_t c : map.cells) FUZZ_CHECK(c >= -1 && c <= 100, "cells within -1..100");
  }
  return 0;
}
