#pragma once
// Point clouds from a KITTI-layout folder of rectified pairs: each chosen
// frame's dense disparity (the runtime's matcher, textureless pixels taken
// back: vision/texture_filter.hpp), back-projected and
// carried into the first camera's frame by a pose per frame (the ground
// truth, or the visual odometry's). What rtfuse-map maps offline and what
// the OctoMap reference test inserts into both maps. Allocates, reads files.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "apps/kitti_sequence.hpp"
#include "mapping/disparity_points.hpp"
#include "mapping/map_point.hpp"
#include "vision/disparity_params.hpp"

namespace rtfuse::apps {

struct StereoCloud {
  int frame = 0;
  mapping::MapPoint origin;  // the left camera's centre
  std::vector<mapping::MapPoint> points;
  mapping::DisparityPointCounts counts;
  double disparity_ms = 0.0;  // matching and the texture filter
};

// Frames `frames` of seq with poses[frame] (left camera k in camera 0's
// frame). False with *error naming the frame's file and the cause.
bool stereo_clouds(const KittiSequence& seq, const std::vector<Eigen::Matrix4d>& poses, const std::vector<int>& frames,
                   const vision::DisparityParams& params, std::vector<StereoCloud>* out, std::string* error);

}  // namespace rtfuse::apps
