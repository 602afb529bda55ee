#pragma once
// The factory calibration file of a ZED-class stereo camera (SN<serial>.conf,
// downloaded from calib.stereolabs.com/?SN=<serial>), read into OpenCV's
// conventions (stereo_calibration.hpp) for the resolution the camera runs.
//
// The file is INI text:
//   [LEFT_CAM_HD]        one section per eye and resolution (2K, FHD, HD, VGA)
//   fx=699.34            fx fy cx cy k1 k2 p1 p2 k3: pixels / plumb-bob
//   ...
//   [STEREO]
//   Baseline=119.997     mm
//   TY=0.00157           mm (some files: TY_HD, which then wins)
//   TZ=0.00237           mm (some files: TZ_HD, which then wins)
//   CV_HD=0.0125         rad, RX_HD, RZ_HD: rotation vector components
// Other keys and sections ([MISC], [IMU], k4.., other resolutions) are
// skipped; '#' and ';' start comment lines.
//
// Convention (ZED SDK file -> OpenCV's x_right = R * x_left + T):
//   rotation    = (RX_<res>, CV_<res>, RZ_<res>): CV is about the optical
//                 frame's y axis (vertical, the "convergence" of the eyes), RX
//                 about x, RZ about z; the vector is used as OpenCV's R as it
//                 stands. Source: Stereolabs' own OpenCV samples
//                 (stereolabs/zed-opencv-native and zed-open-capture,
//                 examples/include/calibration.hpp, initCalibration) build
//                 R = Rodrigues(RX, CV, RZ) and pass it to cv::stereoRectify
//                 unchanged; rtabmap's ZED Open Capture driver
//                 (CameraStereoZedOC.cpp) does the same.
//   translation = -(Baseline, TY, TZ) / 1000 m: (Baseline, TY, TZ) is where
//                 the right optical centre sits in the left camera's frame
//                 (the SDK's stereo_transform is "left to right" and its
//                 baseline is its positive x), so the left frame's origin
//                 seen from the right camera is -Baseline along x. rtabmap
//                 negates the same way ("inverted to get positive
//                 baseline"); Stereolabs' sample passes +Baseline, which
//                 gives the same R1/R2 and remap tables (stereoRectify aligns
//                 the baseline with +x or -x alike) and only flips the sign
//                 of P2's baseline term.
//   Stereolabs does not document the frame of TY/TZ beyond this; they are a
//   fraction of a millimetre and move the rectification by far less than a
//   pixel either way.
#include <cstdint>
#include <string>
#include <string_view>

#include "drivers/camera/camera_modes.hpp"
#include "drivers/camera/stereo_calibration.hpp"

namespace rtfuse::drivers {

// Files larger than this are not calibration files (a real one is ~2 KiB).
constexpr std::size_t kMaxZedCalibrationBytes = 256 * 1024;
// Longer lines are rejected, not truncated.
constexpr std::size_t kMaxZedCalibrationLine = 256;

struct ZedCalibration {
  // From the file name SN<serial>.conf; 0 when the name has another form.
  std::int64_t serial = 0;
  ZedResolution resolution = ZedResolution::kHD;
  StereoCalibration stereo;  // for `resolution`, metres and radians
};

// Reads the calibration of `resolution` from the text of a factory file.
// `name` is the file's name or path, used in messages and for the serial
// (its last path component must be SN<serial>.conf when expected_serial is
// not 0, and that serial must equal expected_serial). On failure *error
// names the file, the line and the key, and the likely fix. Never throws on
// any input; allocates (start-up only).
bool parse_zed_calibration(std::string_view text, std::string_view name, ZedResolution resolution,
                           std::int64_t expected_serial, ZedCalibration* calibration, std::string* error);

// The bytes of the file at `path` (at most kMaxZedCalibrationBytes); on
// failure *error names the file and the errno text.
bool read_zed_calibration_file(const std::string& path, std::string* text, std::string* error);

// Reads the file at `path` and parses it as above.
bool load_zed_calibration(const std::string& path, ZedResolution resolution, std::int64_t expected_serial,
                          ZedCalibration* calibration, std::string* error);

}  // namespace rtfuse::drivers
