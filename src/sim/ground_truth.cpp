#include "sim/ground_truth.hpp"

#include <cmath>

namespace rtfuse::sim {

namespace {
// Assigning the same short literal again is a compare, never a reallocation.
void set_name(std::string& s, const char* name) noexcept {
  if (s != name) s = name;
}
}  // namespace

void fill_ground_truth(const TruthState& truth, TimeNs stamp, std::int32_t seq, rtfuse::odometry_t* msg) noexcept {
  if (msg == nullptr) return;
  msg->header.utime = ns_to_utime(stamp);
  msg->header.seq = seq;
  set_name(msg->header.frame_id, kGroundTruthFrame);
  set_name(msg->child_frame_id, kGroundTruthChildFrame);

  auto& pose = msg->pose.pose;
  pose.position.x = truth.x;
  pose.position.y = truth.y;
  pose.position.z = 0.0;
  // Yaw only (flat floor): q = (cos(yaw/2), 0, 0, sin(yaw/2)).
  pose.orientation.w = std::cos(0.5 * truth.yaw);
  pose.orientation.x = 0.0;
  pose.orientation.y = 0.0;
  pose.orientation.z = std::sin(0.5 * truth.yaw);

  auto& twist = msg->twist.twist;  // in the child frame, base_link
  twist.linear.x = truth.speed;
  twist.linear.y = 0.0;
  twist.linear.z = 0.0;
  twist.angular.x = 0.0;
  twist.angular.y = 0.0;
  twist.angular.z = truth.yaw_rate;

  for (double& c : msg->pose.covariance) c = 0.0;
  for (double& c : msg->twist.covariance) c = 0.0;
}

}  // namespace rtfuse::sim
