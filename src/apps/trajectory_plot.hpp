#pragma once
// A top view of camera trajectories as a PNG (x right, z forward of the
// first camera; the ground truth black, the estimate red, equal scale on
// both axes): the picture to judge a visual odometry run at a glance. A
// tool's writer (allocates, does file I/O).
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rtfuse::apps {

// truth may be empty. False and *error naming the path and the cause.
bool write_trajectory_plot(const std::string& path, const std::vector<Eigen::Matrix4d>& estimate,
                           const std::vector<Eigen::Matrix4d>& truth, std::string* error);

}  // namespace rtfuse::apps
