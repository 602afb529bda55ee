#include "drivers/camera/camera_modes.hpp"

#include <cstdio>

#include "drivers/config_error.hpp"

namespace rtfuse::drivers {

namespace {

constexpr const char* kWho = "zed camera";

// Stereolabs' published modes per eye (ZED, ZED 2, ZED 2i, ZED Mini).
constexpr std::array<CameraMode, kZedModeCount> kModes{{
    {ZedResolution::k2K, 2208, 1242, 15},
    {ZedResolution::kFHD, 1920, 1080, 15},
    {ZedResolution::kFHD, 1920, 1080, 30},
    {ZedResolution::kHD, 1280, 720, 15},
    {ZedResolution::kHD, 1280, 720, 30},
    {ZedResolution::kHD, 1280, 720, 60},
    {ZedResolution::kVGA, 672, 376, 15},
    {ZedResolution::kVGA, 672, 376, 30},
    {ZedResolution::kVGA, 672, 376, 60},
    {ZedResolution::kVGA, 672, 376, 100},
}};

constexpr std::array<ZedResolution, 4> kResolutions{ZedResolution::k2K, ZedResolution::kFHD, ZedResolution::kHD,
                                                    ZedResolution::kVGA};

char upper(char c) { return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c; }

bool same_name(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (upper(a[i]) != upper(b[i])) return false;
  }
  return true;
}

// "2K@15, FHD@15/30, HD@15/30/60, VGA@15/30/60/100"
std::string valid_modes() {
  std::string s;
  for (ZedResolution r : kResolutions) {
    if (!s.empty()) s += ", ";
    s += resolution_name(r);
    char sep = '@';
    for (const CameraMode& m : kModes) {
      if (m.resolution != r) continue;
      s += sep;
      s += std::to_string(m.fps);
      sep = '/';
    }
  }
  return s;
}

}  // namespace

const char* resolution_name(ZedResolution resolution) noexcept {
  switch (resolution) {
    case ZedResolution::k2K: return "2K";
    case ZedResolution::kFHD: return "FHD";
    case ZedResolution::kHD: return "HD";
    case ZedResolution::kVGA: return "VGA";
  }
  return "?";
}

bool parse_resolution(std::string_view name, ZedResolution* resolution) noexcept {
  for (ZedResolution r : kResolutions) {
    if (same_name(name, resolution_name(r))) {
      *resolution = r;
      return true;
    }
  }
  return false;
}

EyeSize eye_size(ZedResolution resolution) noexcept {
  for (const CameraMode& m : kModes) {
    if (m.resolution == resolution) return {m.eye_width, m.eye_height};
  }
  return {};
}

const std::array<CameraMode, kZedModeCount>& zed_modes() noexcept { return kModes; }

bool find_camera_mode(std::string_view resolution, int fps, CameraMode* mode, std::string* error) {
  ZedResolution r{};
  if (!parse_resolution(resolution, &r)) {
    return config_fail(error, kWho, "resolution \"%.*s\" is unknown; valid modes (resolution@fps): %s",
                       static_cast<int>(resolution.size() > 32 ? 32 : resolution.size()), resolution.data(),
                       valid_modes().c_str());
  }
  for (const CameraMode& m : kModes) {
    if (m.resolution == r && m.fps == fps) {
      *mode = m;
      return true;
    }
  }
  return config_fail(error, kWho, "%s has no %d fps mode; valid modes (resolution@fps): %s", resolution_name(r), fps,
                     valid_modes().c_str());
}

}  // namespace rtfuse::drivers
