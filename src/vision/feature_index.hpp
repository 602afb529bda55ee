#pragma once
// The features of one image sorted into square bins per class, so a search
// window visits only the bins it overlaps (a counting sort into fixed
// arrays, rebuilt every frame, sized once).
#include <cstdint>
#include <memory>

#include "vision/feature_detector.hpp"

namespace rtfuse::vision {

class FeatureIndex {
 public:
  // For images of width x height (feature coordinates) holding at most
  // max_features features; bins of bin_size pixels.
  FeatureIndex(int width, int height, int bin_size, int max_features);

  // Indexes features[0..count) (at most max_features; the array must stay
  // alive and unchanged while the index is used).
  void build(const Feature* features, int count) noexcept;

  const Feature* features() const noexcept { return features_; }
  int count() const noexcept { return count_; }

  // Calls visit(index) for every feature of class cls with u in [u0, u1]
  // and v in [v0, v1], bin by bin (rows of bins top to bottom, left to
  // right), in the features' order within a bin: a fixed order, so ties
  // resolve the same way every time.
  template <class Visit>
  void for_each_in(int cls, int u0, int u1, int v0, int v1, Visit&& visit) const noexcept {
    if (u1 < u0 || v1 < v0) return;
    const int bu0 = clamp_bin(u0, cols_), bu1 = clamp_bin(u1, cols_);
    const int bv0 = clamp_bin(v0, rows_), bv1 = clamp_bin(v1, rows_);
    for (int bv = bv0; bv <= bv1; ++bv) {
      for (int bu = bu0; bu <= bu1; ++bu) {
        const int b = (cls * rows_ + bv) * cols_ + bu;
        for (int k = start_[b]; k < start_[b + 1]; ++k) {
          const int i = order_[k];
          const Feature& f = features_[i];
          if (f.u >= u0 && f.u <= u1 && f.v >= v0 && f.v <= v1) visit(i);
        }
      }
    }
  }

 private:
  int clamp_bin(int x, int n) const noexcept {
    const int b = x < 0 ? 0 : x / bin_size_;
    return b >= n ? n - 1 : b;
  }

  int bin_size_, cols_, rows_, capacity_;
  const Feature* features_ = nullptr;
  int count_ = 0;
  std::unique_ptr<int[]> start_;  // per bin (class-major), first position in order_; one more at the end
  std::unique_ptr<int[]> order_;  // feature indices sorted by bin, stable
};

}  // namespace rtfuse::vision
