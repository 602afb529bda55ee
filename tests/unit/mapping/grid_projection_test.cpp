// The 2-D grid from the 3-D map, and its map_server files.
#include "mapping/grid_projection.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "mapping/map_server_files.hpp"

namespace grid_projection_test {

using namespace rtfuse::mapping;

OccupancyParams tenth() {
  OccupancyParams p;
  p.resolution = 0.1;
  return p;
}

struct Grid {
  GridSpec spec;
  std::vector<std::int8_t> cells;
  std::int8_t at(const VoxelGrid& grid, double x, double y) const {
    std::uint16_t kx = 0, ky = 0;
    EXPECT_TRUE(grid.key_of(x, kx) && grid.key_of(y, ky));
    return cells[static_cast<std::size_t>(ky - spec.first_y) * spec.width + (kx - spec.first_x)];
  }
};

Grid project(const OccupancyMap& map, double z_min, double z_max) {
  Grid g;
  g.spec = grid_around(map.grid(), 0.0, 0.0, 80, 60, z_min, z_max);
  g.cells.resize(g.spec.cells());
  project_to_grid(map, g.spec, g.cells.data());
  return g;
}

TEST(GridProjection, WallsOccupiedRaysFreeTheRestUnknown) {
  OccupancyMap map(tenth(), {256, 1024});
  std::vector<MapPoint> scan;
  for (int i = -5; i <= 5; ++i) scan.push_back({2.05f, 0.1f * i + 0.05f, 0.45f});  // a wall at x = 2
  map.insert_scan(scan.data(), scan.size(), {0.05f, 0.05f, 0.45f});
  const Grid g = project(map, 0.0, 1.0);
  EXPECT_EQ(g.at(map.grid(), 2.05, 0.05), kCellOccupied);
  EXPECT_EQ(g.at(map.grid(), 1.05, 0.05), kCellFree);
  EXPECT_EQ(g.at(map.grid(), -1.05, 0.05), kCellUnknown);
  EXPECT_EQ(g.at(map.grid(), 2.55, 0.05), kCellUnknown);  // behind the wall
  EXPECT_EQ(g.spec.cells(), 80u * 60u);
}

TEST(GridProjection, OnlyVoxelsBetweenTheHeightsCount) {
  OccupancyMap map(tenth(), {256, 1024});
  const MapPoint ceiling{1.05f, 0.05f, 2.55f};  // a hit at z = 2.55, its ray rising through the column
  map.insert_scan(&ceiling, 1, {1.05f, 0.05f, 0.05f});
  EXPECT_EQ(project(map, 0.0, 1.0).at(map.grid(), 1.05, 0.05), kCellFree);
  EXPECT_EQ(project(map, 0.0, 3.0).at(map.grid(), 1.05, 0.05), kCellOccupied);
  EXPECT_EQ(project(map, 2.6, 3.0).at(map.grid(), 1.05, 0.05), kCellUnknown);  // above the hit: nothing known
}

TEST(GridProjection, CountsAddUpAndCellsOutsideTheMapStayUnknown) {
  OccupancyMap map(tenth(), {256, 1024});
  const MapPoint p{0.55f, 0.05f, 0.05f};
  map.insert_scan(&p, 1, {0.05f, 0.05f, 0.05f});
  GridSpec spec = grid_around(map.grid(), 100.0, 100.0, 10, 10, -1.0, 1.0);
  std::vector<std::int8_t> cells(spec.cells(), 42);
  const ProjectionCounts c = project_to_grid(map, spec, cells.data());
  EXPECT_EQ(c.unknown, 100u);
  for (std::int8_t v : cells) EXPECT_EQ(v, kCellUnknown);
  spec = grid_around(map.grid(), 0.0, 0.0, 20, 10, -1.0, 1.0);  // x from -1 to 1 m
  cells.resize(spec.cells());
  const ProjectionCounts d = project_to_grid(map, spec, cells.data());
  EXPECT_EQ(d.occupied, 1u);
  EXPECT_EQ(d.free, 5u);
  EXPECT_EQ(d.occupied + d.free + d.unknown, 200u);
}

TEST(MapServerFiles, PgmRowsRunFromTheHighestY) {
  const std::int8_t cells[6] = {kCellOccupied, kCellFree, kCellUnknown,   // y row 0
                                kCellFree, kCellFree, kCellOccupied};     // y row 1
  const std::vector<std::uint8_t> pgm = map_server_pgm(cells, 3, 2);
  const std::string header = "P5\n3 2\n255\n";
  ASSERT_EQ(pgm.size(), header.size() + 6);
  EXPECT_EQ(std::string(pgm.begin(), pgm.begin() + static_cast<long>(header.size())), header);
  const std::vector<std::uint8_t> pixels(pgm.begin() + static_cast<long>(header.size()), pgm.end());
  EXPECT_EQ(pixels, (std::vector<std::uint8_t>{254, 254, 0, 0, 254, 205}));
}

TEST(MapServerFiles, YamlNamesTheImageAndTheOrigin) {
  EXPECT_EQ(map_server_yaml("map.pgm", 0.05, -10.0, -7.5),
            "image: map.pgm\nmode: trinary\nresolution: 0.05\norigin: [-10, -7.5, 0.0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
}

}  // namespace grid_projection_test
