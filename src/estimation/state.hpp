#pragma once
// The 15-state omnidirectional model of robot_localization, same order:
// pose in the world frame, velocities and accelerations in base_link.
#include <cstdint>

#include <Eigen/Core>

namespace rtfuse::est {

enum StateIndex : int {
  kX = 0, kY, kZ,
  kRoll, kPitch, kYaw,
  kVx, kVy, kVz,
  kVroll, kVpitch, kVyaw,
  kAx, kAy, kAz,
};

constexpr int kStateSize = 15;

using StateVector = Eigen::Matrix<double, kStateSize, 1>;
using StateMatrix = Eigen::Matrix<double, kStateSize, kStateSize>;
using Matrix3 = Eigen::Matrix3d;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

// Which of the 15 variables a sensor (or one measurement) updates; bit i is
// StateIndex i, the same meaning as robot_localization's 15-boolean config.
using UpdateMask = std::uint16_t;

constexpr UpdateMask mask_bit(int index) { return static_cast<UpdateMask>(1u << index); }
constexpr bool mask_has(UpdateMask m, int index) { return (m >> index) & 1u; }
constexpr UpdateMask kPositionMask = mask_bit(kX) | mask_bit(kY) | mask_bit(kZ);
constexpr UpdateMask kOrientationMask = mask_bit(kRoll) | mask_bit(kPitch) | mask_bit(kYaw);
constexpr UpdateMask kPoseMask = kPositionMask | kOrientationMask;
constexpr UpdateMask kLinearVelocityMask = mask_bit(kVx) | mask_bit(kVy) | mask_bit(kVz);
constexpr UpdateMask kAngularVelocityMask = mask_bit(kVroll) | mask_bit(kVpitch) | mask_bit(kVyaw);
constexpr UpdateMask kTwistMask = kLinearVelocityMask | kAngularVelocityMask;
constexpr UpdateMask kAccelerationMask = mask_bit(kAx) | mask_bit(kAy) | mask_bit(kAz);
constexpr UpdateMask kAllMask = 0x7FFF;

inline bool is_angle_index(int i) { return i == kRoll || i == kPitch || i == kYaw; }

}  // namespace rtfuse::est
