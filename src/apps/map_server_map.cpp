#include "apps/map_server_map.hpp"

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>

namespace rtfuse::apps {

namespace {

// The image's size is bounded so a header cannot ask for gigabytes.
constexpr long kMaxSide = 32768;
constexpr long kMaxPixels = 1L << 28;

// A PGM header's tokens: numbers separated by whitespace, '#' comments to
// the end of the line.
class PgmHeader {
 public:
  PgmHeader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  bool number(long* value) {
    skip();
    if (pos_ >= size_ || !std::isdigit(data_[pos_])) return false;
    long v = 0;
    while (pos_ < size_ && std::isdigit(data_[pos_])) {
      v = v * 10 + (data_[pos_++] - '0');
      if (v > kMaxPixels) return false;
    }
    *value = v;
    return true;
  }
  std::size_t pos() const { return pos_; }
  void advance(std::size_t n) { pos_ += n; }

 private:
  void skip() {
    while (pos_ < size_) {
      if (data_[pos_] == '#') {
        while (pos_ < size_ && data_[pos_] != '\n') ++pos_;
      } else if (std::isspace(data_[pos_])) {
        ++pos_;
      } else {
        return;
      }
    }
  }
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

std::string line_of(const YAML::Mark& mark) { return mark.line >= 0 ? std::to_string(mark.line + 1) : "?"; }

}  // namespace

std::string parse_pgm(const std::uint8_t* data, std::size_t size, const std::string& name, PgmImage* out) {
  if (size < 2 || data[0] != 'P' || (data[1] != '5' && data[1] != '2')) {
    return name + ": not a PGM image (it must start with P5 or P2; save the map as a greyscale PGM)";
  }
  const bool binary = data[1] == '5';
  PgmHeader h(data, size);
  h.advance(2);
  long width = 0, height = 0, max_value = 0;
  if (!h.number(&width) || !h.number(&height) || !h.number(&max_value)) {
    return name + ": its header does not give width, height and maximum value";
  }
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide || width * height > kMaxPixels) {
    return name + ": " + std::to_string(width) + " x " + std::to_string(height) +
           " pixels: each side must be 1 to 32768 and the image at most 2^28 pixels";
  }
  if (max_value < 1 || max_value > 255) {
    return name + ": maximum value " + std::to_string(max_value) +
           ": only 8-bit images (1 to 255) are read; save the map with 8 bits";
  }
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  out->width = static_cast<int>(width);
  out->height = static_cast<int>(height);
  out->max_value = static_cast<int>(max_value);
  out->pixels.assign(pixels, 0);
  if (binary) {
    // Exactly one whitespace byte after the maximum value, then the raster.
    const std::size_t start = h.pos() + 1;
    if (start > size || size - start < pixels) {
      return name + ": truncated: " + std::to_string(pixels) + " pixels expected, " +
             std::to_string(start > size ? 0 : size - start) + " bytes present";
    }
    for (std::size_t i = 0; i < pixels; ++i) {
      if (data[start + i] > max_value) {
        return name + ": pixel " + std::to_string(i) + " is " + std::to_string(data[start + i]) +
               ", above the maximum value " + std::to_string(max_value);
      }
      out->pixels[i] = data[start + i];
    }
    return "";
  }
  for (std::size_t i = 0; i < pixels; ++i) {
    long v = 0;
    if (!h.number(&v)) {
      return name + ": plain PGM: pixel " + std::to_string(i) + " of " + std::to_string(pixels) +
             " is missing or not a number";
    }
    if (v > max_value) {
      return name + ": pixel " + std::to_string(i) + " is " + std::to_string(v) + ", above the maximum value " +
             std::to_string(max_value);
    }
    out->pixels[i] = static_cast<std::uint8_t>(v);
  }
  return "";
}

std::string parse_map_yaml(const std::string& text, const std::string& name, MapServerYaml* out) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    return name + ":" + line_of(e.mark) + ": not YAML: " + e.msg;
  }
  if (!root.IsMap()) return name + ": the file must be a mapping of keys (image, resolution, origin, ...)";
  const auto number = [&](const char* key, double* value, bool required) -> std::string {
    const YAML::Node n = root[key];
    if (!n) return required ? name + ": key '" + key + "' is missing" : "";
    try {
      *value = n.as<double>();
    } catch (const YAML::Exception&) {
      return name + ":" + line_of(n.Mark()) + ": key '" + key + "' must be a number";
    }
    if (!std::isfinite(*value)) return name + ":" + line_of(n.Mark()) + ": key '" + key + "' must be finite";
    return "";
  };
  try {
    const YAML::Node image = root["image"];
    if (!image) return name + ": key 'image' is missing (the map's picture, e.g. image: map.pgm)";
    if (!image.IsScalar() || image.Scalar().empty()) {
      return name + ":" + line_of(image.Mark()) + ": key 'image' must name a file";
    }
    out->image = image.Scalar();
    std::string e = number("resolution", &out->resolution, true);
    if (!e.empty()) return e;
    if (!(out->resolution > 0.0)) {
      return name + ":" + line_of(root["resolution"].Mark()) + ": key 'resolution' must be positive (metres a cell)";
    }
    const YAML::Node origin = root["origin"];
    if (!origin) return name + ": key 'origin' is missing (origin: [x, y, yaw] of the lower-left cell)";
    if (!origin.IsSequence() || origin.size() != 3) {
      return name + ":" + line_of(origin.Mark()) + ": key 'origin' must be [x, y, yaw]";
    }
    double o[3];
    for (std::size_t i = 0; i < 3; ++i) {
      try {
        o[i] = origin[i].as<double>();
      } catch (const YAML::Exception&) {
        return name + ":" + line_of(origin.Mark()) + ": key 'origin' must hold three numbers";
      }
      if (!std::isfinite(o[i])) return name + ":" + line_of(origin.Mark()) + ": key 'origin' must be finite";
    }
    out->origin_x = o[0], out->origin_y = o[1], out->origin_yaw = o[2];
    e = number("occupied_thresh", &out->occupied_thresh, true);
    if (!e.empty()) return e;
    e = number("free_thresh", &out->free_thresh, true);
    if (!e.empty()) return e;
    if (!(out->free_thresh >= 0.0 && out->free_thresh < out->occupied_thresh && out->occupied_thresh <= 1.0)) {
      return name + ": thresholds: 0 <= free_thresh < occupied_thresh <= 1 is needed (map_server's usual 0.196 "
                    "and 0.65)";
    }
    const YAML::Node negate = root["negate"];
    if (negate) {
      const std::string v = negate.IsScalar() ? negate.Scalar() : "";
      if (v == "0" || v == "false") {
        out->negate = false;
      } else if (v == "1" || v == "true") {
        out->negate = true;
      } else {
        return name + ":" + line_of(negate.Mark()) + ": key 'negate' must be 0 or 1";
      }
    }
    const YAML::Node mode = root["mode"];
    if (mode) {
      const std::string v = mode.IsScalar() ? mode.Scalar() : "";
      if (v == "trinary") {
        out->mode = MapMode::kTrinary;
      } else if (v == "scale") {
        out->mode = MapMode::kScale;
      } else if (v == "raw") {
        out->mode = MapMode::kRaw;
      } else {
        return name + ":" + line_of(mode.Mark()) + ": key 'mode' must be trinary, scale or raw";
      }
    }
  } catch (const YAML::Exception& e) {
    return name + ":" + line_of(e.mark) + ": " + e.msg;
  }
  return "";
}

OccupancyGridMap occupancy_of(const MapServerYaml& yaml, const PgmImage& image) {
  OccupancyGridMap map;
  map.width = image.width;
  map.height = image.height;
  map.resolution = yaml.resolution;
  map.origin_x = yaml.origin_x, map.origin_y = yaml.origin_y, map.origin_yaw = yaml.origin_yaw;
  map.cells.assign(image.pixels.size(), -1);
  for (int row = 0; row < image.height; ++row) {
    // The image's top row is the grid's highest y.
    const std::uint8_t* line = image.pixels.data() + static_cast<std::size_t>(image.height - 1 - row) * image.width;
    std::int8_t* cells = map.cells.data() + static_cast<std::size_t>(row) * image.width;
    for (int x = 0; x < image.width; ++x) {
      const double shade = static_cast<double>(line[x]) / image.max_value;  // 0 black .. 1 white
      const double occupancy = yaml.negate ? shade : 1.0 - shade;
      std::int8_t cell;
      if (yaml.mode == MapMode::kRaw) {
        const double value = std::round(shade * 255.0);
        cell = value <= 100.0 ? static_cast<std::int8_t>(value) : std::int8_t{-1};
      } else if (occupancy > yaml.occupied_thresh) {
        cell = 100;
      } else if (occupancy < yaml.free_thresh) {
        cell = 0;
      } else if (yaml.mode == MapMode::kScale) {
        cell = static_cast<std::int8_t>(std::rint((occupancy - yaml.free_thresh) /
                                                  (yaml.occupied_thresh - yaml.free_thresh) * 100.0));
      } else {
        cell = -1;
      }
      cells[x] = cell;
    }
  }
  return map;
}

std::string load_map_server(const std::string& yaml_path, OccupancyGridMap* out) {
  std::ifstream yaml_in(yaml_path);
  if (!yaml_in) return yaml_path + ": cannot be read (is the path right?)";
  std::stringstream text;
  text << yaml_in.rdbuf();
  MapServerYaml yaml;
  std::string error = parse_map_yaml(text.str(), yaml_path, &yaml);
  if (!error.empty()) return error;
  std::string image_path = yaml.image;
  if (image_path[0] != '/') {
    const std::size_t slash = yaml_path.rfind('/');
    if (slash != std::string::npos) image_path = yaml_path.substr(0, slash + 1) + image_path;
  }
  std::ifstream image_in(image_path, std::ios::binary);
  if (!image_in) return yaml_path + ": its image " + image_path + " cannot be read";
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(image_in)), std::istreambuf_iterator<char>());
  PgmImage image;
  error = parse_pgm(bytes.data(), bytes.size(), image_path, &image);
  if (!error.empty()) return error;
  *out = occupancy_of(yaml, image);
  return "";
}

}  // namespace rtfuse::apps
