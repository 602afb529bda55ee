// The camera's factory calibration file (SN<serial>.conf), then the
// rectification the camera computes from it at start-up: the first byte
// picks the resolution, the rest is the file.
// Property: the file is refused with the line and key, or it gives finite
// positive intrinsics; the rectification is refused with a reason, or it is
// finite with a positive baseline.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "drivers/camera/stereo_rectification.hpp"
#include "drivers/camera/zed_calibration.hpp"
#include "fuzz_check.hpp"

using namespace rtfuse::drivers;

namespace {

bool positive_finite(const CameraIntrinsics& c) {
  const double all[] = {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3};
  for (double v : all)
    if (!std::isfinite(v)) return false;
  return c.fx > 0.0 && c.fy > 0.0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const ZedResolution resolution = static_cast<ZedResolution>(data[0] % 4);
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  ZedCalibration calibration;
  std::string error;
  if (!parse_zed_calibration(text, "SN1010.conf", resolution, 0, &calibration, &error)) {
    FUZZ_CHECK(!error.empty(), "a refused file says why");
    return 0;
  }
  const StereoCalibration& s = calibration.stereo;
  FUZZ_CHECK(calibration.resolution == resolution, "the resolution asked for");
  FUZZ_CHECK(s.width > 0 && s.height > 0, "image size known");
  FUZZ_CHECK(positive_finite(s.left) && positive_finite(s.right), "intrinsics finite, focal lengths positive");
  FUZZ_CHECK(s.rotation.allFinite() && s.translation.allFinite(), "extrinsics finite");

  StereoRectification rect;
  if (!compute_stereo_rectification(s, &rect, &error)) {
    FUZZ_CHECK(!error.empty(), "a refused calibration says why");
    return 0;
  }
  FUZZ_CHECK(std::isfinite(rect.fx) && rect.fx > 0.0 && std::isfinite(rect.fy) && rect.fy > 0.0, "rectified focal");
  FUZZ_CHECK(std::isfinite(rect.baseline_m) && rect.baseline_m > 0.0, "positive baseline");
  FUZZ_CHECK(rect.q.allFinite(), "finite reprojection");
  return 0;
}
