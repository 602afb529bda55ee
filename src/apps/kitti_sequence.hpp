#pragma once
// A folder in the layout of the KITTI odometry benchmark: image_l/ and
// image_r/ (or KITTI's own image_0/ and image_1/) with one 8-bit PNG per
// frame, calib.txt with the rectified projection matrices P0 and P1, and,
// when present, poses.txt (the ground truth: a 3x4 row-major pose of the
// left camera in the first one's frame per line). For rtfuse-vo; allocates,
// reads files.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vision/stereo_egomotion.hpp"

namespace rtfuse::apps {

// P0 and P1 of calib.txt: lines "P0: 12 numbers" (labels optional: without
// them the first two lines are P0 and P1; other labelled lines such as P2,
// P3, Tr are ignored). False with "<name>:<line>: what" on anything else,
// and when P1 is missing or does not describe a rectified pair to the right.
bool parse_kitti_calibration(const std::string& text, const std::string& name, vision::StereoCameraModel* camera,
                             std::string* error);

// Poses, one per line; "<name>:<line>: what" on a malformed line.
bool parse_kitti_poses(const std::string& text, const std::string& name, std::vector<Eigen::Matrix4d>* poses,
                       std::string* error);

// One line of a KITTI pose file for pose (12 numbers, %.9e).
std::string kitti_pose_line(const Eigen::Matrix4d& pose);

struct KittiSequence {
  std::string dir;
  std::vector<std::string> left, right;  // per frame; "" where that eye's image is missing
  vision::StereoCameraModel camera;
  std::vector<Eigen::Matrix4d> ground_truth;  // empty without poses.txt
};

// Lists the frames (the PNG names of the left folder, sorted; a right image
// of the same name) and reads calib.txt and poses.txt. False with a message
// naming the folder or file and the fix.
bool open_kitti_sequence(const std::string& dir, KittiSequence* out, std::string* error);

}  // namespace rtfuse::apps
