#include "navigation/path_follower.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rtfuse::navigation {

namespace {

double follower_length(double dx, double dy) noexcept { return std::sqrt(dx * dx + dy * dy); }

// The point where the segment from s to e leaves the circle of radius L
// around r, s inside it and e on or outside: the larger root of
// |s - r + t (e - s)| = L, in [0, 1].
Point2 follower_circle_exit(Point2 r, Point2 s, Point2 e, double lookahead) noexcept {
  const double dx = e.x - s.x, dy = e.y - s.y;
  const double fx = s.x - r.x, fy = s.y - r.y;
  const double a = dx * dx + dy * dy;
  if (!(a > 0.0)) return e;
  const double b = 2.0 * (fx * dx + fy * dy);
  const double c = fx * fx + fy * fy - lookahead * lookahead;  // <= 0: s is inside
  // c <= 0 makes the discriminant at least b^2; the max keeps a rounding
  // from taking the root of a negative.
  const double disc = std::max(0.0, b * b - 4.0 * a * c);
  const double t = std::clamp((-b + std::sqrt(disc)) / (2.0 * a), 0.0, 1.0);
  return Point2{s.x + t * dx, s.y + t * dy};
}

}  // namespace

PathFollower::PathFollower(const FollowerParams& params, int max_points) : params_(params), capacity_(max_points) {
  std::string error;
  if (!params.check(&error)) throw std::invalid_argument("path follower: " + error);
  if (max_points < 1 || max_points > kMaxFollowPathPoints) {
    throw std::invalid_argument("path follower: max_points must be in [1, " + std::to_string(kMaxFollowPathPoints) +
                                "]");
  }
  points_.reset(new Point2[static_cast<std::size_t>(max_points)]);
  along_.reset(new double[static_cast<std::size_t>(max_points)]);
}

PathFollower::~PathFollower() = default;

bool PathFollower::set_path(const Point2* points, int n) noexcept {
  clear_path();
  if (points == nullptr || n < 1 || n > capacity_) return false;
  for (int i = 0; i < n; ++i) {
    if (!usable(points[i])) return false;
  }
  double along = 0.0;
  for (int i = 0; i < n; ++i) {
    if (i > 0) along += follower_length(points[i].x - points[i - 1].x, points[i].y - points[i - 1].y);
    points_[i] = points[i];
    along_[i] = along;
  }
  size_ = n;
  progress_point_ = points_[0];
  return true;
}

void PathFollower::clear_path() noexcept {
  size_ = 0;
  progress_ = 0;
  progress_along_ = 0.0;
  progress_point_ = Point2{};
  reached_ = false;
}

FollowResult PathFollower::follow(const Pose2& robot, double speed_mps) noexcept {
  FollowResult out;
  if (size_ == 0) return out;  // kNoPath, zero
  const Point2 last = points_[size_ - 1];
  // Without a pose, or once reached: the last nearest point, zero.
  out.nearest_index = progress_;
  out.nearest = progress_point_;
  out.remaining_m = std::max(0.0, along_[size_ - 1] - progress_along_);
  if (reached_) {
    out.state = FollowState::kReached;
    out.lookahead = last;
    return out;
  }
  if (!usable(robot)) {
    out.state = FollowState::kBadPose;
    return out;
  }
  const Point2 r{robot.x, robot.y};

  // The nearest point, from where the last one was, forward only.
  int best = progress_;
  double best_t = 0.0;
  double best_d2 = 0.0;
  if (size_ == 1) {
    best_d2 = (r.x - last.x) * (r.x - last.x) + (r.y - last.y) * (r.y - last.y);
  } else {
    bool first = true;
    for (int i = progress_, looked = 0; i + 1 < size_ && looked < kFollowWindowSegments; ++i, ++looked) {
      if (i > progress_ && along_[i] - progress_along_ > params_.search_window_m) break;
      const Point2 a = points_[i], b = points_[i + 1];
      const double dx = b.x - a.x, dy = b.y - a.y;
      const double len2 = dx * dx + dy * dy;
      double t = 0.0;
      if (len2 > 0.0) t = std::clamp(((r.x - a.x) * dx + (r.y - a.y) * dy) / len2, 0.0, 1.0);
      const double qx = a.x + t * dx - r.x, qy = a.y + t * dy - r.y;
      const double d2 = qx * qx + qy * qy;
      if (first || d2 <= best_d2) {  // a tie goes to the later segment: progress
        first = false;
        best = i;
        best_t = t;
        best_d2 = d2;
      }
    }
  }
  progress_ = best;
  out.nearest_index = best;
  if (size_ == 1) {
    out.nearest = last;
    out.remaining_m = 0.0;
  } else {
    const Point2 a = points_[best], b = points_[best + 1];
    out.nearest = Point2{a.x + best_t * (b.x - a.x), a.y + best_t * (b.y - a.y)};
    const double segment = along_[best + 1] - along_[best];
    out.remaining_m = std::max(0.0, (along_[size_ - 1] - along_[best + 1]) + (1.0 - best_t) * segment);
    // Never behind the last one, even by a rounding: the window is
    // measured from here.
    progress_along_ = std::max(progress_along_, along_[best] + best_t * segment);
  }
  progress_point_ = out.nearest;
  out.cross_track_m = std::sqrt(best_d2);

  const double to_goal = follower_length(last.x - r.x, last.y - r.y);
  if (to_goal <= params_.goal_tolerance_m && out.remaining_m <= params_.goal_tolerance_m) {
    reached_ = true;
    out.state = FollowState::kReached;
    out.lookahead = last;
    return out;
  }

  const double speed = std::isfinite(speed_mps) ? std::fabs(speed_mps) : 0.0;
  // speed up to 1e308 times at most 10 s stays finite; the clamp does the rest.
  const double lookahead =
      std::clamp(std::min(speed, 1e300) * params_.lookahead_time_s, params_.min_lookahead_m, params_.max_lookahead_m);
  out.lookahead_m = lookahead;

  // The lookahead point, walking on from the nearest point.
  const double l2 = lookahead * lookahead;
  const auto outside = [&](Point2 p) noexcept {
    return (p.x - r.x) * (p.x - r.x) + (p.y - r.y) * (p.y - r.y) >= l2;
  };
  Point2 carrot = out.nearest;
  if (!outside(carrot)) {
    Point2 s = out.nearest;
    int j = best;
    bool found = false;
    for (int looked = 0; j + 1 < size_ && looked < kFollowWindowSegments; ++j, ++looked) {
      const Point2 e = points_[j + 1];
      if (outside(e)) {
        carrot = follower_circle_exit(r, s, e, lookahead);
        found = true;
        break;
      }
      s = e;
    }
    // All within L: the end of what was walked, the path's end unless the
    // walk's bound stopped it first.
    if (!found) carrot = s;
  }
  out.lookahead = carrot;

  // The lookahead point in base_link.
  const double c = std::cos(robot.yaw), sn = std::sin(robot.yaw);
  const double dx = carrot.x - r.x, dy = carrot.y - r.y;
  const double xl = c * dx + sn * dy;
  const double yl = -sn * dx + c * dy;
  const double d2 = xl * xl + yl * yl;
  const double& v_max = params_.max_linear_mps;
  const double& w_max = params_.max_angular_rps;
  if (!(d2 > 1e-12)) {
    // The point pursued is under the robot, not reached: only where a path
    // runs through its own end before it. No direction to drive in, so
    // none; the nearest point moves on over the next calls.
    out.state = FollowState::kTracking;
    return out;
  }
  const double heading_error = std::atan2(yl, xl);
  if (std::fabs(heading_error) > params_.rotate_to_heading_min_angle_rad) {
    out.state = FollowState::kRotating;
    out.command = Velocity2{0.0, heading_error > 0.0 ? w_max : -w_max};
    return out;
  }

  const double curvature = 2.0 * yl / d2;
  out.curvature = curvature;
  const double bend = std::fabs(curvature);
  double v = v_max;
  // r / r_min = 1 / (|curvature| r_min), for radii below r_min.
  if (params_.regulated_min_radius_m > 0.0 && bend * params_.regulated_min_radius_m > 1.0) {
    v = v_max / (bend * params_.regulated_min_radius_m);
  }
  // The distance left is the path's, or the straight line to the goal when
  // that is longer: a robot off the path near its end, or a one-point
  // path, is not yet near the goal.
  const double left = std::max(out.remaining_m, to_goal);
  if (params_.approach_distance_m > 0.0 && left < params_.approach_distance_m) {
    const double approach = v * (left / params_.approach_distance_m);
    v = std::min(v, std::max(approach, params_.min_approach_speed_mps));
  }
  double w = v * curvature;
  if (std::fabs(w) > w_max) {
    v = w_max / bend;  // the same arc, at the angular limit
    w = curvature > 0.0 ? w_max : -w_max;
  }
  out.state = FollowState::kTracking;
  out.command = Velocity2{std::clamp(v, 0.0, v_max), std::clamp(w, -w_max, w_max)};
  if (!finite(out.command)) out.command = Velocity2{};  // cannot happen; never let it out
  return out;
}

}  // namespace rtfuse::navigation
