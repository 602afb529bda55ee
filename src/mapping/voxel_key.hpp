#pragma once
// Voxel addresses with OctoMap's conventions, so a voxel here is the voxel
// of the same key in an OcTree of the same resolution: 16 bits per axis,
// key 32768 holding [0, resolution) and the map reaching 32768 voxels each
// way from the origin. The conversions are OctoMap's arithmetic in the same
// precision (double scale, floor), which is what puts a point on a voxel
// boundary into the same voxel as OctoMap does.
#include <cmath>
#include <cstdint>

#include "mapping/map_point.hpp"

namespace rtfuse::mapping {

inline constexpr int kKeyCentre = 32768;  // OctoMap's tree_max_val at depth 16
inline constexpr int kTreeDepth = 16;

struct VoxelKey {
  std::uint16_t k[3] = {0, 0, 0};

  friend bool operator==(const VoxelKey& a, const VoxelKey& b) noexcept {
    return a.k[0] == b.k[0] && a.k[1] == b.k[1] && a.k[2] == b.k[2];
  }
  friend bool operator!=(const VoxelKey& a, const VoxelKey& b) noexcept { return !(a == b); }
};

class VoxelGrid {
 public:
  explicit VoxelGrid(double resolution) noexcept : resolution_(resolution), inverse_(1.0 / resolution) {}

  double resolution() const noexcept { return resolution_; }

  // OctoMap's coordToKeyChecked: false outside the map (and for NaN or
  // infinity, which OctoMap's int conversion happens to reject too).
  bool key_of(double coordinate, std::uint16_t& key) const noexcept {
    const double scaled = std::floor(inverse_ * coordinate);
    if (!(scaled >= -kKeyCentre && scaled < kKeyCentre)) return false;
    key = static_cast<std::uint16_t>(static_cast<int>(scaled) + kKeyCentre);
    return true;
  }
  bool key_of(const MapPoint& p, VoxelKey& key) const noexcept {
    return key_of(p.x, key.k[0]) && key_of(p.y, key.k[1]) && key_of(p.z, key.k[2]);
  }

  // The centre of a voxel along one axis (OctoMap's keyToCoord).
  double centre(std::uint16_t key) const noexcept {
    return (static_cast<double>(static_cast<int>(key) - kKeyCentre) + 0.5) * resolution_;
  }

 private:
  double resolution_;
  double inverse_;
};

}  // namespace rtfuse::mapping
