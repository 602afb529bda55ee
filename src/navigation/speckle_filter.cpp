#include "navigation/speckle_filter.hpp"

namespace rtfuse::navigation {

std::size_t drop_speckles(const std::int8_t* in, std::int8_t* out, int width, int height,
                          int occupied_from) noexcept {
  if (in == nullptr || out == nullptr || width <= 0 || height <= 0) return 0;
  const auto is_obstacle = [occupied_from](std::int8_t v) { return v >= occupied_from; };
  std::size_t dropped = 0;
  for (int y = 0; y < height; ++y) {
    const std::int8_t* row = in + static_cast<std::size_t>(y) * static_cast<std::size_t>(width);
    std::int8_t* out_row = out + static_cast<std::size_t>(y) * static_cast<std::size_t>(width);
    for (int x = 0; x < width; ++x) {
      const std::int8_t v = row[x];
      out_row[x] = v;
      if (!is_obstacle(v)) continue;
      bool neighbour = false;
      for (int dy = -1; dy <= 1 && !neighbour; ++dy) {
        const int ny = y + dy;
        if (ny < 0 || ny >= height) continue;
        const std::int8_t* nrow = in + static_cast<std::size_t>(ny) * static_cast<std::size_t>(width);
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx;
          if ((dx == 0 && dy == 0) || nx < 0 || nx >= width) continue;
          if (is_obstacle(nrow[nx])) {
            neighbour = true;
            break;
          }
        }
      }
      if (!neighbour) {
        out_row[x] = 0;
        ++dropped;
      }
    }
  }
  return dropped;
}

}  // namespace rtfuse::navigation
