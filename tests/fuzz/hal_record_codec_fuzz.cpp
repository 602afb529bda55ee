// Each record of a HAL recording on its own, as the codec decodes it: the
// first byte picks the record type (recording_info_t, recording_file_t,
// recording_end_t, loop_tick_t, the bus events of each device kind,
// hal_video_t, hal_serial_t), the rest is the message. Property: a record is refused with
// a message, or it is canonical: encoding what was decoded gives bytes that
// decode again and encode to the same bytes.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_check.hpp"
#include "transport/hal_record_codec.hpp"

using namespace rtfuse::transport;

namespace {

std::vector<RecordedDevice> device_table() {
  return {{"can0", DeviceKind::kCan, 0},       {"i2c-1", DeviceKind::kI2c, 1},
          {"imu-drdy", DeviceKind::kGpioEdge, 1}, {"led", DeviceKind::kGpioOutput, 0},
          {"loop-clock", DeviceKind::kClock, 0},  {"camera", DeviceKind::kVideo, 2},
          {"gnss0", DeviceKind::kSerial, 0}};
}

template <class Decode, class Encode>
void check_round_trip(const std::uint8_t* data, int size, Decode decode, Encode encode) {
  std::string error;
  std::vector<std::uint8_t> first;
  if (!decode(data, size, &first, &error)) {
    FUZZ_CHECK(!error.empty(), "a refused record says why");
    return;
  }
  FUZZ_CHECK(encode(&first), "what was decoded can be encoded");
  std::vector<std::uint8_t> second;
  FUZZ_CHECK(decode(first.data(), static_cast<int>(first.size()), &second, &error), error.c_str());
  FUZZ_CHECK(encode(&second), "what was decoded can be encoded");
  FUZZ_CHECK(first == second, "canonical: one more round trip changes no byte");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static HalRecordCodec codec(device_table());
  static std::vector<std::uint8_t> buf(1 << 21);
  const std::uint8_t which = data[0] % 11;
  const std::uint8_t* msg = data + 1;
  const int n = static_cast<int>(size - 1);
  const int cap = static_cast<int>(buf.size());

  // Each case decodes into an object kept between the decode and the
  // encode: the lambdas hand encoded bytes back through *bytes.
  switch (which) {
    case 0: {
      RecordingInfo info;
      check_round_trip(
          msg, n,
          [&](const std::uint8_t* d, int s, std::vector<std::uint8_t>* bytes, std::string* e) {
            if (!decode_recording_info(d, s, &info, e)) return false;
            *bytes = encode_recording_info(info);
            return true;
          },
          [&](std::vector<std::uint8_t>* bytes) { return !bytes->empty(); });
      break;
    }
    case 1: {
      RecordedFile file;
      check_round_trip(
          msg, n,
          [&](const std::uint8_t* d, int s, std::vector<std::uint8_t>* bytes, std::string* e) {
            if (!decode_recorded_file(d, s, &file, e)) return false;
            *bytes = encode_recorded_file(file);
            return true;
          },
          [&](std::vector<std::uint8_t>* bytes) { return !bytes->empty(); });
      break;
    }
    case 2: {
      RecordingEnd end;
      check_round_trip(
          msg, n,
          [&](const std::uint8_t* d, int s, std::vector<std::uint8_t>* bytes, std::string* e) {
            if (!decode_recording_end(d, s, &end, e)) return false;
            *bytes = encode_recording_end(end);
            return true;
          },
          [&](std::vector<std::uint8_t>* bytes) { return !bytes->empty(); });
      break;
    }
    case 3: {
      check_round_trip(
          msg, n,
          [&](const std::uint8_t* d, int s, std::vector<std::uint8_t>* bytes, std::string* e) {
            LoopTick tick;
            if (!HalRecordCodec::decode_tick(d, s, &tick, e)) return false;
            const int w = codec.encode_tick(tick.time_ns, tick.seq, tick.consumed.data(),
                                            static_cast<int>(tick.consumed.size()), tick.published, buf.data(), cap);
            bytes->assign(buf.data(), buf.data() + (w > 0 ? w : 0));
            return true;
          },
          [&](std::vector<std::uint8_t>* bytes) { return !bytes->empty(); });
      break;
    }
    case 9: {
      const std::string channel(codec.channel(5));
      check_round_trip(
          msg, n,
          [&](const std::uint8_t* d, int s, std::vector<std::uint8_t>* bytes, std::string* e) {
            rtfuse::hal::VideoEvent ev;
            const std::uint8_t* frame = nullptr;
            if (!codec.decode_video(channel, d, s, &ev, &frame, e)) return false;
            FUZZ_CHECK(ev.device == 5, "the event names the channel's device");
            if (ev.data_size > 0) FUZZ_CHECK(frame != nullptr, "frame bytes when data_size says so");
            std::vector<std::uint8_t> copy(frame ? frame : d, frame ? frame + ev.data_size : d);
            const int w = codec.encode_video(ev, copy.data(), buf.data(), cap);
            bytes->assign(buf.data(), buf.data() + (w > 0 ? w : 0));
            return true;
          },
          [&](std::vector<std::uint8_t>* bytes) { return !bytes->empty(); });
      break;
    }
    default: {  // 4..8 and 10: the bus devices (0..4, and the serial port 6)
      const std::uint8_t device = static_cast<std::uint8_t>(which == 10 ? 6 : which - 4);
      const std::string channel(codec.channel(device));
      check_round_trip(
          msg, n,
          [&](const std::uint8_t* d, int s, std::vector<std::uint8_t>* bytes, std::string* e) {
            rtfuse::hal::BusEvent ev;
            if (!codec.decode(channel, d, s, &ev, e)) return false;
            FUZZ_CHECK(ev.device == device, "the event names the channel's device");
            const int w = codec.encode(ev, buf.data(), cap);
            bytes->assign(buf.data(), buf.data() + (w > 0 ? w : 0));
            return true;
          },
          [&](std::vector<std::uint8_t>* bytes) { return !bytes->empty(); });
      break;
    }
  }
  return 0;
}
