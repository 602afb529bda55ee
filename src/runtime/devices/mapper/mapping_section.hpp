#pragma once
// [mapping]: the occupancy map built from the camera's keyframes on a
// thread of its own (mapper_device.hpp). Plain values; the mapper turns
// them into the mapping layer's parameters. Schema: docs/configuration.md.
#include <string>

#include "runtime/config/name.hpp"

namespace rtfuse {

struct MappingSection {
  bool enabled = false;
  // Keyframes: a pair at most this often (capture stamps), and, when either
  // is positive, only after the robot moved or turned this much since the
  // last one mapped (a robot standing still maps nothing new).
  double keyframe_interval_s = 0.2;
  double keyframe_distance_m = 0.0;
  double keyframe_angle_rad = 0.0;
  // A keyframe is placed with the filter's pose at its capture stamp as the
  // loop had it this long after the stamp (so the measurements of that
  // instant are in); no estimate then and it is dropped, counted.
  double pose_delay_s = 0.1;
  // Dense disparity: disparities searched (input pixels) and the downscale.
  int disparities = 64;
  bool half_resolution = true;
  int min_texture = 4;  // grey levels of mean horizontal change a pixel needs (0: keep all)
  // The map: OctoMap's sensor model and defaults.
  double resolution_m = 0.05;
  double max_range_m = 6.0;
  double prob_hit = 0.7;
  double prob_miss = 0.4;
  double clamp_min = 0.1192;
  double clamp_max = 0.971;
  double occupancy_threshold = 0.5;
  int memory_mb = 128;  // the map's fixed pool; full: the map stops growing, counted
  // The 2-D grid: a square of grid_size_m centred on the map frame's origin,
  // voxels between the two heights projected, published at grid_rate_hz (of
  // capture time, with the keyframes that changed it).
  double grid_rate_hz = 1.0;
  double grid_size_m = 20.0;
  double grid_min_z_m = 0.1;
  double grid_max_z_m = 2.0;
  Name grid_channel{"rtfuse/map"};
  // At exit: <output>.bt, <output>.pgm + <output>.yaml and <output>.png
  // ("": none). Relative to the working directory.
  std::string output;
};

}  // namespace rtfuse
