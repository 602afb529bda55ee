#include "drivers/camera/stereo_rectification.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "drivers/config_error.hpp"

namespace rtfuse::drivers {

namespace {

constexpr const char* kWho = "stereo rectification";
constexpr double kMaxRelativeRotationRad = 0.5;

// cv::undistortPoints on one point with OpenCV's default stopping rule (five
// fixed-point iterations, not a convergence test): stereoRectify sizes its
// views from these approximate positions, so matching its figures means
// iterating the same way. Returns the normalised (undistorted) coordinates.
Eigen::Vector2d undistort_normalised(const CameraIntrinsics& k, double u, double v) {
  const double ifx = 1.0 / k.fx;
  const double ify = 1.0 / k.fy;
  const double x0 = (u - k.cx) * ifx;
  const double y0 = (v - k.cy) * ify;
  double x = x0;
  double y = y0;
  for (int i = 0; i < 5; ++i) {
    const double r2 = x * x + y * y;
    const double icdist = 1.0 / (1.0 + ((k.k3 * r2 + k.k2) * r2 + k.k1) * r2);
    if (icdist < 0.0) {  // past the distortion model's fold: OpenCV gives up here
      x = x0;
      y = y0;
      break;
    }
    const double dx = 2.0 * k.p1 * x * y + k.p2 * (r2 + 2.0 * x * x);
    const double dy = k.p1 * (r2 + 2.0 * y * y) + 2.0 * k.p2 * x * y;
    x = (x0 - dx) * icdist;
    y = (y0 - dy) * icdist;
  }
  return {x, y};
}

// A raw pixel's undistorted position in a rectified eye's pixels
// (cv::undistortPoints with R and P), rounded to float as OpenCV's point
// arrays are.
Eigen::Vector2f raw_to_rectified(const CameraIntrinsics& k, const Eigen::Matrix3d& rr, float u, float v) {
  const Eigen::Vector2d n = undistort_normalised(k, u, v);
  const Eigen::Vector3d p = rr * Eigen::Vector3d(n.x(), n.y(), 1.0);
  const double w = 1.0 / p.z();
  return {static_cast<float>(p.x() * w), static_cast<float>(p.y() * w)};
}

struct RectF {
  float x = 0, y = 0, width = 0, height = 0;
};

// The largest rectangle inside, and the smallest around, the rectified image
// of the raw image's border, sampled on a 9 x 9 grid (OpenCV's way).
void view_rectangles(const CameraIntrinsics& k, const Eigen::Matrix3d& r, const Eigen::Matrix<double, 3, 4>& p, int width,
                     int height, RectF* inner, RectF* outer) {
  constexpr int kN = 9;
  const Eigen::Matrix3d rr = p.leftCols<3>() * r;
  float ix0 = -FLT_MAX, ix1 = FLT_MAX, iy0 = -FLT_MAX, iy1 = FLT_MAX;
  float ox0 = FLT_MAX, ox1 = -FLT_MAX, oy0 = FLT_MAX, oy1 = -FLT_MAX;
  for (int y = 0; y < kN; ++y) {
    for (int x = 0; x < kN; ++x) {
      const float u = static_cast<float>(x) * static_cast<float>(width) / (kN - 1);
      const float v = static_cast<float>(y) * static_cast<float>(height) / (kN - 1);
      const Eigen::Vector2f q = raw_to_rectified(k, rr, u, v);
      ox0 = std::min(ox0, q.x());
      ox1 = std::max(ox1, q.x());
      oy0 = std::min(oy0, q.y());
      oy1 = std::max(oy1, q.y());
      if (x == 0) ix0 = std::max(ix0, q.x());
      if (x == kN - 1) ix1 = std::min(ix1, q.x());
      if (y == 0) iy0 = std::max(iy0, q.y());
      if (y == kN - 1) iy1 = std::min(iy1, q.y());
    }
  }
  *inner = {ix0, iy0, ix1 - ix0, iy1 - iy0};
  *outer = {ox0, oy0, ox1 - ox0, oy1 - oy0};
}

bool finite_intrinsics(const CameraIntrinsics& k) {
  const double v[] = {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1, k.p2, k.k3};
  for (double x : v) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

}  // namespace

Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& r) noexcept {
  const double theta = std::sqrt(r.dot(r));
  if (theta < DBL_EPSILON) return Eigen::Matrix3d::Identity();
  const Eigen::Vector3d k = r / theta;
  const double c = std::cos(theta);
  const double s = std::sin(theta);
  Eigen::Matrix3d kx;
  kx << 0.0, -k.z(), k.y(), k.z(), 0.0, -k.x(), -k.y(), k.x(), 0.0;
  return c * Eigen::Matrix3d::Identity() + (1.0 - c) * (k * k.transpose()) + s * kx;
}

// The steps and their order are cv::stereoRectify's (calib3d, OpenCV 4.6):
// split the relative rotation in two halves so both cameras turn by the same
// amount, then turn both about the axis that brings the baseline onto x;
// focal length from the mean fy; principal points from the mean position of
// the undistorted, rotated image corners; with CALIB_ZERO_DISPARITY both
// eyes share one principal point; finally alpha = 0 scales the focal length
// until the rectified views hold no pixel from outside the raw images.
bool compute_stereo_rectification(const StereoCalibration& c, StereoRectification* out, std::string* error) {
  if (c.width <= 0 || c.height <= 0) {
    return config_fail(error, kWho, "image size %d x %d: must be positive", c.width, c.height);
  }
  if (!finite_intrinsics(c.left) || !finite_intrinsics(c.right) || !c.rotation.allFinite() ||
      !c.translation.allFinite()) {
    return config_fail(error, kWho, "calibration holds a non-finite value (NaN or infinity)");
  }
  if (c.left.fx <= 0.0 || c.left.fy <= 0.0 || c.right.fx <= 0.0 || c.right.fy <= 0.0) {
    return config_fail(error, kWho, "focal lengths left %g x %g, right %g x %g px: must be > 0", c.left.fx, c.left.fy,
                       c.right.fx, c.right.fy);
  }
  const double angle = std::sqrt(c.rotation.dot(c.rotation));
  if (angle > kMaxRelativeRotationRad) {
    return config_fail(error, kWho,
                       "the eyes are rotated %.3f rad from each other (more than %.1f): not a side-by-side pair; check "
                       "the rotation's units (radians)",
                       angle, kMaxRelativeRotationRad);
  }
  const double width = c.width;
  const double height = c.height;

  // Half the relative rotation, backwards: applied to the right camera and
  // its transpose to the left one, both end up with the same orientation.
  const Eigen::Matrix3d r_half = rotation_from_vector(-0.5 * c.rotation);
  Eigen::Vector3d t = r_half * c.translation;
  if (!(std::fabs(t.x()) > std::fabs(t.y())) || std::fabs(t.x()) <= 0.0) {
    return config_fail(error, kWho,
                       "translation (%g, %g, %g) m is not mostly along x: only side-by-side (horizontal) pairs are "
                       "supported",
                       c.translation.x(), c.translation.y(), c.translation.z());
  }
  // The rotation that brings t onto the x axis (same direction as t.x): its
  // angle is acos(|t.x| / |t|), taken as atan2 of the cross product's norm
  // (acos is not among the functions checked to round alike on both
  // architectures).
  const double cx_sign = t.x() > 0.0 ? 1.0 : -1.0;
  Eigen::Vector3d w = t.cross(Eigen::Vector3d(cx_sign, 0.0, 0.0));
  const double nw = std::sqrt(w.dot(w));
  if (nw > 0.0) w *= std::atan2(nw, std::fabs(t.x())) / nw;
  const Eigen::Matrix3d w_r = rotation_from_vector(w);
  const Eigen::Matrix3d r1 = w_r * r_half.transpose();
  const Eigen::Matrix3d r2 = w_r * r_half;
  t = r2 * c.translation;

  double f = (c.left.fy + c.right.fy) * 0.5;
  double ccx[2] = {0.0, 0.0};
  double ccy[2] = {0.0, 0.0};
  for (int k = 0; k < 2; ++k) {
    const CameraIntrinsics& cam = k == 0 ? c.left : c.right;
    const Eigen::Matrix3d& r = k == 0 ? r1 : r2;
    double sx = 0.0, sy = 0.0;
    for (int i = 0; i < 4; ++i) {
      const float u = static_cast<float>((i % 2) * (width - 1));
      const float v = static_cast<float>((i < 2 ? 0 : 1) * (height - 1));
      const Eigen::Vector2d n = undistort_normalised(cam, u, v);
      const Eigen::Vector3d p = r * Eigen::Vector3d(n.x(), n.y(), 1.0);
      // projectPoints with focal f and principal point 0, stored as float.
      sx += static_cast<float>(f * p.x() / p.z());
      sy += static_cast<float>(f * p.y() / p.z());
    }
    ccx[k] = (width - 1) / 2 - sx / 4;
    ccy[k] = (height - 1) / 2 - sy / 4;
  }
  // CALIB_ZERO_DISPARITY: one principal point for both eyes.
  ccx[0] = ccx[1] = (ccx[0] + ccx[1]) * 0.5;
  ccy[0] = ccy[1] = (ccy[0] + ccy[1]) * 0.5;

  Eigen::Matrix<double, 3, 4> p1 = Eigen::Matrix<double, 3, 4>::Zero();
  p1(0, 0) = p1(1, 1) = f;
  p1(0, 2) = ccx[0];
  p1(1, 2) = ccy[0];
  p1(2, 2) = 1.0;
  Eigen::Matrix<double, 3, 4> p2 = p1;
  p2(0, 2) = ccx[1];
  p2(1, 2) = ccy[1];
  p2(0, 3) = t.x() * f;

  RectF inner[2], outer[2];
  view_rectangles(c.left, r1, p1, c.width, c.height, &inner[0], &outer[0]);
  view_rectangles(c.right, r2, p2, c.width, c.height, &inner[1], &outer[1]);

  // alpha = 0: the smallest zoom that keeps every border of both views'
  // inscribed rectangles outside the image.
  double s = -DBL_MAX;
  for (int k = 0; k < 2; ++k) {
    const double cx0 = ccx[k];
    const double cy0 = ccy[k];
    const double cx1 = width * cx0 / width;
    const double cy1 = height * cy0 / height;
    const RectF& in = inner[k];
    s = std::max(s, cx1 / (cx0 - in.x));
    s = std::max(s, cy1 / (cy0 - in.y));
    s = std::max(s, (width - cx1) / (static_cast<float>(in.x + in.width) - cx0));
    s = std::max(s, (height - cy1) / (static_cast<float>(in.y + in.height) - cy0));
  }
  if (!std::isfinite(s) || s <= 0.0) {
    return config_fail(error, kWho,
                       "no rectified view fits inside both raw images (scale %g): the distortion or rotation is too "
                       "strong for this calibration; check k1/k2/k3 and the rotation",
                       s);
  }
  f *= s;
  p1(0, 0) = p1(1, 1) = f;
  p2(0, 0) = p2(1, 1) = f;
  p2(0, 3) *= s;

  StereoRectification& o = *out;
  o.width = c.width;
  o.height = c.height;
  o.left.rotation = r1;
  o.left.projection = p1;
  o.right.rotation = r2;
  o.right.projection = p2;
  o.q = Eigen::Matrix4d::Zero();
  o.q(0, 0) = 1.0;
  o.q(0, 3) = -ccx[0];
  o.q(1, 1) = 1.0;
  o.q(1, 3) = -ccy[0];
  o.q(2, 3) = f;
  o.q(3, 2) = -1.0 / t.x();
  o.q(3, 3) = (ccx[0] - ccx[1]) / t.x();
  o.fx = f;
  o.fy = f;
  o.cx = ccx[0];
  o.cy = ccy[0];
  o.baseline_m = std::fabs(t.x());
  return true;
}

RawPositionMap::RawPositionMap(const CameraIntrinsics& raw, const RectifiedEye& eye)
    : raw_(raw), inverse_((eye.projection.leftCols<3>() * eye.rotation).inverse()) {}

// cv::initUndistortRectifyMap's per-pixel formula: back-project the
// rectified pixel to a ray, turn it into the raw camera's frame, distort
// with the plumb-bob model, project with the raw camera matrix.
bool RawPositionMap::at(double u, double v, double* x_out, double* y_out) const noexcept {
  const Eigen::Vector3d ray = inverse_ * Eigen::Vector3d(u, v, 1.0);
  if (!(ray.z() > 0.0)) return false;
  const double iw = 1.0 / ray.z();
  const double x = ray.x() * iw;
  const double y = ray.y() * iw;
  const double x2 = x * x;
  const double y2 = y * y;
  const double r2 = x2 + y2;
  const double xy2 = 2.0 * x * y;
  const double kr = 1.0 + ((raw_.k3 * r2 + raw_.k2) * r2 + raw_.k1) * r2;
  *x_out = raw_.fx * (x * kr + raw_.p1 * xy2 + raw_.p2 * (r2 + 2.0 * x2)) + raw_.cx;
  *y_out = raw_.fy * (y * kr + raw_.p1 * (r2 + 2.0 * y2) + raw_.p2 * xy2) + raw_.cy;
  return true;
}

}  // namespace rtfuse::drivers
