#include "drivers/camera/zed_usb_hint.hpp"

#include <cstdio>

namespace rtfuse::drivers {

namespace {

bool digit(char c) { return c >= '0' && c <= '9'; }

// The part of `offered` that describes YUYV: from "YUYV " at the start of an
// entry up to the next ';' (entries are "FMT sizes; FMT sizes" or, after the
// detailed one, "; also MJPG, UYVY" which names no sizes).
std::string_view yuyv_entry(std::string_view offered) {
  std::size_t at = 0;
  for (;;) {
    const std::size_t p = offered.find("YUYV ", at);
    if (p == std::string_view::npos) return {};
    // Only at the start of an entry, not inside "also YUYV, ...".
    if (p == 0 || (p >= 2 && offered[p - 2] == ';' && offered[p - 1] == ' ')) {
      const std::size_t end = offered.find(';', p);
      return offered.substr(p + 5, end == std::string_view::npos ? std::string_view::npos : end - p - 5);
    }
    at = p + 1;
  }
}

// Calls f(width, height) for every "WxH" in text; ranges ("16x16..1920x1080")
// give both ends, so a stepwise range up to a big size counts as big. Rates
// ("@15/30", "12.5") have no 'x' after them and are skipped.
template <typename F>
int for_each_size(std::string_view text, F f) {
  int n = 0;
  std::size_t i = 0;
  while (i < text.size()) {
    // A number right after '/' is a step ("..1920x1080/2x2"), not a size.
    if (!digit(text[i]) || (i > 0 && (digit(text[i - 1]) || text[i - 1] == '/'))) {
      ++i;
      continue;
    }
    int w = 0;
    while (i < text.size() && digit(text[i])) w = w * 10 + (text[i++] - '0');
    if (i + 1 < text.size() && text[i] == 'x' && digit(text[i + 1])) {
      ++i;
      int h = 0;
      while (i < text.size() && digit(text[i])) h = h * 10 + (text[i++] - '0');
      f(w, h);
      ++n;
    }
  }
  return n;
}

bool vga_side_by_side(int w, int h) {
  const EyeSize vga = eye_size(ZedResolution::kVGA);
  return w <= 2 * vga.width && h <= vga.height;
}

}  // namespace

bool looks_like_usb2(const CameraMode& requested, const hal::VideoFormat& given, std::string_view offered) {
  if (requested.resolution == ZedResolution::kVGA) return false;
  bool only_vga = true;
  bool any_vga = false;
  const int sizes = for_each_size(yuyv_entry(offered), [&](int w, int h) {
    only_vga = only_vga && vga_side_by_side(w, h);
    any_vga = any_vga || (w == 2 * eye_size(ZedResolution::kVGA).width && h == eye_size(ZedResolution::kVGA).height);
  });
  if (sizes > 0) return only_vga && any_vga;
  // No size list (the device enumerates nothing): judge by what it gave.
  const EyeSize vga = eye_size(ZedResolution::kVGA);
  return given.width == 2 * vga.width && given.height == vga.height;
}

std::string zed_usb2_hint(const CameraMode& requested, const hal::VideoFormat& given, std::string_view offered) {
  if (!looks_like_usb2(requested, given, offered)) return {};
  const EyeSize vga = eye_size(ZedResolution::kVGA);
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "the camera offers only VGA side-by-side frames (%dx%d) but %s (%dx%d) was asked for: this looks "
                "like a USB 2 connection (a ZED gives only VGA over USB 2). Plug it into a USB 3 port with a USB 3 "
                "cable (no USB 2 hub in between), or set the camera's resolution to \"VGA\"",
                2 * vga.width, vga.height, resolution_name(requested.resolution), side_by_side_width(requested),
                side_by_side_height(requested));
  return buf;
}

}  // namespace rtfuse::drivers
