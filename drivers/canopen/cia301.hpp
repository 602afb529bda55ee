#pragma once
// The CiA 301 communication objects the encoder master uses (predefined
// connection set) and the SocketCAN error-class bits it reacts to. Kept here,
// not borrowed from hal/mock, because drivers never include the mocks.
#include <cstdint>

namespace rtfuse::drivers::cia301 {

constexpr std::uint32_t kNmtCobId = 0x000;
constexpr std::uint32_t kDefaultSyncCobId = 0x080;
constexpr std::uint32_t kEmcyBase = 0x080;       // + node-id
constexpr std::uint32_t kTpdo1Base = 0x180;      // + node-id
constexpr std::uint32_t kHeartbeatBase = 0x700;  // + node-id
constexpr std::uint32_t kMaxStandardId = 0x7FF;

constexpr std::uint8_t kNmtStartRemoteNode = 0x01;

// Heartbeat byte (bit 7 is the node-guarding toggle, always 0 in a heartbeat
// but masked anyway so a guarding-style producer is read right).
constexpr std::uint8_t kStateBootUp = 0x00;
constexpr std::uint8_t kStateStopped = 0x04;
constexpr std::uint8_t kStateOperational = 0x05;
constexpr std::uint8_t kStatePreOperational = 0x7F;
constexpr std::uint8_t kStateMask = 0x7F;

constexpr std::uint8_t kHeartbeatDlc = 1;
constexpr std::uint8_t kEmcyDlc = 8;
constexpr std::uint16_t kEmcyErrorReset = 0x0000;

// Error-frame class bits as hal::CanFrame::id carries them (Linux
// <linux/can/error.h> values; the HAL passes them through unchanged).
constexpr std::uint32_t kCanErrBusOff = 0x00000040U;
constexpr std::uint32_t kCanErrRestarted = 0x00000100U;

}  // namespace rtfuse::drivers::cia301
