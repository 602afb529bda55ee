#include "apps/mapper_files.hpp"

#include <cstdio>

#include "apps/map_outputs.hpp"
#include "mapping/map_digest.hpp"

namespace rtfuse::apps {

bool write_mapper_files(MapperDevice& mapper, const std::string& prefix, const std::string& title,
                        std::string* error) {
  MapOutputs out;
  out.prefix = prefix;
  out.title = title;
  for (int i = 0; i < mapper.trajectory_size(); ++i) {
    out.path.push_back({mapper.trajectory()[i].x, mapper.trajectory()[i].y});
  }
  const MapperStats s = mapper.stats();
  const mapping::OccupancyMap& map = mapper.map();
  char line[160];
  out.figures.push_back("# the map");
  std::snprintf(line, sizeof line, "keyframes   %lld (%lld dropped)", static_cast<long long>(s.inserted),
                static_cast<long long>(mapper.dropped()));
  out.figures.push_back(line);
  std::snprintf(line, sizeof line, "voxels      %.2f cm, range %.1f m", mapper.config().resolution_m * 100.0,
                mapper.config().max_range_m);
  out.figures.push_back(line);
  std::snprintf(line, sizeof line, "known       %llu", static_cast<unsigned long long>(map.known_voxels()));
  out.figures.push_back(line);
  std::snprintf(line, sizeof line, "occupied    %llu", static_cast<unsigned long long>(map.occupied_voxels()));
  out.figures.push_back(line);
  std::snprintf(line, sizeof line, "memory      %.2f MB", static_cast<double>(map.store().bytes_used()) / 1e6);
  out.figures.push_back(line);
  std::snprintf(line, sizeof line, "digest      %016llx",
                static_cast<unsigned long long>(mapping::map_digest(map)));
  out.figures.push_back(line);
  out.figures.push_back("");
  out.figures.push_back("# the grid");
  std::snprintf(line, sizeof line, "heights     %.2f to %.2f m", mapper.config().grid_min_z_m,
                mapper.config().grid_max_z_m);
  out.figures.push_back(line);
  return write_map_outputs(map, mapper.grid_spec(), mapper.grid_cells(), out, error);
}

}  // namespace rtfuse::apps
