#pragma once
// One rectified stereo pair as a PNG: left | right side by side in RGB, with
// horizontal guide lines across both halves. It is the picture to trust a
// calibration by: after rectification a scene point lies on the same row in
// both eyes, so every feature must sit at the same height against a line in
// the left and in the right half.
//
// With a header, a band above the pair says what the picture is: where the
// pair comes from and when, its size, the rectified camera (fx, cx, cy,
// baseline) and what the green lines mean, so the PNG reads on its own.
//
// A tool for snapshots (allocates, does file I/O); never on the real-time path.
#include <cstdint>
#include <string>

namespace rtfuse::apps {

// The guide lines' colour: pure green stands out against any grey.
constexpr std::uint8_t kGuideRgb[3] = {0, 255, 0};

// What the header band says besides the size and the guide lines.
struct StereoPngHeader {
  std::string source;  // e.g. "V4L2 camera /dev/video0", "recording drive.lcm"
  std::string when;    // e.g. "frame counter 42, t = 5.000 s into the simulated drive"
  // The rectified pinhole both eyes share, pixels, and the baseline, metres.
  double fx = 0.0, cx = 0.0, cy = 0.0, baseline_m = 0.0;
};

// The header band's height in rows above a pair whose eyes are `width`
// pixels wide: with a header, the pair's row y is the picture's row
// stereo_png_header_rows(width) + y.
int stereo_png_header_rows(int width);

// Writes `path` as an 8-bit RGB PNG of 2 * width x height: the grey left eye
// in the left half, the right eye in the right half (R = G = B = grey), and
// rows guide_every_px, 2 * guide_every_px, ... (y % guide_every_px == 0,
// y > 0) drawn in kGuideRgb across the whole width; guide_every_px <= 0
// draws none. left and right are width x height images whose rows are
// stride bytes apart.
//
// False and *error naming the path and the cause (the errno text for I/O,
// libpng's message otherwise) on failure; a partial regular file is removed.
bool write_stereo_png(const std::string& path, const std::uint8_t* left, const std::uint8_t* right, int width,
                      int height, int stride, int guide_every_px, std::string* error);

// As above with the header band on top: 2 * width x (header rows + height),
// the pair and its guide lines moved down by stereo_png_header_rows(width)
// and otherwise the same pixels. A null header is the picture above.
bool write_stereo_png(const std::string& path, const std::uint8_t* left, const std::uint8_t* right, int width,
                      int height, int stride, int guide_every_px, const StereoPngHeader* header, std::string* error);

}  // namespace rtfuse::apps
