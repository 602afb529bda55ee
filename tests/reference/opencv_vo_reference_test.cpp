// vision::StereoOdometry against an independent stereo odometry built from
// OpenCV (test-only): Shi-Tomasi corners tracked by pyramidal Lucas-Kanade
// into the right image and the next left image (forward-backward checked),
// triangulated from the previous pair, cv::solvePnPRansac + LM refinement
// into the current left image. Different features, matching and cost; the
// same real KITTI 06 frames of ../shared/data.
//
// Why this reference exists: the ground truth of frames 1-11 of these
// frames is a constant twist (the same rotation per frame to 1e-4 deg in
// all three axes, an interpolation over a gap of the GPS/IMU, not a car's
// motion), and there both image-based estimators agree with each other and
// not with it, by about 0.5 deg of yaw and 0.6 deg of roll over the eleven
// frames. From frame 12 on the ground truth is measured and the VO follows
// it closely. The tests pin those three facts, so the VO's accuracy on
// these frames is judged where the ground truth can judge it
// (docs/performance.md, "Stereo visual odometry").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "apps/grey_png.hpp"
#include "apps/kitti_sequence.hpp"
#include "apps/trajectory_metrics.hpp"
#include "vision/stereo_odometry.hpp"

namespace {

using rtfuse::apps::GreyPng;
using rtfuse::apps::KittiSequence;
using rtfuse::vision::StereoCameraModel;

const std::string kSeq = std::string(RTFUSE_SHARED_DATA) + "/kitti/kitti06_0000_0050";
constexpr double kPi = 3.14159265358979323846;

// Per frame k >= 1: the motion previous left camera -> current left camera
// (x_cur = T x_prev) of each estimator and of the ground truth.
struct Motions {
  std::vector<Eigen::Matrix4d> vo, opencv, truth;
  bool ok = false;
  std::string error;
};

cv::Mat mat_of(const GreyPng& g) {
  return cv::Mat(g.height, g.width, CV_8UC1, const_cast<std::uint8_t*>(g.pixels.data()));
}

// LK from a to b, kept where tracking back from b lands within 0.3 px.
std::vector<unsigned char> track(const cv::Mat& a, const cv::Mat& b, const std::vector<cv::Point2f>& from,
                                 std::vector<cv::Point2f>* to) {
  const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 0.001);
  std::vector<unsigned char> st, st_back;
  std::vector<float> err;
  std::vector<cv::Point2f> back;
  cv::calcOpticalFlowPyrLK(a, b, from, *to, st, err, cv::Size(21, 21), 4, stop);
  cv::calcOpticalFlowPyrLK(b, a, *to, back, st_back, err, cv::Size(21, 21), 4, stop);
  for (std::size_t i = 0; i < from.size(); ++i) {
    st[i] = st[i] && st_back[i] && cv::norm(back[i] - from[i]) < 0.3;
  }
  return st;
}

bool opencv_motion(const StereoCameraModel& cam, const cv::Mat& lp, const cv::Mat& rp, const cv::Mat& lc,
                   Eigen::Matrix4d* out) {
  std::vector<cv::Point2f> corners, right, next;
  cv::goodFeaturesToTrack(lp, corners, 3000, 0.01, 7);
  const auto in_right = track(lp, rp, corners, &right);
  const auto in_next = track(lp, lc, corners, &next);
  std::vector<cv::Point3f> points;
  std::vector<cv::Point2f> seen;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const double d = corners[i].x - right[i].x;
    if (!in_right[i] || !in_next[i] || d < 0.5 || std::abs(corners[i].y - right[i].y) > 1.0) continue;
    const double z = cam.f * cam.baseline / d;
    points.emplace_back(static_cast<float>((corners[i].x - cam.cu) * z / cam.f),
                        static_cast<float>((corners[i].y - cam.cv) * z / cam.f), static_cast<float>(z));
    seen.push_back(next[i]);
  }
  if (points.size() < 20) return false;
  const cv::Matx33d k(cam.f, 0, cam.cu, 0, cam.f, cam.cv, 0, 0, 1);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  if (!cv::solvePnPRansac(points, seen, k, cv::noArray(), rvec, tvec, false, 500, 1.0f, 0.999, inliers,
                          cv::SOLVEPNP_ITERATIVE) ||
      inliers.size() < 20) {
    return false;
  }
  std::vector<cv::Point3f> pin;
  std::vector<cv::Point2f> sin;
  for (int i : inliers) pin.push_back(points[static_cast<std::size_t>(i)]), sin.push_back(seen[static_cast<std::size_t>(i)]);
  cv::solvePnPRefineLM(pin, sin, k, cv::noArray(), rvec, tvec);
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  *out = Eigen::Matrix4d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) (*out)(i, j) = r(i, j);
    (*out)(i, 3) = tvec.at<double>(i);
  }
  return true;
}

const Motions& motions() {
  static const Motions m = [] {
    Motions out;
    KittiSequence seq;
    if (!rtfuse::apps::open_kitti_sequence(kSeq, &seq, &out.error)) return out;
    if (seq.ground_truth.size() != seq.left.size()) {
      out.error = kSeq + ": poses.txt does not have a pose per frame";
      return out;
    }
    std::vector<GreyPng> left(seq.left.size()), right(seq.left.size());
    for (std::size_t k = 0; k < seq.left.size(); ++k) {
      if (!rtfuse::apps::read_grey_png(seq.left[k], &left[k], &out.error) ||
          !rtfuse::apps::read_grey_png(seq.right[k], &right[k], &out.error)) {
        return out;
      }
    }
    const int w = left[0].width, h = left[0].height;
    rtfuse::vision::StereoOdometry vo(w, h, seq.camera, rtfuse::vision::StereoOdometryParams{});
    for (std::size_t k = 0; k < left.size(); ++k) {
      const auto r = vo.process({left[k].pixels.data(), w, h, w}, {right[k].pixels.data(), w, h, w}, k);
      if (k == 0) continue;
      if (r.status != rtfuse::vision::VoStatus::kMotion) {
        out.error = "the VO solved no motion at frame " + std::to_string(k);
        return out;
      }
      Eigen::Matrix4d cv_motion;
      if (!opencv_motion(seq.camera, mat_of(left[k - 1]), mat_of(right[k - 1]), mat_of(left[k]), &cv_motion)) {
        out.error = "the OpenCV reference solved no motion at frame " + std::to_string(k);
        return out;
      }
      out.vo.push_back(rtfuse::vision::egomotion_transform(r.motion.params));
      out.opencv.push_back(cv_motion);
      // Poses are camera -> first camera: x_cur = T_cur^-1 T_prev x_prev.
      out.truth.push_back(seq.ground_truth[k].inverse() * seq.ground_truth[k - 1]);
    }
    out.ok = true;
    return out;
  }();
  return m;
}

double angle_deg(const Eigen::Matrix3d& r) {
  return Eigen::AngleAxisd(r).angle() * 180.0 / kPi;
}

// Rotation vector (deg) of a motion, in the camera's axes (x right, y down,
// z forward: y is yaw, z is roll).
Eigen::Vector3d rotation_vector_deg(const Eigen::Matrix4d& t) {
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(t.topLeftCorner<3, 3>()));
  return aa.axis() * aa.angle() * 180.0 / kPi;
}

// Per frame from `first` (1-based frame numbers): the rotation between a and
// b's motions (deg) and the distance between their translations (m).
struct Differences {
  std::vector<double> rotation_deg, translation_m;
};
Differences differences(const std::vector<Eigen::Matrix4d>& a, const std::vector<Eigen::Matrix4d>& b, int first,
                        int last) {
  Differences d;
  for (int k = first; k <= last; ++k) {
    const Eigen::Matrix4d& x = a[static_cast<std::size_t>(k - 1)];
    const Eigen::Matrix4d& y = b[static_cast<std::size_t>(k - 1)];
    d.rotation_deg.push_back(angle_deg(x.topLeftCorner<3, 3>().transpose() * y.topLeftCorner<3, 3>()));
    d.translation_m.push_back((x.topRightCorner<3, 1>() - y.topRightCorner<3, 1>()).norm());
  }
  return d;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}
double max_of(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
}

// Mean ratio of the translations' lengths (a's over b's), frames first..last.
double scale_ratio(const std::vector<Eigen::Matrix4d>& a, const std::vector<Eigen::Matrix4d>& b, int first,
                   int last) {
  double sum = 0.0;
  for (int k = first; k <= last; ++k) {
    sum += a[static_cast<std::size_t>(k - 1)].topRightCorner<3, 1>().norm() /
           b[static_cast<std::size_t>(k - 1)].topRightCorner<3, 1>().norm();
  }
  return sum / (last - first + 1);
}

// KITTI poses (camera k -> camera 0) of per-frame motions (x_cur = T x_prev).
std::vector<Eigen::Matrix4d> poses_of(const std::vector<Eigen::Matrix4d>& motions) {
  std::vector<Eigen::Matrix4d> poses{Eigen::Matrix4d::Identity()};
  for (const Eigen::Matrix4d& m : motions) poses.push_back(poses.back() * m.inverse());
  return poses;
}

class VoReference : public ::testing::Test {
 protected:
  // In the XML report and on stdout: the figures docs/performance.md quotes.
  void report(const char* name, double value) {
    RecordProperty(name, std::to_string(value));
    std::printf("%s = %.4f\n", name, value);
  }

  void SetUp() override {
    ASSERT_TRUE(motions().ok) << motions().error;
    ASSERT_EQ(motions().vo.size(), 50u);
  }
};

// On every frame, frames 1-11 included, the two image-based estimators see
// the same motion.
TEST_F(VoReference, AgreesWithOpenCvStereoPnpOnEveryFrame) {
  const Differences d = differences(motions().vo, motions().opencv, 1, 50);
  report("vo_vs_opencv_rotation_median_deg", median(d.rotation_deg));
  report("vo_vs_opencv_rotation_max_deg", max_of(d.rotation_deg));
  report("vo_vs_opencv_translation_median_m", median(d.translation_m));
  EXPECT_LT(median(d.rotation_deg), 0.025) << "median rotation difference per frame";
  EXPECT_LT(max_of(d.rotation_deg), 0.06) << "largest rotation difference of a frame";
  EXPECT_LT(median(d.translation_m), 0.02) << "median translation difference per frame";
}

// Where the ground truth is measured (frame 12 on), the VO follows it per
// frame, and accumulates little rotation against it.
TEST_F(VoReference, FollowsTheGroundTruthWhereItIsMeasured) {
  const Differences d = differences(motions().vo, motions().truth, 12, 50);
  const Differences o = differences(motions().opencv, motions().truth, 12, 50);
  report("frames_12_50_vo_rotation_median_deg", median(d.rotation_deg));
  report("frames_12_50_vo_rotation_max_deg", max_of(d.rotation_deg));
  report("frames_12_50_vo_translation_median_m", median(d.translation_m));
  report("frames_12_50_opencv_rotation_median_deg", median(o.rotation_deg));
  report("frames_12_50_opencv_translation_median_m", median(o.translation_m));
  // Both are longer than the ground truth: the data's scale, not the VO's.
  const double vo_scale = scale_ratio(motions().vo, motions().truth, 12, 50);
  const double cv_scale = scale_ratio(motions().opencv, motions().truth, 12, 50);
  report("frames_12_50_vo_scale", vo_scale);
  report("frames_12_50_opencv_scale", cv_scale);
  EXPECT_GT(vo_scale, 1.0);
  EXPECT_GT(cv_scale, vo_scale);
  EXPECT_LT(median(d.rotation_deg), 0.022);
  EXPECT_LT(max_of(d.rotation_deg), 0.07);
  EXPECT_LT(median(d.translation_m), 0.012);
  Eigen::Matrix4d vo = Eigen::Matrix4d::Identity(), truth = Eigen::Matrix4d::Identity();
  for (int k = 12; k <= 50; ++k) {
    vo = motions().vo[static_cast<std::size_t>(k - 1)] * vo;
    truth = motions().truth[static_cast<std::size_t>(k - 1)] * truth;
  }
  report("frames_12_50_vo_accumulated_rotation_deg",
         angle_deg(vo.topLeftCorner<3, 3>().transpose() * truth.topLeftCorner<3, 3>()));
  EXPECT_LT(angle_deg(vo.topLeftCorner<3, 3>().transpose() * truth.topLeftCorner<3, 3>()), 0.16)
      << "rotation error accumulated over frames 12-50";
}

// The ground truth of frames 1-11 is one twist repeated, and both
// estimators depart from it there by far more than they differ from each
// other.
TEST_F(VoReference, GroundTruthOfFramesOneToElevenIsAConstantTwistTheImagesDoNotShow) {
  const Eigen::Vector3d first = rotation_vector_deg(motions().truth[0]);
  for (int k = 2; k <= 11; ++k) {
    EXPECT_LT((rotation_vector_deg(motions().truth[static_cast<std::size_t>(k - 1)]) - first).norm(), 1e-3)
        << "ground truth rotation of frame " << k;
  }
  Eigen::Matrix4d vo = Eigen::Matrix4d::Identity(), ocv = Eigen::Matrix4d::Identity(),
                  truth = Eigen::Matrix4d::Identity();
  for (int k = 1; k <= 11; ++k) {
    vo = motions().vo[static_cast<std::size_t>(k - 1)] * vo;
    ocv = motions().opencv[static_cast<std::size_t>(k - 1)] * ocv;
    truth = motions().truth[static_cast<std::size_t>(k - 1)] * truth;
  }
  const double vo_vs_truth = angle_deg(vo.topLeftCorner<3, 3>().transpose() * truth.topLeftCorner<3, 3>());
  const double ocv_vs_truth = angle_deg(ocv.topLeftCorner<3, 3>().transpose() * truth.topLeftCorner<3, 3>());
  const double vo_vs_ocv = angle_deg(vo.topLeftCorner<3, 3>().transpose() * ocv.topLeftCorner<3, 3>());
  report("frames_1_11_vo_vs_truth_deg", vo_vs_truth);
  report("frames_1_11_opencv_vs_truth_deg", ocv_vs_truth);
  report("frames_1_11_vo_vs_opencv_deg", vo_vs_ocv);
  EXPECT_GT(vo_vs_truth, 0.5);
  EXPECT_GT(ocv_vs_truth, 0.5);
  EXPECT_LT(vo_vs_ocv, 0.15);
}

// What the targets (0.5 %, 0.2 m, 0.8 deg on frames 0-50) ask: an
// estimator equal to the ground truth from frame 12 on that moves as the
// images show in frames 1-11 (the VO's motions there, which OpenCV's
// confirm) still misses them.
TEST_F(VoReference, ExactFromFrameTwelveTheTargetsAreStillMissed) {
  std::vector<Eigen::Matrix4d> m = motions().truth;
  for (int k = 1; k <= 11; ++k) m[static_cast<std::size_t>(k - 1)] = motions().vo[static_cast<std::size_t>(k - 1)];
  std::vector<Eigen::Matrix4d> truth = poses_of(motions().truth);
  const rtfuse::apps::TrajectoryErrors e = rtfuse::apps::compare_trajectories(poses_of(m), truth);
  report("exact_after_11_final_error_pct", e.final_error_pct);
  report("exact_after_11_ate_rmse_m", e.ate_rmse_m);
  report("exact_after_11_final_rotation_error_deg", e.final_rotation_error_deg);
  EXPECT_GT(e.final_error_pct, 0.5);
  EXPECT_GT(e.ate_rmse_m, 0.2);
}

}  // namespace
