#pragma once
// Frame-to-frame stereo visual odometry on rectified grey pairs (the
// VISO2-S scheme): features at half resolution in both eyes, circular
// matching against the previous pair (guided by the previous motion when
// there is one), an even spread of matches (buckets, preferring features
// that have been inliers for frames in a row), sub-pixel positions at full
// resolution, and RANSAC + Gauss-Newton egomotion with covariance.
//
// Pure: no threads, no clock, no I/O. Every buffer is sized in the
// constructor from the image size; process() allocates nothing, and gives
// the same bits for the same frames on every architecture (integer image
// processing, portable floating point, a RANSAC seeded by the frame number).
#include <cstdint>
#include <memory>

#include "vision/circular_matcher.hpp"
#include "vision/feature_detector.hpp"
#include "vision/feature_filters.hpp"
#include "vision/feature_index.hpp"
#include "vision/patch_aligner.hpp"
#include "vision/plane.hpp"
#include "vision/stereo_egomotion.hpp"

namespace rtfuse::vision {

struct StereoOdometryParams {
  bool half_resolution = true;   // detect and match at half size, refine at full size
  SuppressionParams suppression;  // at the matching resolution
  // Full-resolution pixels:
  int max_disparity_px = 256;
  int row_tolerance_px = 2;         // left/right rows of a rectified pair
  int flow_radius_px = 200;         // motion search without a prediction
  int predicted_radius_px = 24;     // around the previous motion's prediction
  int bucket_size_px = 50;          // spread: at most bucket_max matches per bucket
  int bucket_max = 2;
  // Circles start only at the strongest previous-left features of each
  // bucket (0: at every feature): most circles are discarded by the
  // buckets anyway, so this keeps the matching's cost to what is used.
  int queries_per_bucket = 8;
  // Ages (frames in a row as an inlier) above this count no more when
  // choosing queries and matches; 0 chooses by response alone.
  int age_priority_cap = 255;
  int refine_radius_px = 2;         // full-resolution search around a match
  bool subpixel = true;             // align the current-left patch in the other images (vision/patch_aligner)
  EgomotionParams egomotion;
  std::uint64_t seed = 0x7274667573652d76ULL;  // mixed with the frame number for RANSAC
};

enum class VoStatus : std::uint8_t {
  kMotion = 0,       // a motion from the previous pair to this one
  kFirstFrame,       // features only, nothing to match yet
  kTooFewMatches,    // a plain wall, a flash, a covered lens
  kNoConsensus,      // matches but no motion they agree on
  kBadInput,         // wrong size or no pixels
};
const char* to_string(VoStatus s) noexcept;

struct StereoOdometryResult {
  VoStatus status = VoStatus::kBadInput;
  Egomotion motion;           // previous left camera -> this left camera (when kMotion)
  int features_left = 0;      // this pair
  int features_right = 0;
  int matches = 0;            // circles closed
  int bucketed = 0;           // kept after the spread
  int tracked = 0;            // inliers whose feature was an inlier the frame before too
  bool predicted = false;     // the search followed the previous motion
};

class StereoOdometry {
 public:
  // For width x height pairs of the given camera (full resolution).
  StereoOdometry(int width, int height, const StereoCameraModel& camera, const StereoOdometryParams& params);
  ~StereoOdometry();
  StereoOdometry(const StereoOdometry&) = delete;
  StereoOdometry& operator=(const StereoOdometry&) = delete;

  // One rectified pair; frame_number seeds the RANSAC.
  StereoOdometryResult process(const GreyView& left, const GreyView& right, std::uint64_t frame_number) noexcept;
  // Forget the previous pair (after a gap): the next pair starts again.
  void reset() noexcept;

  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  const StereoCameraModel& camera() const noexcept { return camera_; }

 private:
  struct Eye;
  struct Slot;
  void detect(const GreyView& img, Eye& eye) noexcept;
  int bucket_of(int u, int v) const noexcept;  // matching-resolution position
  int priority(const Eye& eye, int i) const noexcept;
  int select_queries(const Eye& prev_left) noexcept;
  int bucket(const Slot& prev, const Slot& cur, int n) noexcept;
  bool refine(const Slot& prev, const Slot& cur, const CircularMatch& m, StereoObservation* out) noexcept;

  int width_, height_, scale_;
  StereoCameraModel camera_;
  StereoOdometryParams params_;
  MatchParams match_;
  int max_features_;
  FeatureFilters filters_;
  Plane<std::uint8_t> half_;
  Plane<std::int16_t> blob_, corner_;
  Plane<std::uint8_t> du_small_, dv_small_;
  Plane<std::uint8_t> ref_du_, ref_dv_, win_du_, win_dv_;  // full-resolution gradients around a refined match
  std::unique_ptr<Slot> slots_[2];
  int cur_ = 0;
  bool have_prev_ = false;
  bool have_motion_ = false;
  Egomotion last_motion_;
  CircularMatcher matcher_;
  std::unique_ptr<CircularMatch[]> matches_;
  int match_capacity_;
  std::unique_ptr<int[]> bucket_slots_;  // buckets x the most kept per bucket
  std::unique_ptr<int[]> queries_;  // previous-left features that start a circle; kept matches
  int bucket_cols_, bucket_rows_;
  std::unique_ptr<StereoObservation[]> observations_;
  std::unique_ptr<int[]> observation_match_;  // per observation, its match
  StereoEgomotion egomotion_;
  PatchAligner aligner_;
};

}  // namespace rtfuse::vision
