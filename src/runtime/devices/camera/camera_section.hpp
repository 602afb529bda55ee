#pragma once
// [camera]: a ZED-class stereo camera on V4L2 (or the simulated robot's), as
// the TOML describes it. Plain values; camera_device.cpp turns them into the
// driver's config. Schema: docs/configuration.md.
#include <cstdint>
#include <string>

#include "runtime/config/name.hpp"

namespace rtfuse {

struct CameraSection {
  bool enabled = false;
  Name device{"/dev/video0"};
  std::string calibration_file;  // the factory SN<serial>.conf (resolved path)
  // The calibration file's bytes when they come from elsewhere than the file
  // (the embedded config's, a recording's), or once read at start-up (see
  // camera_calibration.hpp); "" = read calibration_file.
  std::string calibration_text;
  std::int64_t serial = 0;       // 0: any; else the file must be this camera's
  Name resolution{"VGA"};        // 2K, FHD, HD, VGA
  int fps = 30;
  int buffers = 4;               // V4L2 mmap buffers
  int pool_frames = 4;           // rectified pairs lent to consumers
  Name frame{"camera_optical"};  // the left eye's optical frame: static transform base_link -> frame
  double reopen_backoff_s = 0.25;  // first wait before reopening an unplugged camera
  double reopen_backoff_max_s = 8.0;
  Name info_channel{"rtfuse/camera/info"};        // camera_info_t of the rectified left eye
  Name preview_channel{"rtfuse/camera/preview"};  // image_t, both eyes side by side
  double preview_rate_hz = 1.0;  // 0: no preview
  int preview_downscale = 2;
};

}  // namespace rtfuse
