#include "runtime/devices/camera/camera_config.hpp"

#include <string>

#include "drivers/camera/camera_modes.hpp"
#include "hal/video_stream.hpp"
#include "runtime/config/toml_reader.hpp"
#include "runtime/devices/device_config.hpp"

namespace rtfuse::config {
namespace {

void read_camera(const Section& s, CameraSection& c, const std::string& config_file) {
  s.reject_unknown({"device", "calibration", "serial", "resolution", "fps", "buffers", "pool_frames", "frame",
                    "reopen_backoff", "reopen_backoff_max", "info_channel", "preview_channel", "preview_rate",
                    "preview_downscale"});
  s.require({"calibration"});
  c.enabled = true;
  s.read_name("device", c.device);
  std::string calibration;
  if (s.read("calibration", calibration)) {
    if (calibration.empty()) {
      s.value_error("calibration", "must name the camera's factory calibration file (SN<serial>.conf)");
    } else {
      c.calibration_file = relative_to_config(calibration, config_file);
    }
  }
  read_int(s, "serial", c.serial, 0, std::int64_t{1} << 40);
  s.read_name("resolution", c.resolution);
  read_int(s, "fps", c.fps, 1, 1000);
  drivers::CameraMode mode;
  std::string why;
  if (!drivers::find_camera_mode(c.resolution.view(), c.fps, &mode, &why)) {
    s.value_error(s.has("fps") ? "fps" : "resolution", why);
  }
  read_int(s, "buffers", c.buffers, 2, hal::kMaxVideoBuffers);
  read_int(s, "pool_frames", c.pool_frames, 2, 16);
  s.read_name("frame", c.frame);
  read_number(s, "reopen_backoff", c.reopen_backoff_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "reopen_backoff_max", c.reopen_backoff_max_s, positive_finite, "must be > 0 s and finite");
  if (c.reopen_backoff_max_s < c.reopen_backoff_s) {
    s.value_error("reopen_backoff_max", "must be >= reopen_backoff");
  }
  s.read_name("info_channel", c.info_channel);
  s.read_name("preview_channel", c.preview_channel);
  read_number(s, "preview_rate", c.preview_rate_hz, non_negative_finite, "must be >= 0 Hz and finite (0: no preview)");
  read_int(s, "preview_downscale", c.preview_downscale, 1, 16);
}

}  // namespace

void read_camera_config(const Section& root, RuntimeConfig& cfg) {
  const toml::table* camera = section_table(root, "camera");
  if (camera) read_camera(Section(camera, "camera", root.diag()), cfg.hardware.camera, cfg.source);
}

}  // namespace rtfuse::config
