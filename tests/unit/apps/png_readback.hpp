#pragma once
// The apps tests' look at a PNG they made the code write: read back with
// libpng as 8-bit RGB, and the pixels counted by colour.
#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace rtfuse::apps::test_png {

struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> px;
  const std::uint8_t* at(int x, int y) const { return &px[(static_cast<std::size_t>(y) * width + x) * 3]; }
  bool is(int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b) const {
    const std::uint8_t* p = at(x, y);
    return p[0] == r && p[1] == g && p[2] == b;
  }
  // Pixels of exactly this colour in [x0, x1) x [y0, y1).
  int count(std::uint8_t r, std::uint8_t g, std::uint8_t b, int x0, int y0, int x1, int y1) const {
    int n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) n += is(x, y, r, g, b) ? 1 : 0;
    return n;
  }
  int count(std::uint8_t r, std::uint8_t g, std::uint8_t b) const { return count(r, g, b, 0, 0, width, height); }
};

// The file as libpng reads it; fails the test unless it is 8-bit RGB.
inline RgbImage read_rgb_png(const std::string& path) {
  RgbImage out;
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) {
    ADD_FAILURE() << path << ": " << image.message;
    return out;
  }
  EXPECT_EQ(image.format, static_cast<png_uint_32>(PNG_FORMAT_RGB)) << "8-bit RGB, no alpha";
  image.format = PNG_FORMAT_RGB;
  out.width = static_cast<int>(image.width);
  out.height = static_cast<int>(image.height);
  out.px.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.px.data(), 0, nullptr)) {
    ADD_FAILURE() << path << ": " << image.message;
    out = RgbImage{};
  }
  return out;
}

// A file name of this test process in the test's temporary folder.
inline std::string temp_png(const std::string& prefix, const char* name) {
  return ::testing::TempDir() + prefix + std::to_string(::getpid()) + "_" + name;
}

}  // namespace rtfuse::apps::test_png
