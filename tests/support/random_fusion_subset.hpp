#pragma once
// A random fusion vector for the EKF's update tests: `size` distinct state
// variables in ascending order (the order Ekf::correct fuses them in).
#include <algorithm>
#include <random>
#include <vector>

#include "estimation/state.hpp"

namespace rtfuse::test {

inline std::vector<int> random_fusion_subset(std::mt19937& rng, int size) {
  std::vector<int> all(est::kStateSize);
  for (int i = 0; i < est::kStateSize; ++i) all[i] = i;
  std::shuffle(all.begin(), all.end(), rng);
  std::vector<int> idx(all.begin(), all.begin() + size);
  std::sort(idx.begin(), idx.end());
  return idx;
}

}  // namespace rtfuse::test
