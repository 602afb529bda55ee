#pragma once
// A point of a scan in the map's frame, in metres. Single precision because
// OctoMap's point3d is: the ray arithmetic that decides which voxels a ray
// crosses starts from these floats, and equality with OctoMap needs the same
// starting values.
namespace rtfuse::mapping {

struct MapPoint {
  float x = 0.0f;
  float y = 0.0f;
  float z = 0.0f;
};

inline bool is_finite(const MapPoint& p) noexcept {
  // Comparisons, not std::isfinite: the build may one day use -ffast-math
  // elsewhere, and x - x is 0 only for finite x.
  return (p.x - p.x) == 0.0f && (p.y - p.y) == 0.0f && (p.z - p.z) == 0.0f;
}

}  // namespace rtfuse::mapping
