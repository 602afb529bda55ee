#pragma once
// The [camera] section's factory calibration. Its bytes are read once, at
// start-up, and then travel with the configuration: the camera driver, the
// simulated camera and the recording all use the same text, and a replay on
// another machine uses the text the recording carries instead of a file
// that may not be there.
#include <cstdint>
#include <string>

#include "drivers/camera/zed_calibration.hpp"
#include "runtime/config/hardware_config.hpp"

namespace rtfuse {

// The key under which a recording carries the calibration text.
constexpr const char* kCameraCalibrationKey = "camera.calibration";

// Reads calibration_file into calibration_text unless the text is already
// there. False with *error naming the file and the errno text.
bool resolve_camera_calibration(CameraSection* camera, std::string* error);

// The calibration for the section's resolution, from calibration_text (read
// from calibration_file first when empty). expected_serial 0 accepts any
// camera. On failure *error names the file, line and key.
bool load_camera_calibration(const CameraSection& camera, std::int64_t expected_serial,
                             drivers::ZedCalibration* out, std::string* error);

}  // namespace rtfuse
