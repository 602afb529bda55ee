// vision::SemiGlobalMatcher against OpenCV 4.6's StereoSGBM (test-only) on
// the Middlebury 2003 pairs of RTFUSE_SHARED_DATA (teddy, cones: 450 x 375,
// ground truth x 4, 0 unknown): the share of known pixels whose estimate is
// off by more than 1 px, unestimated pixels counted as off, must be no
// worse than OpenCV's with the settings (MODE_SGBM, block 5, P1 =
// 8 * 25, P2 = 32 * 25, disp12MaxDiff 1, uniqueness 10, speckles 100 / 2,
// 64 disparities, one thread). Both see the same grey images (the luma
// rtfuse-stereo reads). The times are printed, never asserted: the side by
// side speed figures come from rtfuse_bench_opencv (docs/performance.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "apps/grey_png.hpp"
#include "vision/semi_global_matcher.hpp"

namespace opencv_sgbm_reference_test {

using rtfuse::apps::GreyPng;

const std::string kDir = std::string(RTFUSE_SHARED_DATA) + "/middlebury";
constexpr int kDisparities = 64;
constexpr int kRuns = 3;

struct Scores {
  double bad1 = 0.0;   // share of known pixels off by more than 1 px or unestimated
  double bad2 = 0.0;   // the same at 2 px
  double valid = 0.0;  // share of known pixels with an estimate
  double ms = 0.0;     // median of kRuns
};

// est(x, y) < 0: no estimate.
template <class Est>
void score(const GreyPng& truth, Est est, Scores* s) {
  long known = 0, bad1 = 0, bad2 = 0, valid = 0;
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      const int t = truth.pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(truth.width) +
                                 static_cast<std::size_t>(x)];
      if (t == 0) continue;
      ++known;
      const double e = est(x, y);
      if (e < 0.0) {
        ++bad1;
        ++bad2;
        continue;
      }
      ++valid;
      const double err = std::fabs(e - t / 4.0);
      bad1 += err > 1.0 ? 1 : 0;
      bad2 += err > 2.0 ? 1 : 0;
    }
  }
  s->bad1 = static_cast<double>(bad1) / static_cast<double>(known);
  s->bad2 = static_cast<double>(bad2) / static_cast<double>(known);
  s->valid = static_cast<double>(valid) / static_cast<double>(known);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

class OpencvSgbmReference : public ::testing::TestWithParam<const char*> {};

TEST_P(OpencvSgbmReference, NoWorseThanStereoSgbm) {
  const std::string dir = kDir + "/" + GetParam();
  GreyPng left, right, truth;
  std::string error;
  ASSERT_TRUE(rtfuse::apps::read_luma_png(dir + "/im2.png", &left, &error)) << error;
  ASSERT_TRUE(rtfuse::apps::read_luma_png(dir + "/im6.png", &right, &error)) << error;
  ASSERT_TRUE(rtfuse::apps::read_grey_png(dir + "/disp2.png", &truth, &error)) << error;
  ASSERT_EQ(left.width, truth.width);
  ASSERT_EQ(left.height, truth.height);
  const int w = left.width, h = left.height;

  cv::setNumThreads(1);
  const cv::Mat l(h, w, CV_8UC1, left.pixels.data()), r(h, w, CV_8UC1, right.pixels.data());
  cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(0, kDisparities, 5, 8 * 25, 32 * 25, 1, 0, 10, 100, 2,
                                                        cv::StereoSGBM::MODE_SGBM);
  cv::Mat cv_disp;

  rtfuse::vision::SemiGlobalMatcher matcher(w, h);  // the defaults: 64 disparities, full resolution
  ASSERT_TRUE(matcher.valid()) << matcher.error();
  rtfuse::vision::Plane<std::uint16_t> ours(w, h);
  const rtfuse::vision::GreyView lv{left.pixels.data(), w, h, w}, rv{right.pixels.data(), w, h, w};

  // Interleaved, so both see the same machine.
  std::vector<double> ms_cv, ms_ours;
  for (int k = 0; k < kRuns; ++k) {
    auto t0 = std::chrono::steady_clock::now();
    sgbm->compute(l, r, cv_disp);
    auto t1 = std::chrono::steady_clock::now();
    ASSERT_EQ(matcher.compute(lv, rv, rtfuse::vision::view_of(ours)), rtfuse::vision::DisparityStatus::kOk);
    auto t2 = std::chrono::steady_clock::now();
    ms_cv.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    ms_ours.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
  }
  ASSERT_EQ(cv_disp.type(), CV_16S);

  Scores cv_scores, our_scores;
  score(truth, [&](int x, int y) {
    const int v = cv_disp.at<std::int16_t>(y, x);
    return v < 0 ? -1.0 : v / 16.0;
  }, &cv_scores);
  score(truth, [&](int x, int y) {
    const int v = ours.at(x, y);
    return v == rtfuse::vision::kInvalidDisparity ? -1.0 : v / static_cast<double>(rtfuse::vision::kDisparityScale);
  }, &our_scores);
  cv_scores.ms = median(ms_cv);
  our_scores.ms = median(ms_ours);
  std::printf("%s: bad>1px ours %.2f %% vs OpenCV %.2f %%; bad>2px ours %.2f %% vs %.2f %%; estimated ours %.2f %% "
              "vs %.2f %%; ms ours %.1f vs OpenCV %.1f (this build, median of %d)\n",
              GetParam(), 100 * our_scores.bad1, 100 * cv_scores.bad1, 100 * our_scores.bad2, 100 * cv_scores.bad2,
              100 * our_scores.valid, 100 * cv_scores.valid, our_scores.ms, cv_scores.ms, kRuns);
  EXPECT_LE(our_scores.bad1, cv_scores.bad1);
  // Sanity on the reference itself: the issue measured about 20 %.
  EXPECT_LT(cv_scores.bad1, 0.35);
}

INSTANTIATE_TEST_SUITE_P(Middlebury, OpencvSgbmReference, ::testing::Values("teddy", "cones"));

}  // namespace opencv_sgbm_reference_test
