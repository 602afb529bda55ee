#include "apps/grey_png.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

#include <png.h>

namespace rtfuse::apps {

namespace {

// One PNG decoded by libpng's simplified API into `format` (its own
// conversions), or false with *error naming the path and the cause.
bool read_png(const std::string& path, png_uint_32 format, std::vector<std::uint8_t>* pixels, int* width,
              int* height, std::string* error) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    *error = path + ": cannot open: " + std::strerror(errno);
    return false;
  }
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_stdio(&image, f)) {
    *error = path + ": not a readable PNG: " + image.message;
    std::fclose(f);
    return false;
  }
  image.format = format;
  if (image.width == 0 || image.height == 0 || image.width > 16384 || image.height > 16384) {
    *error = path + ": " + std::to_string(image.width) + " x " + std::to_string(image.height) +
             " pixels: not an image size this reads (1..16384 a side)";
    png_image_free(&image);
    std::fclose(f);
    return false;
  }
  pixels->resize(PNG_IMAGE_SIZE(image));
  const bool ok = png_image_finish_read(&image, nullptr, pixels->data(), 0, nullptr) != 0;
  if (!ok) *error = path + ": cannot decode: " + image.message;
  *width = static_cast<int>(image.width);
  *height = static_cast<int>(image.height);
  png_image_free(&image);
  std::fclose(f);
  return ok;
}

}  // namespace

bool read_grey_png(const std::string& path, GreyPng* out, std::string* error) {
  GreyPng img;
  if (!read_png(path, PNG_FORMAT_GRAY, &img.pixels, &img.width, &img.height, error)) return false;
  *out = std::move(img);
  return true;
}

bool read_luma_png(const std::string& path, GreyPng* out, std::string* error) {
  std::vector<std::uint8_t> rgb;
  int width = 0, height = 0;
  if (!read_png(path, PNG_FORMAT_RGB, &rgb, &width, &height, error)) return false;
  GreyPng img;
  img.width = width;
  img.height = height;
  img.pixels.resize(static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height));
  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    const unsigned r = rgb[3 * i], g = rgb[3 * i + 1], b = rgb[3 * i + 2];
    img.pixels[i] = static_cast<std::uint8_t>((77 * r + 150 * g + 29 * b + 128) >> 8);
  }
  *out = std::move(img);
  return true;
}

}  // namespace rtfuse::apps
