#pragma once
// Position values of 8..32 bits from a PDO, turned into one continuous int64
// count. A counter narrower than 64 bits wraps; between two samples the true
// motion is taken as the shortest way round, so it is exact only while the
// shaft moves less than half the counter range between two received samples
// (an 8-bit counter: < 128 counts per SYNC period).
#include <cstdint>

#include "hal/can_bus.hpp"

namespace rtfuse::drivers {

// Little-endian value of `bytes` bytes from data[offset]; caller checked the DLC.
inline std::uint64_t read_le(const hal::CanFrame& frame, int offset, int bytes) noexcept {
  std::uint64_t raw = 0;
  for (int i = 0; i < bytes; ++i) raw |= std::uint64_t{frame.data[offset + i]} << (8 * i);
  return raw;
}

inline std::uint64_t width_mask(int bits) noexcept {
  return bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
}

// The value as the device means it: two's complement when signed.
inline std::int64_t position_from_raw(std::uint64_t raw, int bits, bool is_signed) noexcept {
  raw &= width_mask(bits);
  if (is_signed && bits < 64 && (raw >> (bits - 1)) != 0) {
    return static_cast<std::int64_t>(raw) - static_cast<std::int64_t>(std::uint64_t{1} << bits);
  }
  return static_cast<std::int64_t>(raw);
}

// Shortest signed step from `prev` to `raw` on a `bits`-wide wheel: in
// [-2^(bits-1), 2^(bits-1)). Signedness does not matter: both wrap alike.
inline std::int64_t wrapped_delta(std::uint64_t raw, std::uint64_t prev, int bits) noexcept {
  const std::uint64_t mask = width_mask(bits);
  const std::uint64_t d = (raw - prev) & mask;
  const std::uint64_t half = std::uint64_t{1} << (bits - 1);
  return d >= half ? static_cast<std::int64_t>(d) - static_cast<std::int64_t>(half) * 2
                   : static_cast<std::int64_t>(d);
}

}  // namespace rtfuse::drivers
