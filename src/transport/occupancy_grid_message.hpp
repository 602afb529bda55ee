#pragma once
// The mapper's 2-D grid as occupancy_grid_t (nav_msgs/OccupancyGrid), for
// lcm-spy, a planner and anything that speaks ROS's map. Like the camera's
// encoders it allocates once, in create(), for the largest grid, and
// encode() only copies numbers and cells into the message and encodes
// into the buffer sized then.
#include <cstdint>
#include <memory>
#include <string>

#include "core/time.hpp"
#include "transport/camera_messages.hpp"

namespace rtfuse::transport {

struct OccupancyGridLayout {
  int width = 0;          // cells along x
  int height = 0;         // cells along y
  double resolution = 0;  // metres per cell
  double origin_x = 0.0;  // cell (0, 0)'s lower-left corner in the frame, metres
  double origin_y = 0.0;
};

class OccupancyGridEncoder {
 public:
  // For grids of at most max_cells cells in frame_id. nullptr and *error
  // when max_cells is not positive or too large for one LCM message.
  static std::unique_ptr<OccupancyGridEncoder> create(int max_cells, const std::string& frame_id,
                                                      TimeNs map_start, std::string* error);
  ~OccupancyGridEncoder();
  OccupancyGridEncoder(const OccupancyGridEncoder&) = delete;
  OccupancyGridEncoder& operator=(const OccupancyGridEncoder&) = delete;

  // cells: layout.width * layout.height values (-1, 0..100), row 0 the
  // lowest y. An empty message (ok() false) and a counted failure when the
  // layout holds more cells than max_cells or a value is out of range.
  // No allocation.
  EncodedMessage encode(const OccupancyGridLayout& layout, const std::int8_t* cells, TimeNs stamp) noexcept;

  std::int64_t encode_failures() const noexcept;

 private:
  struct Impl;
  explicit OccupancyGridEncoder(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rtfuse::transport
