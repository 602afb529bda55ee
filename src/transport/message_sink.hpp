#pragma once
// Where encoded messages go: lcm_publish from the caller's buffer in the
// daemon, a comparison in a replay, a capture in tests. Below the runtime so
// that a device's own outputs (a camera's preview) and the publisher's reach
// the same sink.
#include <cstdint>

#include "core/time.hpp"

namespace rtfuse::transport {

class MessageSink {
 public:
  virtual ~MessageSink() = default;
  // The bytes are valid only during the call. False: the message was lost.
  virtual bool publish(const char* channel, const std::uint8_t* data, int size, TimeNs now) = 0;
};

}  // namespace rtfuse::transport
