#include "runtime/devices/camera/camera_calibration.hpp"

namespace rtfuse {

bool resolve_camera_calibration(CameraSection* camera, std::string* error) {
  if (!camera->calibration_text.empty()) return true;
  return drivers::read_zed_calibration_file(camera->calibration_file, &camera->calibration_text, error);
}

bool load_camera_calibration(const CameraSection& camera, std::int64_t expected_serial,
                             drivers::ZedCalibration* out, std::string* error) {
  drivers::ZedResolution resolution;
  if (!drivers::parse_resolution(camera.resolution.view(), &resolution)) {
    *error = "camera.resolution '" + std::string(camera.resolution.view()) + "' is not one of 2K, FHD, HD, VGA";
    return false;
  }
  if (!camera.calibration_text.empty()) {
    return drivers::parse_zed_calibration(camera.calibration_text, camera.calibration_file, resolution,
                                          expected_serial, out, error);
  }
  return drivers::load_zed_calibration(camera.calibration_file, resolution, expected_serial, out, error);
}

}  // namespace rtfuse
