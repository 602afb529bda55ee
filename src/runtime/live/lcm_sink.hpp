#pragma once
// Publisher output straight onto LCM (lcm_publish from the caller's buffer).
#include "runtime/pipeline/publisher.hpp"
#include "transport/lcm_node.hpp"

namespace rtfuse {

class LcmSink final : public MessageSink {
 public:
  explicit LcmSink(transport::LcmNode& lcm) : lcm_(lcm) {}
  bool publish(const char* channel, const std::uint8_t* data, int size, TimeNs) override {
    return lcm_.publish(channel, data, size);
  }

 private:
  transport::LcmNode& lcm_;
};

}  // namespace rtfuse
