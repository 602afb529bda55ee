#include "vision/stereo_odometry.hpp"

#include <algorithm>
#include <climits>
#include <cmath>

namespace rtfuse::vision {

const char* to_string(VoStatus s) noexcept {
  switch (s) {
    case VoStatus::kMotion: return "motion";
    case VoStatus::kFirstFrame: return "first-frame";
    case VoStatus::kTooFewMatches: return "too-few-matches";
    case VoStatus::kNoConsensus: return "no-consensus";
    case VoStatus::kBadInput: return "bad-input";
  }
  return "unknown";
}

struct StereoOdometry::Eye {
  std::unique_ptr<Feature[]> features;
  FeatureIndex index;
  Plane<std::uint8_t> grey;  // the image itself (the caller's may be gone next frame)
  // Per feature (left eyes): for how many frames in a row it has been an
  // inlier of the motion, up to 255.
  std::unique_ptr<std::uint8_t[]> age;
  Eye(int w, int h, int max_features, int match_w, int match_h)
      : features(new Feature[static_cast<std::size_t>(std::max(1, max_features))]),
        index(match_w, match_h, max_features),
        grey(w, h),
        age(new std::uint8_t[static_cast<std::size_t>(std::max(1, max_features))]()) {}
};

struct StereoOdometry::Slot {
  Eye left, right;
  Slot(int w, int h, int max_features, int mw, int mh)
      : left(w, h, max_features, mw, mh), right(w, h, max_features, mw, mh) {}
};

namespace {

// Where the previous motion puts a previous-left feature, in matching pixels.
class ConstantVelocity final : public MotionPrediction {
 public:
  ConstantVelocity(const StereoCameraModel& cam, const Eigen::Matrix4d& motion, int scale)
      : cam_(cam), t_(motion), scale_(scale) {}
  bool predict(int u, int v, int disparity, int* ur, int* vr, int* ul, int* vl) const noexcept override {
    const double s = scale_;
    const double d = std::max(1.0, s * disparity);
    const double x = (s * u - cam_.cu) * cam_.baseline / d;
    const double y = (s * v - cam_.cv) * cam_.baseline / d;
    const double z = cam_.f * cam_.baseline / d;
    const Eigen::Vector4d q = t_ * Eigen::Vector4d(x, y, z, 1.0);
    if (q.z() < 0.1) return false;
    const double pu = cam_.f * q.x() / q.z() + cam_.cu;
    const double pv = cam_.f * q.y() / q.z() + cam_.cv;
    const double pr = cam_.f * (q.x() - cam_.baseline) / q.z() + cam_.cu;
    if (!std::isfinite(pu) || !std::isfinite(pv) || !std::isfinite(pr) || std::abs(pu) > 1e6 || std::abs(pv) > 1e6 ||
        std::abs(pr) > 1e6) {
      return false;
    }
    *ul = static_cast<int>(std::lround(pu / s));
    *vl = static_cast<int>(std::lround(pv / s));
    *ur = static_cast<int>(std::lround(pr / s));
    *vr = *vl;
    return true;
  }

 private:
  const StereoCameraModel& cam_;
  Eigen::Matrix4d t_;
  int scale_;
};

// The 32-byte descriptor at (u, v) of gradient planes, as describe() builds it.
void descriptor_at(const Plane<std::uint8_t>& du, const Plane<std::uint8_t>& dv, int u, int v,
                   std::uint8_t* out) noexcept {
  Feature f;
  f.u = u;
  f.v = v;
  describe(du, dv, &f, 1);
  std::copy(f.descriptor, f.descriptor + kDescriptorBytes, out);
}

// How far a descriptor reaches from its centre (vision/feature_detector.cpp).
constexpr int kDescriptorReach = 5;
// Beyond the refinement search, no more than the windowed gradients allow.
constexpr int kMaxRefineRadius = 20;

}  // namespace

StereoOdometry::StereoOdometry(int width, int height, const StereoCameraModel& camera,
                               const StereoOdometryParams& params)
    : width_(width),
      height_(height),
      scale_(params.half_resolution ? 2 : 1),
      camera_(camera),
      params_(params),
      max_features_(max_features(width / scale_, height / scale_, params.suppression)),
      filters_(width),
      half_(params.half_resolution ? width / 2 : 1, params.half_resolution ? height / 2 : 1),
      blob_(width / scale_, height / scale_),
      corner_(width / scale_, height / scale_),
      du_small_(width / scale_, height / scale_),
      dv_small_(width / scale_, height / scale_),
      ref_du_(2 * kDescriptorReach + 1, 2 * kDescriptorReach + 1),
      ref_dv_(2 * kDescriptorReach + 1, 2 * kDescriptorReach + 1),
      win_du_(2 * (std::clamp(params.refine_radius_px, 0, kMaxRefineRadius) + kDescriptorReach) + 1,
              2 * (std::clamp(params.refine_radius_px, 0, kMaxRefineRadius) + kDescriptorReach) + 1),
      win_dv_(win_du_.width(), win_du_.height()),
      matcher_(max_features_),
      match_capacity_(max_features_),
      egomotion_(max_features_) {
  const int mw = width / scale_, mh = height / scale_;
  for (auto& s : slots_) s = std::make_unique<Slot>(width, height, max_features_, mw, mh);
  match_.max_disparity = params.max_disparity_px / scale_;
  match_.row_tolerance = std::max(0, params.row_tolerance_px / scale_);
  match_.flow_radius = params.flow_radius_px / scale_;
  match_.predicted_radius = std::max(1, params.predicted_radius_px / scale_);
  matches_.reset(new CircularMatch[static_cast<std::size_t>(std::max(1, match_capacity_))]);
  bucket_cols_ = std::max(1, (width + params.bucket_size_px - 1) / params.bucket_size_px);
  bucket_rows_ = std::max(1, (height + params.bucket_size_px - 1) / params.bucket_size_px);
  const int per_bucket = std::max({1, params.bucket_max, params.queries_per_bucket});
  bucket_slots_.reset(new int[static_cast<std::size_t>(bucket_cols_ * bucket_rows_ * per_bucket)]);
  queries_.reset(new int[static_cast<std::size_t>(std::max(1, max_features_))]);
  observations_.reset(new StereoObservation[static_cast<std::size_t>(std::max(1, match_capacity_))]);
  observation_match_.reset(new int[static_cast<std::size_t>(std::max(1, match_capacity_))]);
}

StereoOdometry::~StereoOdometry() = default;

void StereoOdometry::reset() noexcept {
  have_prev_ = false;
  have_motion_ = false;
}

void StereoOdometry::detect(const GreyView& img, Eye& eye) noexcept {
  for (int v = 0; v < img.height; ++v) std::copy(img.row(v), img.row(v) + img.width, eye.grey.row(v));
  // The matching image's gradients for the descriptors. Refinement takes
  // full-resolution gradients only around the few matches it refines
  // (FeatureFilters::sobel5x5_window): a whole-image pass per eye cost more
  // than all of refinement.
  GreyView match = img;
  if (scale_ == 2) {
    FeatureFilters::halve(img, half_);
    match = view_of(half_);
  }
  filters_.sobel5x5(match, du_small_, dv_small_);
  filters_.blob_corner5x5(match, blob_, corner_);
  int dropped = 0;
  const int n = suppress_non_maxima(blob_, corner_, params_.suppression, eye.features.get(), max_features_, &dropped);
  describe(du_small_, dv_small_, eye.features.get(), n);
  std::fill(eye.age.get(), eye.age.get() + n, std::uint8_t{0});
  eye.index.build(eye.features.get(), n);
}

namespace {

// Of n items, the k strongest of each bucket (ties: the earlier item), as
// positions 0..n in their original order, into kept; returns how many.
// slots holds buckets * k ints.
template <class BucketOf, class StrengthOf>
int keep_strongest(int n, int buckets, int k, BucketOf bucket_of, StrengthOf strength_of, int* slots,
                   int* kept) noexcept {
  std::fill(slots, slots + buckets * k, -1);
  for (int m = 0; m < n; ++m) {
    int* slot = slots + bucket_of(m) * k;
    // Insert by strength, stronger first; an equal strength stays behind.
    int pos = k;
    for (int j = 0; j < k; ++j) {
      if (slot[j] < 0 || strength_of(m) > strength_of(slot[j])) {
        pos = j;
        break;
      }
    }
    if (pos == k) continue;
    for (int j = k - 1; j > pos; --j) slot[j] = slot[j - 1];
    slot[pos] = m;
  }
  int count = 0;
  for (int m = 0; m < n; ++m) {
    const int* slot = slots + bucket_of(m) * k;
    if (std::find(slot, slot + k, m) != slot + k) kept[count++] = m;
  }
  return count;
}

}  // namespace

int StereoOdometry::bucket_of(int u, int v) const noexcept {
  const int bu = std::min(bucket_cols_ - 1, u * scale_ / params_.bucket_size_px);
  const int bv = std::min(bucket_rows_ - 1, v * scale_ / params_.bucket_size_px);
  return bv * bucket_cols_ + bu;
}

int StereoOdometry::priority(const Eye& eye, int i) const noexcept {
  // A feature that has agreed with the motion for frames in a row is more
  // likely a static, well-localised point than a new one (Cvisic et al.,
  // SOFT, 2017): its age comes first, its response breaks ties.
  const int strength = std::abs(static_cast<int>(eye.features[i].value));  // < 2^13
  const int age = std::min(static_cast<int>(eye.age[i]), std::max(0, params_.age_priority_cap));
  return (age << 16) + strength;
}

int StereoOdometry::select_queries(const Eye& prev_left) noexcept {
  const Feature* f = prev_left.features.get();
  const int n = prev_left.index.size();
  if (params_.queries_per_bucket <= 0) {
    for (int i = 0; i < n; ++i) queries_[i] = i;
    return n;
  }
  return keep_strongest(
      n, bucket_cols_ * bucket_rows_, params_.queries_per_bucket, [&](int i) { return bucket_of(f[i].u, f[i].v); },
      [&](int i) { return priority(prev_left, i); }, bucket_slots_.get(), queries_.get());
}

int StereoOdometry::bucket(const Slot& prev, const Slot& cur, int n) noexcept {
  // Per bucket, the bucket_max matches whose previous-left feature has the
  // highest priority (age, then the current response), kept in match order.
  const Feature* lc = cur.left.features.get();
  const int kept = keep_strongest(
      n, bucket_cols_ * bucket_rows_, std::max(1, params_.bucket_max),
      [&](int m) { return bucket_of(lc[matches_[m].lc].u, lc[matches_[m].lc].v); },
      [&](int m) {
        const CircularMatch& c = matches_[m];
        return (std::min(static_cast<int>(prev.left.age[c.lp]), std::max(0, params_.age_priority_cap)) << 16) +
               std::abs(static_cast<int>(lc[c.lc].value));
      },
      bucket_slots_.get(), queries_.get());
  for (int i = 0; i < kept; ++i) matches_[i] = matches_[queries_[i]];
  return kept;
}

bool StereoOdometry::refine(const Slot& prev, const Slot& cur, const CircularMatch& m,
                            StereoObservation* out) noexcept {
  const int s = scale_;
  const Feature& lc = cur.left.features[m.lc];
  const int ru = lc.u * s, rv = lc.v * s;
  const int r = std::clamp(params_.refine_radius_px, 0, kMaxRefineRadius);
  // Features keep their margin from the border (at least 2 * kMinFeatureMargin
  // here), so the reference's window fits; the searches check theirs.
  const int reach = kDescriptorReach;
  std::uint8_t ref[kDescriptorBytes];
  FeatureFilters::sobel5x5_window(view_of(cur.left.grey), ru - reach, rv - reach, ref_du_, ref_dv_);
  descriptor_at(ref_du_, ref_dv_, reach, reach, ref);
  const bool have_patch = params_.subpixel && aligner_.set_reference(cur.left.grey, ru, rv);
  // The position in `eye` (full resolution) whose descriptor is closest to
  // the reference, near (u0, v0); sub-pixel by a parabola through the costs.
  auto locate = [&](const Eye& eye, const Feature& f, double* u, double* v) {
    const int u0 = f.u * s, v0 = f.v * s;
    // The search window must keep the descriptor inside the image.
    if (u0 - r < 5 + 2 || v0 - r < 5 + 2 || u0 + r >= width_ - 7 || v0 + r >= height_ - 7) {
      *u = u0, *v = v0;
      return true;
    }
    int best = INT_MAX, bu = 0, bv = 0;
    std::uint8_t d[kDescriptorBytes];
    const int o = r + reach;  // (u0, v0) in the window
    FeatureFilters::sobel5x5_window(view_of(eye.grey), u0 - o, v0 - o, win_du_, win_dv_);
    for (int dv = -r; dv <= r; ++dv) {
      for (int du = -r; du <= r; ++du) {
        descriptor_at(win_du_, win_dv_, o + du, o + dv, d);
        const int c = descriptor_sad(ref, d);
        if (c < best) best = c, bu = du, bv = dv;
      }
    }
    *u = u0 + bu;
    *v = v0 + bv;
    // The fraction: the reference patch aligned in this image.
    if (have_patch) {
      double au = 0.0, av = 0.0;
      if (aligner_.align(eye.grey, *u, *v, 1.5, &au, &av)) *u = au, *v = av;
    }
    return true;
  };
  double vr = 0.0;
  out->u_lc = ru;
  out->v_lc = rv;
  return locate(prev.left, prev.left.features[m.lp], &out->u_lp, &out->v_lp) &&
         locate(prev.right, prev.right.features[m.rp], &out->u_rp, &vr) &&
         locate(cur.right, cur.right.features[m.rc], &out->u_rc, &vr) && (out->v_rc = out->v_lc, true);
}

StereoOdometryResult StereoOdometry::process(const GreyView& left, const GreyView& right,
                                             std::uint64_t frame_number) noexcept {
  StereoOdometryResult res;
  if (!left.valid() || !right.valid() || left.width != width_ || left.height != height_ || right.width != width_ ||
      right.height != height_) {
    res.status = VoStatus::kBadInput;
    return res;
  }
  Slot& cur = *slots_[cur_];
  Slot& prev = *slots_[1 - cur_];
  detect(left, cur.left);
  detect(right, cur.right);
  res.features_left = cur.left.index.count();
  res.features_right = cur.right.index.count();
  if (!have_prev_) {
    res.status = VoStatus::kFirstFrame;
    have_prev_ = true;
    cur_ = 1 - cur_;
    return res;
  }
  const ConstantVelocity cv(camera_, egomotion_transform(last_motion_.params), scale_);
  res.predicted = have_motion_;
  const int queries = select_queries(prev.left);
  int n = matcher_.match(prev.left.index, prev.right.index, cur.left.index, cur.right.index, match_,
                         have_motion_ ? &cv : nullptr, matches_.get(), match_capacity_, queries_.get(), queries);
  // A prediction that found little (a sudden change of motion) is not
  // trusted: the full search again.
  if (have_motion_ && n < 3 * params_.egomotion.min_inliers) {
    res.predicted = false;
    n = matcher_.match(prev.left.index, prev.right.index, cur.left.index, cur.right.index, match_, nullptr,
                       matches_.get(), match_capacity_, queries_.get(), queries);
  }
  res.matches = n;
  n = bucket(prev, cur, n);
  int obs = 0;
  for (int i = 0; i < n; ++i) {
    if (refine(prev, cur, matches_[i], &observations_[obs])) observation_match_[obs++] = i;
  }
  res.bucketed = obs;
  cur_ = 1 - cur_;
  if (obs < params_.egomotion.min_inliers) {
    res.status = VoStatus::kTooFewMatches;
    have_motion_ = false;
    return res;
  }
  const std::uint64_t seed = params_.seed ^ (frame_number * 0x9E3779B97F4A7C15ULL);
  res.motion = egomotion_.estimate(camera_, observations_.get(), obs, params_.egomotion, seed);
  if (!res.motion.ok) {
    res.status = VoStatus::kNoConsensus;
    have_motion_ = false;
    return res;
  }
  for (int i = 0; i < obs; ++i) {
    if (!egomotion_.inlier(i)) continue;
    const CircularMatch& m = matches_[observation_match_[i]];
    cur.left.age[m.lc] = static_cast<std::uint8_t>(std::min(255, prev.left.age[m.lp] + 1));
    if (prev.left.age[m.lp] > 0) ++res.tracked;
  }
  res.status = VoStatus::kMotion;
  last_motion_ = res.motion;
  have_motion_ = true;
  return res;
}

}  // namespace rtfuse::vision
