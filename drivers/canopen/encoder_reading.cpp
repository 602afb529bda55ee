#include "drivers/canopen/encoder_reading.hpp"

namespace rtfuse::drivers {

const char* to_string(EncoderHealth health) noexcept {
  switch (health) {
    case EncoderHealth::kOk: return "ok";
    case EncoderHealth::kBusOff: return "bus-off";
    case EncoderHealth::kSilent: return "silent";
    case EncoderHealth::kNotStarted: return "not started";
    case EncoderHealth::kNoSample: return "no sample";
    case EncoderHealth::kEmcy: return "emcy";
    case EncoderHealth::kStuck: return "stuck";
    case EncoderHealth::kJump: return "jump";
  }
  return "?";
}

}  // namespace rtfuse::drivers
