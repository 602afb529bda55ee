#pragma once
// Reading an 8-bit grey image from a PNG (libpng): the KITTI frames of
// rtfuse-vo. Any PNG libpng reads is converted to 8-bit grey. A tool's
// reader (allocates, does file I/O); never on the real-time path.
#include <cstdint>
#include <string>
#include <vector>

namespace rtfuse::apps {

struct GreyPng {
  std::vector<std::uint8_t> pixels;  // width * height, rows packed
  int width = 0;
  int height = 0;
};

// False and *error naming the path and the cause (the errno text when it
// cannot be opened, libpng's message when it is not a readable PNG).
bool read_grey_png(const std::string& path, GreyPng* out, std::string* error);

// As read_grey_png, but a colour PNG becomes its BT.601 luma computed on the
// stored (gamma-encoded) values, Y = (77 R + 150 G + 29 B + 128) >> 8: the Y
// a camera's YUYV carries, which is what the camera path matches on (it
// keeps Y and drops the chroma). libpng's own grey conversion is a linear-light
// one that would give other grey levels. Grey PNGs come out unchanged.
bool read_luma_png(const std::string& path, GreyPng* out, std::string* error);

}  // namespace rtfuse::apps
