#pragma once
// What a GNSS receiver puts on the wire, for the driver tests: an NMEA
// sentence with its checksum and CR LF, a UBX frame with its Fletcher sum.
// (The tests check these against published examples before trusting them.)
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace rtfuse::test {

inline std::string nmea_sentence(const std::string& body) {
  unsigned sum = 0;
  for (char c : body) sum ^= static_cast<unsigned char>(c);
  char tail[8];
  std::snprintf(tail, sizeof tail, "*%02X\r\n", sum);
  return "$" + body + tail;
}

inline std::vector<std::uint8_t> ubx_frame(std::uint8_t cls, std::uint8_t id, const std::vector<std::uint8_t>& payload) {
  // Sized once: GCC 12's -Warray-bounds misreads an insert after a short
  // initializer list.
  std::vector<std::uint8_t> f(6 + payload.size() + 2);
  f[0] = 0xB5;
  f[1] = 0x62;
  f[2] = cls;
  f[3] = id;
  f[4] = static_cast<std::uint8_t>(payload.size());
  f[5] = static_cast<std::uint8_t>(payload.size() >> 8);
  for (std::size_t i = 0; i < payload.size(); ++i) f[6 + i] = payload[i];
  std::uint8_t a = 0, b = 0;
  for (std::size_t i = 2; i < 6 + payload.size(); ++i) {
    a = static_cast<std::uint8_t>(a + f[i]);
    b = static_cast<std::uint8_t>(b + a);
  }
  f[6 + payload.size()] = a;
  f[7 + payload.size()] = b;
  return f;
}

}  // namespace rtfuse::test
