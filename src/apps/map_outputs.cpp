#include "apps/map_outputs.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "apps/map_figure.hpp"
#include "mapping/map_server_files.hpp"
#include "mapping/octomap_binary.hpp"

namespace rtfuse::apps {
namespace {

bool write_bytes(const std::string& path, const void* data, std::size_t size, std::string* error) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) {
    *error = path + ": cannot write: " + std::strerror(errno);
    return false;
  }
  const bool ok = std::fwrite(data, 1, size, f) == size;
  const int err = errno;
  if (std::fclose(f) != 0 || !ok) {
    *error = path + ": writing failed: " + std::strerror(ok ? errno : err);
    return false;
  }
  return true;
}

}  // namespace

bool write_map_outputs(const mapping::OccupancyMap& map, const mapping::GridSpec& spec, const std::int8_t* cells,
                       const MapOutputs& out, std::string* error) {
  mapping::OctomapBinaryWriter writer(map.store().capacity().bricks);
  std::vector<std::uint8_t> bt;
  writer.write(map, bt);
  if (!write_bytes(out.prefix + ".bt", bt.data(), bt.size(), error)) return false;
  const double resolution = map.params().resolution;
  const double ox = mapping::grid_origin_x(map.grid(), spec), oy = mapping::grid_origin_y(map.grid(), spec);
  const std::vector<std::uint8_t> pgm = mapping::map_server_pgm(cells, spec.width, spec.height);
  const std::string image = out.prefix + ".pgm";
  const std::string yaml = mapping::map_server_yaml(image.substr(image.find_last_of('/') + 1), resolution, ox, oy);
  if (!write_bytes(image, pgm.data(), pgm.size(), error) ||
      !write_bytes(out.prefix + ".yaml", yaml.data(), yaml.size(), error)) {
    return false;
  }
  MapFigure figure;
  figure.title = out.title;
  figure.cells = cells;
  figure.width = spec.width;
  figure.height = spec.height;
  figure.resolution = resolution;
  figure.origin_x = ox;
  figure.origin_y = oy;
  figure.path = out.path;
  figure.figures = out.figures;
  return write_map_png(figure, out.prefix + ".png", error);
}

}  // namespace rtfuse::apps
