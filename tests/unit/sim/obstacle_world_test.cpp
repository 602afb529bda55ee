// Obstacles inside the drive area: the scenario's [[obstacle]]s, their
// solids in the camera world, the truth a map is scored against, and the
// loader's refusal of a path that drives through one.
#include <gtest/gtest.h>

#include <string>

#include "sim/camera_world.hpp"
#include "sim/drive_scenario.hpp"

namespace obstacle_world_test {

using namespace rtfuse::sim;

const std::string kScenario = std::string(RTFUSE_SOURCE_DIR) + "/config/scenarios/obstacles.toml";

TEST(ObstacleWorld, TheScenarioLoadsWithItsObstacles) {
  DriveScenario sc;
  std::string error;
  ASSERT_TRUE(load_drive_scenario(kScenario, &sc, &error)) << error;
  ASSERT_EQ(sc.obstacles.size(), 9u);
  EXPECT_DOUBLE_EQ(sc.obstacles[3].x, 7.1);
  EXPECT_DOUBLE_EQ(sc.obstacles[3].size_y, 2.0);
}

TEST(ObstacleWorld, ObstaclesAreSolidWhereTheyStandAndNowhereElse) {
  CameraWorldConfig config;
  config.obstacles.push_back(ObstacleBox{3.0, 2.0, 0.4, 1.0, 1.5});
  const CameraWorld world(config);
  const CameraWorld empty{CameraWorldConfig{}};
  EXPECT_EQ(world.surface_count(), empty.surface_count() + 5);
  EXPECT_TRUE(world.solid_in(2.9, 1.9, 3.0, 2.0, 0.5, 0.6));
  EXPECT_TRUE(world.solid_in(3.15, 2.45, 3.25, 2.55, 1.4, 1.6));   // a cell over its corner
  EXPECT_FALSE(world.solid_in(3.21, 2.0, 3.3, 2.1, 0.0, 1.0));     // beside it
  EXPECT_FALSE(world.solid_in(2.9, 1.9, 3.0, 2.0, 1.6, 2.0));      // above it
  EXPECT_FALSE(empty.solid_in(2.9, 1.9, 3.0, 2.0, 0.5, 0.6));
  // Behind a wall is solid up to its height.
  EXPECT_TRUE(world.solid_in(world.wall_max_x(), 0.0, world.wall_max_x() + 0.1, 0.1, 0.0, 1.0));
  EXPECT_FALSE(world.solid_in(world.wall_max_x(), 0.0, world.wall_max_x() + 0.1, 0.1, 2.6, 3.0));
}

TEST(ObstacleWorld, AWorldWithoutObstaclesIsTheWorldItWas) {
  // Obstacles come last, with texture streams of their own: the other
  // surfaces, and so every existing scenario's frames, do not change.
  CameraWorldConfig config;
  config.obstacles.push_back(ObstacleBox{3.0, 2.0, 0.4, 1.0, 1.5});
  const CameraWorld with(config);
  const CameraWorld without{CameraWorldConfig{}};
  for (int i = 0; i < without.surface_count(); ++i) {
    EXPECT_EQ(with.surface(i).origin, without.surface(i).origin) << i;
    ASSERT_EQ(with.surface(i).texture, without.surface(i).texture) << i;
    if (with.surface(i).texture >= 0) {
      EXPECT_EQ(with.texture(with.surface(i).texture).texel(0, 3, 5),
                without.texture(without.surface(i).texture).texel(0, 3, 5));
    }
  }
}

TEST(ObstacleWorld, APathThroughAnObstacleIsRefusedWithWhereAndWhen) {
  const std::string text = R"(
[robot]
left_nodes = [1]
right_nodes = [2]

[[path]]
type = "straight"
length_m = 6.0
speed_mps = 0.5

[[obstacle]]
x_m = 3.0
y_m = 0.2
size_x_m = 0.5
size_y_m = 0.5
)";
  std::string error;
  EXPECT_FALSE(load_drive_scenario_string(text, "through.toml", nullptr, &error));
  EXPECT_NE(error.find("through.toml:12:"), std::string::npos) << error;
  EXPECT_NE(error.find("the path passes 0.34 m from this obstacle at t = 5.3 s"), std::string::npos) << error;
}

TEST(ObstacleWorld, ObstaclesOutsideTheDriveAreaOrShapelessAreRefused) {
  const std::string text = R"(
duration_s = 1.0

[robot]
left_nodes = [1]
right_nodes = [2]

[[obstacle]]
x_m = 100.0
y_m = 0.0
size_x_m = 0.5
size_y_m = 0.5

[[obstacle]]
x_m = 1.0
y_m = 1.0
size_x_m = 0.0
size_y_m = 0.5
)";
  std::string error;
  EXPECT_FALSE(load_drive_scenario_string(text, "bad.toml", nullptr, &error));
  EXPECT_NE(error.find("inside the drive area"), std::string::npos) << error;
  EXPECT_NE(error.find("size_x_m"), std::string::npos) << error;
}

}  // namespace obstacle_world_test
