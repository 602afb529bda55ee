#pragma once
// The video modes a ZED-class stereo camera (ZED, ZED 2, ZED 2i, ZED Mini)
// offers over UVC. One YUYV frame holds both eyes side by side, left eye in
// the left half, so the frame is twice an eye wide. The resolution names are
// the suffixes of the factory calibration file's sections ([LEFT_CAM_HD]).
#include <array>
#include <cstddef>
#include <string>
#include <string_view>

namespace rtfuse::drivers {

enum class ZedResolution { k2K, kFHD, kHD, kVGA };

// "2K", "FHD", "HD", "VGA".
const char* resolution_name(ZedResolution resolution) noexcept;
// Case-insensitive ("hd" and "HD" both name HD720). False for anything else.
bool parse_resolution(std::string_view name, ZedResolution* resolution) noexcept;

struct EyeSize {
  int width = 0;
  int height = 0;
};
EyeSize eye_size(ZedResolution resolution) noexcept;

struct CameraMode {
  ZedResolution resolution = ZedResolution::kHD;
  int eye_width = 0;   // one eye, pixels
  int eye_height = 0;
  int fps = 0;
};

// Every mode, by resolution from the largest, then by frame rate.
constexpr int kZedModeCount = 10;
const std::array<CameraMode, kZedModeCount>& zed_modes() noexcept;

// The mode for a resolution name and frame rate. On failure *error lists the
// valid choices ("2K@15, FHD@15/30, HD@15/30/60, VGA@15/30/60/100").
bool find_camera_mode(std::string_view resolution, int fps, CameraMode* mode, std::string* error);

// The side-by-side frame the device delivers for a mode.
constexpr int side_by_side_width(const CameraMode& mode) noexcept { return 2 * mode.eye_width; }
constexpr int side_by_side_height(const CameraMode& mode) noexcept { return mode.eye_height; }
// YUYV: 2 bytes per pixel; bytes of one tightly packed line and frame.
constexpr int kYuyvBytesPerPixel = 2;
constexpr int yuyv_min_bytes_per_line(const CameraMode& mode) noexcept {
  return side_by_side_width(mode) * kYuyvBytesPerPixel;
}
constexpr std::size_t yuyv_frame_bytes(const CameraMode& mode, int bytes_per_line) noexcept {
  return static_cast<std::size_t>(bytes_per_line) * static_cast<std::size_t>(mode.eye_height);
}

}  // namespace rtfuse::drivers
