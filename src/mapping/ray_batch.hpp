#pragma once
// Four rays stepped at once in the four 64-bit lanes of AVX2, each exactly
// as run_ray (ray_traversal.hpp) steps it alone: the same double sums, the
// same integer comparisons of their bits, the same tie rules, so the same
// voxels. One ray's steps are a chain of dependent compares and selects of
// a few cycles each that leaves most of the core idle; four independent
// chains in one register fill it. On a CPU without AVX2 (and on aarch64)
// the caller steps the rays one by one.
#include <cstddef>
#include <cstdint>

#include "mapping/ray_traversal.hpp"
#include "mapping/scan_window.hpp"

namespace rtfuse::mapping {

// Whether step_rays4 runs here.
bool ray_batch_available() noexcept;

// Steps the rays of the lanes set in `live` (bit i: rays[i], a kFast
// RayState, not ended), writing to out the voxels the caller has to look
// at: those outside the scan's window and those whose window bit is not
// set yet (a voxel may come more than once: the caller's visit() sets the
// bits, so it decides). A voxel whose bit is set was visited before and is
// left out. Returns when a live ray ends (its bit cleared: the caller may
// start another in its lane) or when out may have no room for another
// step, with the number of keys written and rays[] and live updated, so
// the same call resumes. capacity at least 4. Only where
// ray_batch_available().
std::size_t step_rays4(RayState* rays, unsigned& live, const ScanWindow::Probe& window, std::uint64_t* out,
                       std::size_t capacity) noexcept;

}  // namespace rtfuse::mapping
