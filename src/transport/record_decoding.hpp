#pragma once
// What every decoder of a rtfuse/rec/* or rtfuse/hal/* record shares: its
// error messages, the bounds it checks before lcm-gen's decoder trusts a
// count (transport/lcm_wire.hpp), and the decode of the whole message that
// refuses another type, a short record or trailing bytes.
#include <cstdint>
#include <exception>
#include <limits>
#include <string>
#include <utility>

#include "hal/status.hpp"
#include "transport/lcm_wire.hpp"

namespace rtfuse::transport::decoding {

inline void set_error(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

// Every hal_* record starts with fingerprint, utime, time_ns, then the device
// string. Offset just past that string, or -1 (wire::after_string).
inline int after_device_string(const std::uint8_t* b, int size) {
  return wire::after_string(b, size, 8 + 8 + 8, std::numeric_limits<std::int32_t>::max());
}

inline bool count_within(const std::uint8_t* b, int size, int at, int max) {
  if (at < 0 || size - at < 4) return false;
  const std::int32_t v = wire::load_i32(b + at);
  return v >= 0 && v <= max;
}

template <class Msg>
bool decode_message(Msg& msg, const void* data, int size, const char* type, std::string* error) {
  if (data == nullptr || size < 8) {
    set_error(error, std::string(type) + " record of " + std::to_string(size) + " bytes is too short");
    return false;
  }
  if (wire::load_i64(static_cast<const std::uint8_t*>(data)) != Msg::getHash()) {
    set_error(error, std::string("not a ") + type + " (the type fingerprint differs)");
    return false;
  }
  int used = -1;
  try {
    used = msg.decode(data, 0, size);
  } catch (const std::exception&) {
    used = -1;
  }
  if (used < 0) {
    set_error(error, std::string("malformed ") + type + ": the bytes end early or a length is invalid");
    return false;
  }
  if (used != size) {
    set_error(error, std::string(type) + " has " + std::to_string(size - used) + " trailing bytes");
    return false;
  }
  return true;
}

inline bool valid_status(int s) { return s >= 0 && s <= static_cast<int>(hal::HalStatus::kMalformed); }

inline bool bad_field(std::string* error, const char* type, const char* field, long long value) {
  set_error(error, std::string(type) + ": impossible " + field + " " + std::to_string(value));
  return false;
}

}  // namespace rtfuse::transport::decoding
