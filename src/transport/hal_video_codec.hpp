#pragma once
// hal_video_t: one call a driver made on a recorded camera (hal::VideoEvent)
// and, for a dequeue that returned a frame, the frame's bytes. The device
// table and the channels (rtfuse/hal/<camera>) are HalRecordCodec's, which
// hands a video device's records to this codec. Its message object
// persists, so encoding allocates only until the largest frame was seen once.
#include <cstdint>
#include <memory>
#include <string>

#include "hal/video_event.hpp"

namespace rtfuse {
class hal_video_t;  // lcm-gen's type stays out of this header
}

namespace rtfuse::transport {

// A hal_video_t is its frame bytes plus at most this much (fields and a
// 48-character device name): size the encode buffer slot_bytes + this.
constexpr int kVideoRecordOverhead = 256;

class HalVideoCodec {
 public:
  HalVideoCodec();
  ~HalVideoCodec();
  HalVideoCodec(const HalVideoCodec&) = delete;
  HalVideoCodec& operator=(const HalVideoCodec&) = delete;

  // ev, a call on the camera named `device`, and, when ev.has_frame(), its
  // ev.data_size bytes at data. Bytes written or -1 (no camera call, frame
  // bytes missing, capacity too small: data_size + kVideoRecordOverhead fits).
  int encode(const std::string& device, const hal::VideoEvent& ev, const std::uint8_t* data, std::uint8_t* buf,
             int capacity);
  // The hal_video_t of the camera `name` (table index `device`, out->device)
  // into *out; *frame points at its out->data_size frame bytes (inside this
  // codec, valid until the next decode; null without a frame). False with a
  // reason on a wrong type, a bad or truncated length, another device's
  // name, or an impossible value.
  bool decode(std::uint8_t device, const std::string& name, const void* data, int size, hal::VideoEvent* out,
              const std::uint8_t** frame, std::string* error);

 private:
  std::unique_ptr<rtfuse::hal_video_t> msg_;
};

}  // namespace rtfuse::transport
