// rtfuse-vo's readers of a KITTI-layout sequence: calib.txt (P0, P1) and
// poses.txt. The first byte picks the file.
// Property: refused with "<name>:<line>: what", or a usable camera (finite,
// positive focal length and baseline) / finite rigid poses.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "apps/kitti_sequence.hpp"
#include "fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  std::string error;
  if (data[0] & 1) {
    rtfuse::vision::StereoCameraModel camera;
    if (!rtfuse::apps::parse_kitti_calibration(text, "calib.txt", &camera, &error)) {
      FUZZ_CHECK(error.rfind("calib.txt", 0) == 0, "the error names the file");
      return 0;
    }
    FUZZ_CHECK(std::isfinite(camera.f) && camera.f > 0.0, "positive focal length");
    FUZZ_CHECK(std::isfinite(camera.cu) && std::isfinite(camera.cv), "finite principal point");
    FUZZ_CHECK(std::isfinite(camera.baseline) && camera.baseline > 0.0, "positive baseline");
    return 0;
  }
  std::vector<Eigen::Matrix4d> poses;
  if (!rtfuse::apps::parse_kitti_poses(text, "poses.txt", &poses, &error)) {
    FUZZ_CHECK(error.rfind("poses.txt", 0) == 0, "the error names the file");
    return 0;
  }
  for (const Eigen::Matrix4d& p : poses) FUZZ_CHECK(p.allFinite(), "finite poses");
  return 0;
}
