#pragma once
// u-blox UBX frames out of a byte stream: 0xB5 0x62, class, id, a 16-bit
// little-endian length, the payload, and the 8-bit Fletcher checksum of
// class..payload. Only frames whose checksum holds come out. A length
// beyond the buffer is counted and not followed: the framer looks for the
// next sync right after the length field, so a corrupt length never
// swallows the frames behind it (a real frame that long is not one a fix
// needs). A bad checksum is counted and the search goes on after the frame.
// Bytes between frames (NMEA on a shared port) are skipped and counted. No
// allocation: one frame buffer.
#include <cstddef>
#include <cstdint>

#include "core/time.hpp"

namespace rtfuse::drivers {

struct UbxFramerStats {
  std::int64_t frames = 0;
  std::int64_t bad_checksum = 0;
  std::int64_t oversize = 0;  // a length beyond kMaxPayload
  std::int64_t skipped_bytes = 0;
};

class UbxFramer {
 public:
  // NAV-PVT is 92 bytes; NAV-SAT of 60 satellites 728. Larger frames are
  // not ones a fix needs.
  static constexpr std::size_t kMaxPayload = 1024;

  struct Frame {
    std::uint8_t msg_class = 0;
    std::uint8_t msg_id = 0;
    const std::uint8_t* payload = nullptr;  // valid until the next push()
    std::size_t length = 0;
    TimeNs stamp = 0;  // receive time of its first sync byte
  };

  // Feeds one byte received at `stamp`; true when it completed a frame.
  bool push(std::uint8_t byte, TimeNs stamp, Frame* out) noexcept;

  const UbxFramerStats& stats() const noexcept { return stats_; }

 private:
  enum class State : std::uint8_t { kSync1, kSync2, kClass, kId, kLength1, kLength2, kPayload, kCkA, kCkB };

  void restart(std::uint8_t byte, TimeNs stamp) noexcept;

  State state_ = State::kSync1;
  std::uint8_t class_ = 0, id_ = 0, ck_a_ = 0, ck_b_ = 0, rx_ck_a_ = 0;
  std::size_t length_ = 0, got_ = 0;
  TimeNs start_ = 0;
  std::uint8_t payload_[kMaxPayload] = {};
  UbxFramerStats stats_;
};

}  // namespace rtfuse::drivers
