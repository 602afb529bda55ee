#include "vision/feature_index.hpp"

#include <algorithm>

namespace rtfuse::vision {

FeatureIndex::FeatureIndex(int width, int height, int max_features)
    : width_(std::max(1, width)),
      height_(std::max(1, height)),
      capacity_(max_features),
      cells_(((width_ - 1) >> kCellShift) + 1),
      start_(new int[static_cast<std::size_t>(kFeatureClasses * height_ + 1)]()),
      order_(new int[static_cast<std::size_t>(std::max(1, max_features))]()),
      u_(new int[static_cast<std::size_t>(std::max(1, max_features))]()),
      cell_start_(new int[static_cast<std::size_t>(kFeatureClasses * height_ * cells_)]()) {}

void FeatureIndex::build(const Feature* features, int count) noexcept {
  features_ = features;
  count_ = 0;
  size_ = count;
  const int rows = kFeatureClasses * height_;
  std::fill(start_.get(), start_.get() + rows + 1, 0);
  auto row_of = [this](const Feature& f) { return f.cls * height_ + f.v; };
  auto usable = [this](const Feature& f) { return f.cls < kFeatureClasses && f.v >= 0 && f.v < height_; };
  for (int i = 0; i < count && count_ < capacity_; ++i) {
    if (!usable(features[i])) continue;
    ++start_[row_of(features[i]) + 1];
    ++count_;
  }
  for (int r = 0; r < rows; ++r) start_[r + 1] += start_[r];
  // A stable counting sort by row: start_[r] walks forward while filling
  // and is put back afterwards.
  int placed = 0;
  for (int i = 0; i < count && placed < count_; ++i) {
    if (!usable(features[i])) continue;
    const int k = start_[row_of(features[i])]++;
    order_[k] = i;
    u_[k] = features[i].u;
    ++placed;
  }
  for (int r = rows; r > 0; --r) start_[r] = start_[r - 1];
  start_[0] = 0;
  // Columns in order within each row (insertion sort: rows are short and
  // usually sorted already; stable, so equal columns keep their order).
  for (int r = 0; r < rows; ++r) {
    for (int k = start_[r] + 1; k < start_[r + 1]; ++k) {
      const int o = order_[k], u = u_[k];
      int j = k - 1;
      while (j >= start_[r] && u_[j] > u) {
        order_[j + 1] = order_[j];
        u_[j + 1] = u_[j];
        --j;
      }
      order_[j + 1] = o;
      u_[j + 1] = u;
    }
    int* cell = cell_start_.get() + r * cells_;
    int k = start_[r];
    for (int c = 0; c < cells_; ++c) {
      while (k < start_[r + 1] && cell_of(u_[k]) < c) ++k;
      cell[c] = k;
    }
  }
}

}  // namespace rtfuse::vision
