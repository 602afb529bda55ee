// Maps as map_server loads them: the mapper's own PGM + YAML read back to
// the same cells, map_server's three modes and negate, and the refusals of
// broken files with the file, the line and the key.
#include "apps/map_server_map.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "mapping/map_server_files.hpp"

namespace map_server_map_test {

using namespace rtfuse::apps;

const char* const kYaml =
    "image: map.pgm\nmode: trinary\nresolution: 0.05\norigin: [-1.5, 2.25, 0.0]\nnegate: 0\n"
    "occupied_thresh: 0.65\nfree_thresh: 0.196\n";

PgmImage pgm_of(const std::string& text) {
  PgmImage image;
  const std::string e = parse_pgm(reinterpret_cast<const std::uint8_t*>(text.data()), text.size(), "t.pgm", &image);
  EXPECT_EQ(e, "");
  return image;
}

TEST(MapServerMap, TheMappersOwnFilesReadBackToTheSameCells) {
  const int w = 7, h = 5;
  std::vector<std::int8_t> cells(w * h);
  for (int i = 0; i < w * h; ++i) cells[static_cast<std::size_t>(i)] = static_cast<std::int8_t>(i % 3 == 0 ? 100 : i % 3 == 1 ? 0 : -1);
  const std::string dir = testing::TempDir() + "rtfuse_map_server_" + std::to_string(::getpid());
  const std::string yaml_path = dir + ".yaml", pgm_path = dir + ".pgm";
  const std::vector<std::uint8_t> pgm = rtfuse::mapping::map_server_pgm(cells.data(), w, h);
  std::ofstream(pgm_path, std::ios::binary).write(reinterpret_cast<const char*>(pgm.data()),
                                                  static_cast<std::streamsize>(pgm.size()));
  const std::string name = pgm_path.substr(pgm_path.rfind('/') + 1);
  std::ofstream(yaml_path) << rtfuse::mapping::map_server_yaml(name, 0.05, -1.5, 2.25);
  OccupancyGridMap map;
  EXPECT_EQ(load_map_server(yaml_path, &map), "");
  std::remove(yaml_path.c_str());
  std::remove(pgm_path.c_str());
  EXPECT_EQ(map.width, w);
  EXPECT_EQ(map.height, h);
  EXPECT_DOUBLE_EQ(map.resolution, 0.05);
  EXPECT_DOUBLE_EQ(map.origin_x, -1.5);
  EXPECT_DOUBLE_EQ(map.origin_y, 2.25);
  EXPECT_EQ(map.cells, cells);
}

TEST(MapServerMap, PixelsReadAsMapServerReadsThem) {
  MapServerYaml yaml;
  ASSERT_EQ(parse_map_yaml(kYaml, "m.yaml", &yaml), "");
  // One row, top row first: black, white, the unknown grey, a mid grey.
  const PgmImage image = pgm_of("P2\n# a comment\n4 1\n255\n0 254 205 100\n");
  OccupancyGridMap map = occupancy_of(yaml, image);
  EXPECT_EQ(map.cells, (std::vector<std::int8_t>{100, 0, -1, -1}));
  // Scale: between the thresholds, (occupancy - free) / (occupied - free)
  // x 100, rounded: the grey 205 is 0.196078, 0.0 of the way; 100 is
  // 0.6078, 90.7 of it.
  yaml.mode = MapMode::kScale;
  map = occupancy_of(yaml, image);
  EXPECT_EQ(map.cells, (std::vector<std::int8_t>{100, 0, 0, 91}));
  yaml.mode = MapMode::kTrinary;
  yaml.negate = true;
  map = occupancy_of(yaml, image);
  EXPECT_EQ(map.cells[0], 0);
  EXPECT_EQ(map.cells[1], 100);
  yaml.negate = false;
  yaml.mode = MapMode::kRaw;  // the pixel is the value; above 100 unknown
  map = occupancy_of(yaml, image);
  EXPECT_EQ(map.cells, (std::vector<std::int8_t>{0, -1, -1, 100}));
  // The image's top row is the grid's highest y.
  yaml.mode = MapMode::kTrinary;
  map = occupancy_of(yaml, pgm_of(std::string("P5 1 2 255\n\x00\xfe", 13)));
  EXPECT_EQ(map.cells, (std::vector<std::int8_t>{0, 100}));
}

TEST(MapServerMap, BrokenImagesAreRefusedWithWhatIsWrong) {
  PgmImage image;
  const auto refusal = [&](const std::string& text) {
    return parse_pgm(reinterpret_cast<const std::uint8_t*>(text.data()), text.size(), "map.pgm", &image);
  };
  EXPECT_NE(refusal("P6 1 1 255\n\x01\x02\x03").find("P5 or P2"), std::string::npos);
  EXPECT_NE(refusal("P5 3 2 255\n\x01\x02").find("truncated: 6 pixels expected, 2 bytes"), std::string::npos);
  EXPECT_NE(refusal("P5 3 2 65535\n").find("8-bit"), std::string::npos);
  EXPECT_NE(refusal("P5 0 2 255\n").find("1 to 32768"), std::string::npos);
  EXPECT_NE(refusal("P5 40000 40000 255\n").find("1 to 32768"), std::string::npos);
  EXPECT_NE(refusal("P5 3").find("width, height and maximum value"), std::string::npos);
  EXPECT_NE(refusal("P2 2 1 100\n3 101\n").find("pixel 1 is 101, above the maximum value 100"), std::string::npos);
  EXPECT_NE(refusal("P2 2 1 255\n3 x\n").find("pixel 1 of 2"), std::string::npos);
  EXPECT_EQ(refusal("P2 2 1 255\n3 4\n"), "");
}

TEST(MapServerMap, BrokenYamlIsRefusedWithTheLineAndTheKey) {
  MapServerYaml yaml;
  const auto refusal = [&](const std::string& text) { return parse_map_yaml(text, "map.yaml", &yaml); };
  std::string text = kYaml;
  EXPECT_NE(refusal("image: [unclosed\n").find("map.yaml:"), std::string::npos);
  EXPECT_NE(refusal("resolution: 0.05\n").find("key 'image' is missing"), std::string::npos);
  EXPECT_NE(refusal("image: m.pgm\nresolution: fine\n").find("map.yaml:2: key 'resolution' must be a number"),
            std::string::npos);
  EXPECT_NE(refusal("image: m.pgm\nresolution: -1\norigin: [0, 0, 0]\n").find("positive"), std::string::npos);
  EXPECT_NE(refusal("image: m.pgm\nresolution: 0.1\norigin: [0, 0]\n").find("map.yaml:3: key 'origin' must be [x, y, yaw]"),
            std::string::npos);
  EXPECT_NE(refusal("image: m.pgm\nresolution: 0.1\norigin: [0, 0, .nan]\noccupied_thresh: 0.6\nfree_thresh: 0.1\n")
                .find("finite"),
            std::string::npos);
  EXPECT_NE(refusal("image: m.pgm\nresolution: 0.1\norigin: [0, 0, 0]\noccupied_thresh: 0.1\nfree_thresh: 0.6\n")
                .find("free_thresh < occupied_thresh"),
            std::string::npos);
  std::string fancy = text;
  fancy.replace(fancy.find("trinary"), 7, "fancy");
  EXPECT_NE(refusal(fancy).find("'mode' must be trinary, scale or raw"), std::string::npos);
  EXPECT_NE(refusal("- a\n- b\n").find("mapping of keys"), std::string::npos);
  EXPECT_EQ(refusal(text), "");
  EXPECT_EQ(yaml.image, "map.pgm");
  OccupancyGridMap map;
  EXPECT_NE(load_map_server("/nonexistent/map.yaml", &map).find("cannot be read"), std::string::npos);
}

}  // namespace map_server_map_test
