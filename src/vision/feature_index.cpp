#include "vision/feature_index.hpp"

#include <algorithm>

namespace rtfuse::vision {

FeatureIndex::FeatureIndex(int width, int height, int bin_size, int max_features)
    : bin_size_(bin_size),
      cols_(std::max(1, (width + bin_size - 1) / bin_size)),
      rows_(std::max(1, (height + bin_size - 1) / bin_size)),
      capacity_(max_features),
      start_(new int[static_cast<std::size_t>(kFeatureClasses * cols_ * rows_ + 1)]()),
      order_(new int[static_cast<std::size_t>(std::max(1, max_features))]()) {}

void FeatureIndex::build(const Feature* features, int count) noexcept {
  features_ = features;
  count_ = std::min(count, capacity_);
  const int bins = kFeatureClasses * cols_ * rows_;
  std::fill(start_.get(), start_.get() + bins + 1, 0);
  auto bin_of = [this](const Feature& f) {
    return (f.cls * rows_ + clamp_bin(f.v, rows_)) * cols_ + clamp_bin(f.u, cols_);
  };
  for (int i = 0; i < count_; ++i) ++start_[bin_of(features[i]) + 1];
  for (int b = 0; b < bins; ++b) start_[b + 1] += start_[b];
  // A stable counting sort: start_[b] walks forward while filling, and is
  // put back afterwards.
  for (int i = 0; i < count_; ++i) order_[start_[bin_of(features[i])]++] = i;
  for (int b = bins; b > 0; --b) start_[b] = start_[b - 1];
  start_[0] = 0;
}

}  // namespace rtfuse::vision
