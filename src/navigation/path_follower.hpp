#pragma once
// Regulated pure pursuit (Nav2's RegulatedPurePursuitController, its
// semantics): the robot steers along the arc through the point of the path
// a lookahead distance away, at a speed the arc's tightness and the
// distance left regulate.
//
// Per call, with the path in the odom frame:
//  - the nearest point: the point of the path's segments nearest the
//    robot, looked for from the last one forward, in the segments that
//    start within search_window_m along the path of it (and at most
//    kFollowWindowSegments of them), ties to the later segment. Progress
//    never goes back, and the work per call is bounded whatever the
//    path's size. A robot far along a new path is found a window per call
//    (Nav2's max_robot_pose_search_dist).
//  - the lookahead distance L = |speed| * lookahead_time_s within
//    [min_lookahead_m, max_lookahead_m]; the lookahead point is where the
//    path, from the nearest point on, first leaves the circle of radius L
//    around the robot, interpolated on its segment; the path's last point
//    when all of the rest is within L; the nearest point itself when that
//    is already L away (the robot is off the path: it heads back).
//  - reached: within goal_tolerance_m of the last point, with no more than
//    that left along the path (a path that passes its own end earlier is
//    not reached there). Zero from then until the next set_path, whatever
//    the pose: reaching is not undone by drifting.
//  - turning in place: when the lookahead point is more than
//    rotate_to_heading_min_angle_rad off the heading, zero linear and the
//    full angular rate toward it. This is how a path that starts behind
//    the robot is taken: the follower never reverses.
//  - otherwise pursuit: curvature 2 y / d^2 (y the lookahead point's
//    lateral offset in base_link, d its distance), linear max_linear_mps
//    scaled by r / regulated_min_radius_m where the radius r = 1 / |curvature|
//    is smaller, then within approach_distance_m of the end by the
//    distance left / approach_distance_m, not below min_approach_speed_mps
//    (the distance left: along the path from the nearest point, or the
//    straight line to the last point when that is longer);
//    angular = linear * curvature, and where that exceeds max_angular_rps,
//    linear is lowered so that the arc stays the same.
//
// Every command is finite, linear in [0, max_linear_mps], |angular| at
// most max_angular_rps; the acceleration limits are the gate's
// (command_gate.hpp). Pure: no clock, no I/O; the path's storage is
// allocated by the constructor, nothing after.
#include <cstdint>
#include <memory>

#include "navigation/follower_params.hpp"
#include "navigation/pose2.hpp"

namespace rtfuse::navigation {

// The most segments one call looks through, for the nearest point and
// again for the lookahead point: a path of many tiny or repeated points
// costs no more per call than this.
inline constexpr int kFollowWindowSegments = 1024;
// The largest capacity a follower is built with.
inline constexpr int kMaxFollowPathPoints = 1 << 20;

enum class FollowState : std::uint8_t {
  kNoPath,    // no path set: zero
  kBadPose,   // the robot's pose is not finite or absurdly far: zero
  kRotating,  // turning in place toward the lookahead point
  kTracking,  // pure pursuit
  kReached,   // at the path's end: zero until the next set_path
};

struct FollowResult {
  Velocity2 command;  // wanted now, within the speed limits, not yet the acceleration limits
  FollowState state = FollowState::kNoPath;
  // The segment the nearest point is on: from path point nearest_index to
  // the next (0 for a one-point path). With a bad pose, or once reached,
  // the last nearest point found, and the distance left from it.
  int nearest_index = 0;
  Point2 nearest;             // the nearest point of the path
  Point2 lookahead;           // the point pursued
  double lookahead_m = 0.0;   // L
  double curvature = 0.0;     // of the arc to the lookahead point, 1/m, counter-clockwise positive
  double remaining_m = 0.0;   // along the path, from the nearest point to the end
  double cross_track_m = 0.0; // from the robot to the nearest point (not signed)

  bool reached() const noexcept { return state == FollowState::kReached; }
};

class PathFollower {
 public:
  // Allocates room for paths of up to max_points points, here only.
  // Throws std::invalid_argument when params.check() fails or max_points
  // is outside [1, kMaxFollowPathPoints].
  PathFollower(const FollowerParams& params, int max_points);
  ~PathFollower();
  PathFollower(const PathFollower&) = delete;
  PathFollower& operator=(const PathFollower&) = delete;

  // Takes a copy of points[0..n) (odom frame, metres) and starts from its
  // first segment, not reached. Refuses (false, and no path kept: the old
  // one is not followed either) n < 1, n over the capacity, a null
  // pointer or a point that is not usable() (not finite, or beyond
  // kMaxCoordinateM). Repeated points are allowed.
  bool set_path(const Point2* points, int n) noexcept;
  void clear_path() noexcept;

  // The command for the robot at pose robot, driving at speed_mps (the
  // odometry's forward speed, or the last command sent: it sets the
  // lookahead distance; not finite counts as 0).
  FollowResult follow(const Pose2& robot, double speed_mps) noexcept;

  bool has_path() const noexcept { return size_ > 0; }
  int path_size() const noexcept { return size_; }
  const Point2* path() const noexcept { return points_.get(); }
  int capacity() const noexcept { return capacity_; }
  // The segment the last nearest point was on: where the next search starts.
  int progress() const noexcept { return progress_; }
  const FollowerParams& params() const noexcept { return params_; }

 private:
  FollowerParams params_;
  int capacity_ = 0;
  int size_ = 0;
  int progress_ = 0;
  double progress_along_ = 0.0;  // the last nearest point's distance along the path
  Point2 progress_point_;        // and the point
  bool reached_ = false;
  std::unique_ptr<Point2[]> points_;
  std::unique_ptr<double[]> along_;  // path length from the first point to each
};

}  // namespace rtfuse::navigation
