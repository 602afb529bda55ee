// StereoOdometry on real frames: the first KITTI 06 pairs of ../shared/data
// (read with the tool's PNG reader). The motion of each frame is close to
// the ground truth's, the same frames give the same bits, process()
// allocates nothing, and frames it cannot use are said so.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/LU>

#include "apps/grey_png.hpp"
#include "apps/kitti_sequence.hpp"
#include "support/alloc_counter.hpp"
#include "vision/stereo_odometry.hpp"

namespace rtfuse::apps {
namespace stereo_odometry_kitti_test {

const std::string kSeq = std::string(RTFUSE_SHARED_DATA) + "/kitti/kitti06_0000_0050";

struct Frames {
  KittiSequence seq;
  std::vector<GreyPng> left, right;
};

const Frames* load(int n) {
  static Frames* f = nullptr;
  if (f != nullptr) return f;
  if (!std::filesystem::exists(kSeq)) return nullptr;
  f = new Frames;
  std::string err;
  if (!open_kitti_sequence(kSeq, &f->seq, &err)) {
    ADD_FAILURE() << err;
    return nullptr;
  }
  for (int k = 0; k < n; ++k) {
    GreyPng l, r;
    EXPECT_TRUE(read_grey_png(f->seq.left[static_cast<std::size_t>(k)], &l, &err)) << err;
    EXPECT_TRUE(read_grey_png(f->seq.right[static_cast<std::size_t>(k)], &r, &err)) << err;
    f->left.push_back(std::move(l));
    f->right.push_back(std::move(r));
  }
  return f;
}

vision::GreyView view(const GreyPng& p) { return {p.pixels.data(), p.width, p.height, p.width}; }

TEST(StereoOdometryKitti, FrameMotionsFollowTheGroundTruth) {
  const Frames* f = load(6);
  if (f == nullptr) GTEST_SKIP() << kSeq << " is not there";
  vision::StereoOdometry vo(f->left[0].width, f->left[0].height, f->seq.camera, vision::StereoOdometryParams{});
  EXPECT_EQ(vo.process(view(f->left[0]), view(f->right[0]), 0).status, vision::VoStatus::kFirstFrame);
  for (int k = 1; k < 6; ++k) {
    vision::StereoOdometryResult r;
    {
      test::AllocScope scope;
      r = vo.process(view(f->left[static_cast<std::size_t>(k)]), view(f->right[static_cast<std::size_t>(k)]),
                     static_cast<std::uint64_t>(k));
      EXPECT_EQ(scope.count(), 0u) << "frame " << k;
    }
    ASSERT_EQ(r.status, vision::VoStatus::kMotion) << k;
    EXPECT_GT(r.features_left, 1000);
    EXPECT_GT(r.motion.inliers, 80);
    EXPECT_EQ(r.predicted, k > 1);
    // Features carry over: from the second motion on, many inliers were
    // inliers the frame before (none can be at the first).
    EXPECT_LE(r.tracked, r.motion.inliers);
    if (k == 1) {
      EXPECT_EQ(r.tracked, 0);
    } else {
      EXPECT_GT(r.tracked, r.motion.inliers / 3) << k;
    }
    // Camera k-1 -> camera k from the ground truth, against the estimate.
    const Eigen::Matrix4d truth =
        f->seq.ground_truth[static_cast<std::size_t>(k)].inverse() * f->seq.ground_truth[static_cast<std::size_t>(k - 1)];
    const Eigen::Matrix4d est = vision::egomotion_transform(r.motion.params);
    EXPECT_LT((est.topRightCorner<3, 1>() - truth.topRightCorner<3, 1>()).norm(), 0.03) << k;  // of 1.2 m
    const Eigen::Matrix3d dr = est.topLeftCorner<3, 3>().transpose() * truth.topLeftCorner<3, 3>();
    EXPECT_LT(std::acos(std::min(1.0, 0.5 * (dr.trace() - 1.0))), 0.005) << k;  // rad
    EXPECT_GT(r.motion.covariance(5, 5), 0.0);
    EXPECT_LT(std::sqrt(r.motion.covariance(5, 5)), 0.05);
  }
}

TEST(StereoOdometryKitti, SameFramesSameBits) {
  const Frames* f = load(6);
  if (f == nullptr) GTEST_SKIP() << kSeq << " is not there";
  vision::Egomotion runs[2];
  for (auto& out : runs) {
    vision::StereoOdometry vo(f->left[0].width, f->left[0].height, f->seq.camera, vision::StereoOdometryParams{});
    for (int k = 0; k < 3; ++k) {
      const auto r = vo.process(view(f->left[static_cast<std::size_t>(k)]), view(f->right[static_cast<std::size_t>(k)]),
                                static_cast<std::uint64_t>(k));
      if (k == 2) out = r.motion;
    }
  }
  EXPECT_EQ(std::memcmp(runs[0].params.data(), runs[1].params.data(), sizeof(double) * 6), 0);
  EXPECT_EQ(std::memcmp(runs[0].covariance.data(), runs[1].covariance.data(), sizeof(double) * 36), 0);
}

TEST(StereoOdometryKitti, UnusableFramesAreSaidSo) {
  const Frames* f = load(6);
  if (f == nullptr) GTEST_SKIP() << kSeq << " is not there";
  const int w = f->left[0].width, h = f->left[0].height;
  vision::StereoOdometry vo(w, h, f->seq.camera, vision::StereoOdometryParams{});
  // Another size, no pixels: refused before anything is touched.
  const vision::GreyView small{f->left[0].pixels.data(), w - 2, h, w};
  EXPECT_EQ(vo.process(small, small, 0).status, vision::VoStatus::kBadInput);
  EXPECT_EQ(vo.process(vision::GreyView{}, view(f->right[0]), 0).status, vision::VoStatus::kBadInput);
  // A covered lens (all black) after a good frame: too few matches, and the
  // next good pair starts over from it without a wild motion.
  ASSERT_EQ(vo.process(view(f->left[0]), view(f->right[0]), 0).status, vision::VoStatus::kFirstFrame);
  const std::vector<std::uint8_t> black(static_cast<std::size_t>(w * h), 0);
  const vision::GreyView dark{black.data(), w, h, w};
  EXPECT_EQ(vo.process(dark, dark, 1).status, vision::VoStatus::kTooFewMatches);
  const auto r = vo.process(view(f->left[2]), view(f->right[2]), 2);
  EXPECT_NE(r.status, vision::VoStatus::kMotion);
  // A flash: saturated white.
  const std::vector<std::uint8_t> white(static_cast<std::size_t>(w * h), 255);
  const vision::GreyView flash{white.data(), w, h, w};
  EXPECT_EQ(vo.process(flash, flash, 3).status, vision::VoStatus::kTooFewMatches);
}

}  // namespace stereo_odometry_kitti_test
}  // namespace rtfuse::apps
