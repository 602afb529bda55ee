#pragma once
// Sample HAL records shared by the codec tests (tests/unit/transport) and the
// loader tests (tests/unit/runtime): a device table of every bus kind with
// one canonical event of each, a camera's device table and frame, a file
// the configuration names.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "hal/bus_event.hpp"
#include "hal/video_event.hpp"
#include "transport/hal_record_codec.hpp"

namespace rtfuse::test {

using hal::BusEvent;
using hal::BusEventKind;
using hal::CanBusState;
using hal::HalStatus;
using hal::VideoCallKind;
using hal::VideoEvent;
using transport::DeviceKind;
using transport::RecordedFile;
using transport::RecordingInfo;

// Two streams (loop, imu) and a device of every bus kind.
inline RecordingInfo sample_info() {
  RecordingInfo info;
  info.start_ns = 5'000'000'000;
  info.rtfuse_version = "0.1.0";
  info.config_path = "config/robot.toml";
  info.config_text = "[loop]\nrate_hz = 200\n";
  info.config_hash = transport::config_text_hash(info.config_text);
  info.streams = {"loop", "imu"};
  info.devices = {{"can0", DeviceKind::kCan, 0},
                  {"i2c-1", DeviceKind::kI2c, 1},
                  {"imu-drdy", DeviceKind::kGpioEdge, 1},
                  {"led", DeviceKind::kGpioOutput, 0},
                  {"imu-clock", DeviceKind::kClock, 1},
                  {"gnss0", DeviceKind::kSerial, 0}};
  return info;
}

// One canonical event of every kind of sample_info(), with values that
// exercise the ranges.
inline std::vector<BusEvent> every_kind() {
  std::vector<BusEvent> evs;
  BusEvent send;
  send.kind = BusEventKind::kCanSend;
  send.device = 0;
  send.time_ns = 1'234'567'891;
  send.status = HalStatus::kBusError;
  send.bus_state = CanBusState::kErrorPassive;
  send.count = 1;
  send.frames[0].id = 0x1ABCDEF0;
  send.frames[0].extended = true;
  send.frames[0].dlc = 8;
  for (int i = 0; i < 8; ++i) send.frames[0].data[i] = static_cast<std::uint8_t>(0xF0 + i);
  send.lost_before = 0xFFFFFFFFu;  // survives the int32 field
  evs.push_back(send);

  BusEvent rx;
  rx.kind = BusEventKind::kCanReceive;
  rx.device = 0;
  rx.time_ns = 2'000'000'000;
  rx.timeout_ns = 5'000'000;
  rx.length = 16;
  rx.count = 16;
  rx.bus_state = CanBusState::kBusOff;
  for (int i = 0; i < 16; ++i) {
    rx.frames[i].id = 0x181 + static_cast<std::uint32_t>(i);
    rx.frames[i].dlc = static_cast<std::uint8_t>(i % 9);
    rx.frames[i].rtr = i == 3;
    rx.frames[i].error = i == 4;
    rx.frames[i].stamp = 1'999'000'000 + i;
    for (int b = 0; b < 8; ++b) rx.frames[i].data[b] = static_cast<std::uint8_t>(i * 8 + b);
  }
  evs.push_back(rx);

  BusEvent rd;
  rd.kind = BusEventKind::kI2cRead;
  rd.device = 1;
  rd.time_ns = -5;  // time before the epoch of the clock still round-trips
  rd.address = 0x68;
  rd.reg = 0xFF;
  rd.length = 64;
  rd.retries = 123'456'789'012;
  for (int i = 0; i < 64; ++i) rd.data[i] = static_cast<std::uint8_t>(255 - i);
  evs.push_back(rd);

  BusEvent nack = rd;
  nack.status = HalStatus::kNack;
  for (auto& b : nack.data) b = 0;
  nack.length = 14;
  evs.push_back(nack);

  BusEvent wr;
  wr.kind = BusEventKind::kI2cWrite;
  wr.device = 1;
  wr.address = 0x77;
  wr.reg = 0x6B;
  wr.length = 1;
  wr.value = 0x80;
  evs.push_back(wr);

  BusEvent edge;
  edge.kind = BusEventKind::kGpioWaitEdge;
  edge.device = 2;
  edge.timeout_ns = 10'000'000;
  edge.edge_stamp = 3'000'000'001;
  edge.level = 1;
  evs.push_back(edge);

  BusEvent timeout = edge;
  timeout.status = HalStatus::kTimeout;
  timeout.edge_stamp = 0;
  timeout.level = 0;
  evs.push_back(timeout);

  BusEvent set;
  set.kind = BusEventKind::kGpioSet;
  set.device = 3;
  set.level = 1;
  set.status = HalStatus::kIoError;
  evs.push_back(set);

  BusEvent now;
  now.kind = BusEventKind::kClockNow;
  now.device = 4;
  now.time_ns = 4'000'000'123;
  now.clock_ns = 4'000'000'123;
  evs.push_back(now);

  BusEvent sleep;
  sleep.kind = BusEventKind::kClockSleepUntil;
  sleep.device = 4;
  sleep.time_ns = 4'000'000'200;
  sleep.clock_ns = 4'005'000'000;
  evs.push_back(sleep);

  BusEvent read;
  read.kind = BusEventKind::kSerialRead;
  read.device = 5;
  read.time_ns = 5'000'000'000;
  read.timeout_ns = 50'000'000;
  read.length = 64;
  read.count = 64;
  read.edge_stamp = 4'999'999'000;
  for (int i = 0; i < 64; ++i) read.data[i] = static_cast<std::uint8_t>(0xB5 + i);
  evs.push_back(read);

  BusEvent quiet;
  quiet.kind = BusEventKind::kSerialRead;
  quiet.device = 5;
  quiet.timeout_ns = 50'000'000;
  quiet.length = 64;
  quiet.status = HalStatus::kTimeout;
  evs.push_back(quiet);

  BusEvent command;
  command.kind = BusEventKind::kSerialWrite;
  command.device = 5;
  command.length = 3;
  command.data[0] = 0xB5;
  command.data[1] = 0x62;
  command.data[2] = 0x06;
  evs.push_back(command);

  BusEvent reopen;
  reopen.kind = BusEventKind::kSerialReopen;
  reopen.device = 5;
  reopen.time_ns = 6'000'000'000;
  reopen.status = HalStatus::kClosed;
  evs.push_back(reopen);
  return evs;
}

// A CAN bus on the loop stream and a camera on a stream of its own.
inline RecordingInfo camera_info() {
  RecordingInfo info;
  info.streams = {"loop", "camera"};
  info.devices = {{"can0", DeviceKind::kCan, 0}, {"cam0", DeviceKind::kVideo, 1}};
  return info;
}

// A camera frame of n bytes on camera_info()'s camera.
inline VideoEvent dequeue_event(std::uint32_t n) {
  VideoEvent ev;
  ev.kind = VideoCallKind::kDequeue;
  ev.device = 1;
  ev.time_ns = 5'000'000'123;
  ev.timeout_ns = 100'000'000;
  ev.stamp = 4'999'000'000;
  ev.frames_before = 7;
  ev.sequence = 4'000'000'000u;  // above INT32_MAX: kept unsigned
  ev.bytes_used = n;
  ev.length = n + 16;
  ev.data_size = n;
  ev.index = 2;
  ev.corrupted = 1;
  ev.set_format(hal::VideoFormat{hal::kFourccYuyv, 1344, 376, 2688, 1344u * 376 * 2, 30, 1, 4});
  return ev;
}

inline std::vector<std::uint8_t> pattern(std::size_t n) {
  std::vector<std::uint8_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(i * 131 + (i >> 8));
  return v;
}

inline RecordedFile calibration_file() {
  // A NUL and a byte above 127 among the text; the length from the array
  // itself (a hand-counted 36 read past its 30 bytes: found by ASan).
  static constexpr char kText[] = "[LEFT_CAM_VGA]\nfx=350\n\0binary\xff";
  return {"camera.calibration", "/etc/rtfuse/calibration/SN10000001.conf", std::string(kText, sizeof kText - 1)};
}

}  // namespace rtfuse::test
