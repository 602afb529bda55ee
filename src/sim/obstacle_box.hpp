#pragma once
// A solid a scenario stands inside the drive area (a pillar, a box, one
// side of a narrow passage), for the camera to see and the mapper to find:
// on the floor, sides along the world's axes.
namespace rtfuse::sim {

struct ObstacleBox {
  double x = 0.0, y = 0.0;             // centre, odom frame, metres
  double size_x = 0.5, size_y = 0.5;   // footprint
  double height = 1.0;
};

}  // namespace rtfuse::sim
