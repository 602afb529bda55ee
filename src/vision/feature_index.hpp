#pragma once
// The features of one image sorted by class, row and column, so a search
// window visits only the features it contains: per class and row, a run of
// features in increasing column (a counting sort into fixed arrays, rebuilt
// every frame, sized once), entered through a table of where each stretch
// of kCellWidth columns starts. A stereo search (three rows, a long stretch
// of columns) and a motion search (a square) both cost what they find plus
// a look-up and a step or two per row: a binary search per row was most of
// the matching's time, motion windows being 25 rows tall.
#include <cstdint>
#include <memory>

#include "vision/feature_detector.hpp"

namespace rtfuse::vision {

class FeatureIndex {
 public:
  // For images of width x height (feature coordinates) holding at most
  // max_features features.
  FeatureIndex(int width, int height, int max_features);

  // Indexes features[0..count) (at most max_features; the array must stay
  // alive and unchanged while the index is used).
  void build(const Feature* features, int count) noexcept;

  const Feature* features() const noexcept { return features_; }
  int count() const noexcept { return count_; }  // indexed (usable and within capacity)
  int size() const noexcept { return size_; }    // given to build()

  // Calls visit(index) for every feature of class cls with u in [u0, u1]
  // and v in [v0, v1]: rows top to bottom, columns left to right (a fixed
  // order, so ties resolve the same way every time).
  template <class Visit>
  void for_each_in(int cls, int u0, int u1, int v0, int v1, Visit&& visit) const noexcept {
    if (u1 < u0) return;
    if (v0 < 0) v0 = 0;
    if (v1 >= height_) v1 = height_ - 1;
    const int cell = cell_of(u0);
    for (int v = v0; v <= v1; ++v) {
      const int row = cls * height_ + v;
      const int end = start_[row + 1];
      int k = cell_start_[row * cells_ + cell];
      while (k < end && u_[k] < u0) ++k;
      for (; k < end && u_[k] <= u1; ++k) visit(order_[k]);
    }
  }

  static constexpr int kCellShift = 5;  // 32 columns
  static constexpr int kCellWidth = 1 << kCellShift;

 private:
  int cell_of(int u) const noexcept { return (u < 0 ? 0 : u >= width_ ? width_ - 1 : u) >> kCellShift; }

  int width_, height_, capacity_, cells_;
  const Feature* features_ = nullptr;
  int count_ = 0;
  int size_ = 0;
  std::unique_ptr<int[]> start_;  // per (class, row): first position in order_; one more at the end
  std::unique_ptr<int[]> order_;  // feature indices by class, row, column
  std::unique_ptr<int[]> u_;      // their columns
  // Per (class, row) and stretch of columns: the row's first position whose
  // column's stretch is that one or later.
  std::unique_ptr<int[]> cell_start_;
};

}  // namespace rtfuse::vision
