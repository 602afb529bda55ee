// The KITTI layout's parsers (calib.txt, poses.txt) on good and broken
// files, and the trajectory errors on trajectories whose errors are known.
#include "apps/kitti_sequence.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "apps/trajectory_metrics.hpp"

namespace rtfuse::apps {
namespace kitti_sequence_test {

const std::string kP0 = "7.070912e+02 0.000000e+00 6.018873e+02 0.000000e+00 0.000000e+00 7.070912e+02 "
                        "1.831104e+02 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00";
const std::string kP1 = "7.070912e+02 0.000000e+00 6.018873e+02 -3.798145e+02 0.000000e+00 7.070912e+02 "
                        "1.831104e+02 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00";

TEST(KittiCalibration, ReadsUnlabelledAndLabelledFiles) {
  vision::StereoCameraModel cam;
  std::string err;
  ASSERT_TRUE(parse_kitti_calibration(kP0 + "\n" + kP1 + "\n", "calib.txt", &cam, &err)) << err;
  EXPECT_DOUBLE_EQ(cam.f, 707.0912);
  EXPECT_DOUBLE_EQ(cam.cu, 601.8873);
  EXPECT_DOUBLE_EQ(cam.cv, 183.1104);
  EXPECT_NEAR(cam.baseline, 0.53716, 1e-5);
  // KITTI's own: labels, P2/P3/Tr lines, CRLF.
  ASSERT_TRUE(parse_kitti_calibration("P0: " + kP0 + "\r\nP1: " + kP1 + "\r\nP2: " + kP0 + "\r\nTr: 1 2 3\r\n",
                                      "calib.txt", &cam, &err))
      << err;
  EXPECT_NEAR(cam.baseline, 0.53716, 1e-5);
}

TEST(KittiCalibration, BrokenFilesNameTheLineAndTheFix) {
  vision::StereoCameraModel cam;
  std::string err;
  EXPECT_FALSE(parse_kitti_calibration(kP0 + "\n", "seq/calib.txt", &cam, &err));
  EXPECT_EQ(err, "seq/calib.txt: no P1 (right camera's projection matrix; a KITTI calib.txt starts with the P0 and "
                 "P1 lines)");
  EXPECT_FALSE(parse_kitti_calibration(kP0 + "\n1 2 3\n", "c.txt", &cam, &err));
  EXPECT_EQ(err, "c.txt:2: P1 has 3 numbers, not 12 (the 3x4 projection matrix row by row)");
  EXPECT_FALSE(parse_kitti_calibration("P0: " + kP0 + "\nP1: 7.07e+02 x\n", "c.txt", &cam, &err));
  EXPECT_EQ(err, "c.txt:2: 'x' is not a number (P1 is 12 numbers, the 3x4 projection matrix row by row)");
  EXPECT_FALSE(parse_kitti_calibration(kP0 + "\n" + kP0 + "\n", "c.txt", &cam, &err));
  EXPECT_NE(err.find("baseline"), std::string::npos) << err;
  std::string other = kP1;
  other.replace(other.find("6.018873e+02"), 12, "6.5e+02");
  EXPECT_FALSE(parse_kitti_calibration(kP0 + "\n" + other + "\n", "c.txt", &cam, &err));
  EXPECT_NE(err.find("do not describe a rectified pair"), std::string::npos) << err;
  EXPECT_FALSE(parse_kitti_calibration(kP0 + "\nnan" + kP1.substr(12) + "\n", "c.txt", &cam, &err));
  EXPECT_FALSE(parse_kitti_calibration("", "c.txt", &cam, &err));
  EXPECT_NE(err.find("no P0"), std::string::npos);
}

TEST(KittiPoses, RoundTripAndMalformedLines) {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t(0, 3) = 1.5;
  t(2, 3) = -0.25;
  t(0, 1) = 1e-9;
  std::vector<Eigen::Matrix4d> poses;
  std::string err;
  ASSERT_TRUE(parse_kitti_poses(kitti_pose_line(t) + "\n" + kitti_pose_line(t) + "\n", "p.txt", &poses, &err));
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_TRUE(poses[1].isApprox(t, 1e-12));
  EXPECT_FALSE(parse_kitti_poses("1 0 0 0 0 1 0 0 0 0 1\n", "p.txt", &poses, &err));
  EXPECT_EQ(err, "p.txt:1: 11 numbers, a pose is 12 (3x4, row by row)");
}

Eigen::Matrix4d at(double x, double z, double yaw = 0.0) {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t(0, 0) = std::cos(yaw), t(0, 2) = std::sin(yaw), t(2, 0) = -std::sin(yaw), t(2, 2) = std::cos(yaw);
  t(0, 3) = x;
  t(2, 3) = z;
  return t;
}

TEST(TrajectoryErrors, KnownAnswers) {
  std::vector<Eigen::Matrix4d> gt, est;
  for (int i = 0; i <= 10; ++i) {
    gt.push_back(at(0.0, i));
    est.push_back(at(0.1 * i / 10.0, i, 0.01 * i / 10.0));  // drifts 0.1 m and 0.01 rad by the end
  }
  const TrajectoryErrors e = compare_trajectories(est, gt);
  EXPECT_EQ(e.frames, 11);
  EXPECT_NEAR(e.path_length_m, 10.0, 1e-12);
  EXPECT_NEAR(e.final_error_m, 0.1, 1e-12);
  EXPECT_NEAR(e.final_error_pct, 1.0, 1e-10);
  EXPECT_NEAR(e.final_rotation_error_deg, 0.01 * 180.0 / M_PI, 1e-6);
  double sq = 0.0;
  for (int i = 0; i <= 10; ++i) sq += (0.01 * i) * (0.01 * i);
  EXPECT_NEAR(e.ate_rmse_m, std::sqrt(sq / 11.0), 1e-12);
  EXPECT_NEAR(e.rpe_rotation_deg, 0.001 * 180.0 / M_PI, 1e-6);
  EXPECT_EQ(compare_trajectories({}, gt).frames, 0);
}

TEST(TrajectoryErrors, ReanchoredJudgesAStretchAsIfItStartedThere) {
  // The estimate turns 0.01 rad at frame 3 and is exact after it: from
  // frame 3 on it drives a straight line like the ground truth, only turned.
  std::vector<Eigen::Matrix4d> gt, est;
  for (int i = 0; i <= 10; ++i) {
    gt.push_back(at(0.0, i));
    est.push_back(i < 3 ? at(0.0, i) : at(0.0, 2.0) * at(0.0, 1.0, 0.01) * at(0.0, i - 3));
  }
  EXPECT_GT(compare_trajectories(est, gt).final_rotation_error_deg, 0.5);
  const std::vector<Eigen::Matrix4d> e = reanchored(est, 4), g = reanchored(gt, 4);
  ASSERT_EQ(e.size(), 7u);
  EXPECT_TRUE(e[0].isApprox(Eigen::Matrix4d::Identity(), 1e-15));
  const TrajectoryErrors w = compare_trajectories(e, g);
  EXPECT_NEAR(w.path_length_m, 6.0, 1e-12);
  EXPECT_NEAR(w.final_error_m, 0.0, 1e-12);
  EXPECT_NEAR(w.final_rotation_error_deg, 0.0, 1e-6);
  EXPECT_TRUE(reanchored(est, 11).empty());
}

}  // namespace kitti_sequence_test
}  // namespace rtfuse::apps
