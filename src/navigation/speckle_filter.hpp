#pragma once
// Lone obstacle cells out of an occupancy grid before it becomes costs:
// octomap_server's filter_speckles in the plane. Stereo depth leaves
// single false hits scattered over free space; each would become a lethal
// disc of the inscribed radius in the costmap and can refuse a goal or
// close a passage. A cell at or above occupied_from with no such cell
// among its 8 neighbours reads as free. What it costs: an obstacle seen as
// one cell and nothing around it (thinner than a cell, and seen in no
// neighbouring column) is dropped with the speckles.
#include <cstddef>
#include <cstdint>

namespace rtfuse::navigation {

// out = in with lone obstacle cells made free (0); width x height cells,
// row-major. in and out must not overlap. Returns the cells dropped.
// Bounded: one pass, 9 reads a cell. Never allocates.
std::size_t drop_speckles(const std::int8_t* in, std::int8_t* out, int width, int height,
                          int occupied_from) noexcept;

}  // namespace rtfuse::navigation
