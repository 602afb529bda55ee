#pragma once
// One rectified stereo pair as a PNG: left | right side by side in RGB, with
// horizontal guide lines across both halves. It is the picture to trust a
// calibration by: after rectification a scene point lies on the same row in
// both eyes, so every feature must sit at the same height against a line in
// the left and in the right half.
//
// A tool for snapshots (allocates, does file I/O); never on the real-time path.
#include <cstdint>
#include <string>

namespace rtfuse::apps {

// The guide lines' colour: pure green stands out against any grey.
constexpr std::uint8_t kGuideRgb[3] = {0, 255, 0};

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

}  // namespace rtfuse::apps
