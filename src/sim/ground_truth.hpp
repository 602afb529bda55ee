#pragma once
// The ground truth as the odometry message the simulated robot publishes
// ("sim/ground_truth", odom -> base_link), with the semantics of the older
// LCM-level simulator: exact pose and twist, zero covariances.
#include <cstdint>

#include "core/time.hpp"
#include "rtfuse/odometry_t.hpp"
#include "sim/truth_trajectory.hpp"

namespace rtfuse::sim {

constexpr const char* kGroundTruthChannel = "sim/ground_truth";
constexpr const char* kGroundTruthFrame = "odom";
constexpr const char* kGroundTruthChildFrame = "base_link";

// Fills every field of *msg. The frame names fit std::string's inline
// buffer, so this never allocates.
void fill_ground_truth(const TruthState& truth, TimeNs stamp, std::int32_t seq, rtfuse::odometry_t* msg) noexcept;

}  // namespace rtfuse::sim
