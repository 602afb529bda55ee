#pragma once
// The socket through which the mapper's 2-D grid reaches the code that
// plans on it (the navigator), as frame_consumer.hpp is the camera's: a
// consumer plugs in at start-up and neither side knows the other's type.
//
// The source calls its consumers on its own thread, with each grid it
// makes and, for every keyframe it took in (mapped, or skipped because the
// robot had not moved), with that keyframe's stamp: the map is known to be
// current as of then even when no new grid was due. A consumer must copy
// what it keeps and return without blocking; work belongs on its thread.
#include <cstdint>
#include <string>

#include "core/time.hpp"

namespace rtfuse {

// A grid's cells (nav_msgs/OccupancyGrid values: -1 unknown, 0 free, 100
// occupied; row 0 the lowest y) and where they lie in the map's frame.
struct GridLayout {
  int width = 0;
  int height = 0;
  double resolution_m = 0.0;
  double origin_x = 0.0;  // cell (0, 0)'s lower-left corner
  double origin_y = 0.0;
};

class GridConsumer {
 public:
  virtual ~GridConsumer() = default;
  // The source's thread: a new grid of the layout the source was attached
  // with, made from the keyframes up to `stamp`.
  virtual void on_grid(const std::int8_t* cells, TimeNs stamp) noexcept = 0;
  // The source's thread: a keyframe at `stamp` was taken in.
  virtual void on_map_current(TimeNs stamp) noexcept = 0;
};

class GridSource {
 public:
  virtual ~GridSource() = default;
  // Start-up only, before the source's thread runs. False with *error when
  // the source makes no grid or has no room for another consumer.
  virtual bool attach(GridConsumer& consumer, std::string* error) = 0;
  // Fixed for the run.
  virtual GridLayout grid_layout() const noexcept = 0;
};

}  // namespace rtfuse
