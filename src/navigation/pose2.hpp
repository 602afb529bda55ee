#pragma once
// The plane the follower works in: the odom frame's x and y in metres, yaw
// in radians counter-clockwise from x; a base's command as REP 103 has it
// (linear forward along base_link's x, angular counter-clockwise positive).
#include <cmath>

namespace rtfuse::navigation {

struct Point2 {
  double x = 0.0;
  double y = 0.0;
};

struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;
};

struct Velocity2 {
  double linear = 0.0;   // m/s
  double angular = 0.0;  // rad/s
};

// Coordinates farther than this from the odom origin are refused as
// garbage: no robot drives 1000 km on one odometry frame, and within it
// squared distances (at most about 1.6e13) neither overflow nor lose the
// millimetres.
inline constexpr double kMaxCoordinateM = 1e6;

inline bool finite(const Point2& p) noexcept { return std::isfinite(p.x) && std::isfinite(p.y); }
inline bool finite(const Pose2& p) noexcept { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.yaw); }
inline bool finite(const Velocity2& v) noexcept { return std::isfinite(v.linear) && std::isfinite(v.angular); }

// Finite and within kMaxCoordinateM on both axes (any finite yaw: it is
// only ever read through sin and cos).
inline bool usable(const Point2& p) noexcept {
  return std::fabs(p.x) <= kMaxCoordinateM && std::fabs(p.y) <= kMaxCoordinateM;  // false for NaN
}
inline bool usable(const Pose2& p) noexcept { return usable(Point2{p.x, p.y}) && std::isfinite(p.yaw); }

}  // namespace rtfuse::navigation
