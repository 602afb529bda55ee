// make_seeds DIR: writes seed inputs for the harnesses that read rtfuse's
// own binary formats, made with the project's encoders so the fuzzer starts
// from structure it would take long to guess:
//   DIR/hal_recording, DIR/event_log   a small HAL recording of every device
//                                      kind (bus calls, a camera frame,
//                                      ticks, an output, the end record);
//   DIR/hal_record_codec               each of its records, with the
//                                      harness's selector byte;
//   DIR/sample_decoder                 one LCM input message of each type.
// The text formats (configs, calibration files, KITTI files) are seeded from
// real files by tools/fuzz.sh. The recording must load: a seed that the
// loader refuses would teach the fuzzer nothing about the paths after it.
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "rtfuse/imu_t.hpp"
#include "rtfuse/navsat_fix_t.hpp"
#include "rtfuse/nav_stop_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "rtfuse/pose_stamped_t.hpp"
#include "rtfuse/pose_with_covariance_stamped_t.hpp"
#include "rtfuse/twist_with_covariance_stamped_t.hpp"
#include "runtime/replay/hal_recording.hpp"
#include "transport/event_log.hpp"
#include "transport/hal_record_codec.hpp"

using namespace rtfuse;
using namespace rtfuse::transport;

namespace {

void write_file(const std::string& path, const std::vector<std::uint8_t>& bytes, std::uint8_t prefix = 0,
                bool with_prefix = false) {
  std::ofstream out(path, std::ios::binary);
  if (with_prefix) out.put(static_cast<char>(prefix));
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) {
    std::fprintf(stderr, "make_seeds: cannot write %s\n", path.c_str());
    std::exit(1);
  }
}

template <class Msg>
std::vector<std::uint8_t> encode(const Msg& m) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

void fill_covariance(double* c, int n, double v) {
  for (int i = 0; i < n; ++i) c[i * n + i] = v;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_seeds DIR (its subfolders must exist)\n");
    return 2;
  }
  const std::string dir = argv[1];

  // --- the LCM inputs ---------------------------------------------------
  rtfuse::odometry_t odom{};
  odom.header.utime = 1'700'000'000'000'000;
  odom.header.frame_id = "odom";
  odom.child_frame_id = "base_link";
  odom.pose.pose.orientation.w = 1.0;
  odom.twist.twist.linear.x = 0.5;
  fill_covariance(odom.pose.covariance, 6, 0.01);
  fill_covariance(odom.twist.covariance, 6, 0.01);
  rtfuse::imu_t imu{};
  imu.header.utime = 1'700'000'000'000'000;
  imu.header.frame_id = "imu_link";
  imu.orientation.w = 1.0;
  imu.linear_acceleration.z = 9.81;
  fill_covariance(imu.orientation_covariance, 3, 0.001);
  fill_covariance(imu.angular_velocity_covariance, 3, 0.001);
  fill_covariance(imu.linear_acceleration_covariance, 3, 0.01);
  rtfuse::pose_with_covariance_stamped_t pose{};
  pose.header = odom.header;
  pose.header.frame_id = "map";
  pose.pose.pose.orientation.w = 1.0;
  fill_covariance(pose.pose.covariance, 6, 0.1);
  rtfuse::twist_with_covariance_stamped_t twist{};
  twist.header = odom.header;
  twist.header.frame_id = "base_link";
  twist.twist.twist.angular.z = 0.1;
  fill_covariance(twist.twist.covariance, 6, 0.01);
  rtfuse::navsat_fix_t fix{};
  fix.header = odom.header;
  fix.header.frame_id = "gps";
  fix.status = rtfuse::navsat_fix_t::STATUS_FIX;
  fix.latitude = 47.3977;
  fix.longitude = 8.5456;
  fix.altitude = 488.0;
  fill_covariance(fix.position_covariance, 3, 1.0);
  fix.position_covariance_type = rtfuse::navsat_fix_t::COVARIANCE_TYPE_DIAGONAL_KNOWN;
  // The harness's selector: 0 odometry, 1 pose, 2 twist, 3 imu, 4 set_pose,
  // 5 navsat fix.
  write_file(dir + "/sample_decoder/odometry", encode(odom), 0, true);
  write_file(dir + "/sample_decoder/pose", encode(pose), 1, true);
  write_file(dir + "/sample_decoder/twist", encode(twist), 2, true);
  write_file(dir + "/sample_decoder/imu", encode(imu), 3, true);
  write_file(dir + "/sample_decoder/set_pose", encode(pose), 4, true);
  write_file(dir + "/sample_decoder/navsat_fix", encode(fix), 5, true);
  // In the world frame of config/sim.toml, so daemon_input_fuzz (which
  // shares these seeds) starts with a set_pose the filter applies.
  pose.header.frame_id = "odom";
  write_file(dir + "/sample_decoder/set_pose_odom", encode(pose), 4, true);
  // The navigator's inputs, daemon_input_fuzz's selectors 6 and 7: a goal
  // 2 m ahead in the map's frame, a stop and its release.
  rtfuse::pose_stamped_t goal{};
  goal.header = odom.header;
  goal.pose.position.x = 2.0;
  goal.pose.orientation.w = 1.0;
  write_file(dir + "/daemon_input/goal", encode(goal), 6, true);
  rtfuse::nav_stop_t stop{};
  stop.header = odom.header;
  stop.header.frame_id = "base_link";
  stop.stop = true;
  stop.reason = "operator";
  write_file(dir + "/daemon_input/stop", encode(stop), 7, true);
  stop.stop = false;
  write_file(dir + "/daemon_input/release", encode(stop), 7, true);

  // --- a HAL recording ---------------------------------------------------
  // The device table of hal_record_codec_fuzz.cpp, so each record seeds it too.
  RecordingInfo info;
  info.start_ns = 1'000'000'000;
  info.rtfuse_version = "0.1.0";
  info.config_path = "/etc/rtfuse/rtfused.toml";
  info.config_text = "[loop]\nrate_hz = 200\n";
  info.config_hash = config_text_hash(info.config_text);
  info.streams = {"loop", "imu", "camera"};
  info.devices = {{"can0", DeviceKind::kCan, 0},       {"i2c-1", DeviceKind::kI2c, 1},
                  {"imu-drdy", DeviceKind::kGpioEdge, 1}, {"led", DeviceKind::kGpioOutput, 0},
                  {"loop-clock", DeviceKind::kClock, 0},  {"camera", DeviceKind::kVideo, 2},
                  {"gnss0", DeviceKind::kSerial, 0}};
  info.files = {{"camera.calibration", "/etc/rtfuse/SN1.conf", "[STEREO]\nBaseline=120\n"}};
  HalRecordCodec codec(info.devices);

  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> events;  // channel, bytes
  std::vector<std::pair<std::uint8_t, std::vector<std::uint8_t>>> records;  // selector, bytes
  auto add = [&](std::string_view channel, std::vector<std::uint8_t> bytes, std::uint8_t selector) {
    records.emplace_back(selector, bytes);
    events.emplace_back(std::string(channel), std::move(bytes));
  };
  add(kRecordingInfoChannel, encode_recording_info(info), 0);
  add(kRecordedFileChannel, encode_recorded_file(info.files[0]), 1);

  std::vector<std::uint8_t> buf(4096);
  auto bus_event = [&](const hal::BusEvent& ev) {
    const int n = codec.encode(ev, buf.data(), static_cast<int>(buf.size()));
    if (n < 0) {
      std::fprintf(stderr, "make_seeds: the codec refused a %s event\n", hal::to_string(ev.kind));
      std::exit(1);
    }
    add(codec.channel(ev.device), std::vector<std::uint8_t>(buf.begin(), buf.begin() + n),
        static_cast<std::uint8_t>(ev.device == 6 ? 10 : 4 + ev.device));
  };
  TimeNs t = info.start_ns;
  hal::BusEvent ev{};
  ev.kind = hal::BusEventKind::kClockNow, ev.device = 4, ev.time_ns = t, ev.clock_ns = t;
  bus_event(ev);
  ev = {};
  ev.kind = hal::BusEventKind::kCanSend, ev.device = 0, ev.time_ns = t, ev.count = 1;
  ev.bus_state = hal::CanBusState::kErrorActive;
  ev.frames[0].id = 0x080;
  bus_event(ev);
  ev = {};
  ev.kind = hal::BusEventKind::kCanReceive, ev.device = 0, ev.time_ns = t + 1000, ev.length = 16, ev.count = 2;
  ev.bus_state = hal::CanBusState::kErrorActive;
  ev.frames[0].id = 0x181, ev.frames[0].dlc = 4, ev.frames[0].data[0] = 0x10, ev.frames[0].stamp = t + 500;
  ev.frames[1].id = 0x701, ev.frames[1].dlc = 1, ev.frames[1].data[0] = 0x05, ev.frames[1].stamp = t + 600;
  bus_event(ev);
  ev = {};
  ev.kind = hal::BusEventKind::kGpioWaitEdge, ev.device = 2, ev.time_ns = t, ev.timeout_ns = 20'000'000;
  ev.edge_stamp = t + 2000, ev.level = 1;
  bus_event(ev);
  ev = {};
  ev.kind = hal::BusEventKind::kI2cRead, ev.device = 1, ev.time_ns = t + 3000, ev.address = 0x68, ev.reg = 0x3B;
  ev.length = 14;
  for (int i = 0; i < 14; ++i) ev.data[i] = static_cast<std::uint8_t>(i * 17);
  bus_event(ev);
  ev = {};
  ev.kind = hal::BusEventKind::kI2cWrite, ev.device = 1, ev.time_ns = t + 4000, ev.address = 0x68, ev.reg = 0x6B;
  ev.length = 1, ev.value = 0x01;
  bus_event(ev);
  ev = {};
  ev.kind = hal::BusEventKind::kGpioSet, ev.device = 3, ev.time_ns = t + 5000, ev.level = 1;
  bus_event(ev);
  ev = {};
  ev.kind = hal::BusEventKind::kClockSleepUntil, ev.device = 4, ev.time_ns = t + 6000, ev.clock_ns = t + 5'000'000;
  bus_event(ev);
  // A GNSS receiver's UART: a read with the start of a UBX frame, a quiet
  // read, and a command written.
  ev = {};
  ev.kind = hal::BusEventKind::kSerialRead, ev.device = 6, ev.time_ns = t + 6500, ev.timeout_ns = 50'000'000;
  ev.length = 64, ev.count = 6, ev.edge_stamp = t + 6400;
  ev.data[0] = 0xB5, ev.data[1] = 0x62, ev.data[2] = 0x01, ev.data[3] = 0x07, ev.data[4] = 92, ev.data[5] = 0;
  bus_event(ev);
  ev = {};
  ev.kind = hal::BusEventKind::kSerialRead, ev.device = 6, ev.time_ns = t + 6600, ev.timeout_ns = 50'000'000;
  ev.length = 64, ev.status = hal::HalStatus::kTimeout;
  bus_event(ev);
  ev = {};
  ev.kind = hal::BusEventKind::kSerialWrite, ev.device = 6, ev.time_ns = t + 6700, ev.length = 2;
  ev.data[0] = 0xB5, ev.data[1] = 0x62;
  bus_event(ev);

  // A camera: start, one 4x2 grey frame dequeued and released.
  hal::VideoEvent ve{};
  ve.device = 5, ve.kind = hal::VideoCallKind::kStart, ve.time_ns = t;
  ve.pixel_format = 0x59455247;  // 'GREY'
  ve.width = 4, ve.height = 2, ve.bytes_per_line = 4, ve.image_size = 8, ve.buffers = 2;
  ve.fps_numerator = 1, ve.fps_denominator = 30;
  const std::uint8_t frame[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  auto video = [&](const hal::VideoEvent& e) {
    const int n = codec.encode_video(e, frame, buf.data(), static_cast<int>(buf.size()));
    if (n < 0) {
      std::fprintf(stderr, "make_seeds: the codec refused a video event\n");
      std::exit(1);
    }
    add(codec.channel(5), std::vector<std::uint8_t>(buf.begin(), buf.begin() + n), 9);
  };
  video(ve);
  hal::VideoEvent dq = ve;
  dq.kind = hal::VideoCallKind::kDequeue, dq.time_ns = t + 7000, dq.timeout_ns = 0, dq.stamp = t + 6500;
  dq.sequence = 0, dq.bytes_used = 8, dq.length = 8, dq.data_size = 8, dq.index = 0;
  video(dq);
  hal::VideoEvent rel = ve;
  rel.kind = hal::VideoCallKind::kRelease, rel.time_ns = t + 8000, rel.index = 0, rel.frames_before = 1;
  video(rel);

  const std::int64_t consumed[2] = {1, 3};
  for (int k = 1; k <= 2; ++k) {
    const int n = codec.encode_tick(t + k * 5'000'000, k, consumed, 2, 1, buf.data(), static_cast<int>(buf.size()));
    add(kLoopTickChannel, std::vector<std::uint8_t>(buf.begin(), buf.begin() + n), 3);
  }
  events.emplace_back("rtfuse/odom", encode(odom));
  RecordingEnd end;
  end.end_ns = t + 10'000'000;
  end.events = static_cast<std::int64_t>(events.size());
  add(kRecordingEndChannel, encode_recording_end(end), 2);

  const std::string log = dir + "/hal_recording.lcmlog";
  EventLogWriter writer;
  std::string error;
  bool ok = writer.open(log, &error);
  for (const auto& [channel, bytes] : events)
    ok = ok && writer.write(1'000'000, channel, bytes.data(), bytes.size(), &error);
  ok = ok && writer.close(&error);
  if (!ok) {
    std::fprintf(stderr, "make_seeds: %s\n", error.c_str());
    return 1;
  }
  EventLogReader reader;
  HalRecording rec;
  if (!reader.open(log, &error) || !load_hal_recording(reader, {}, &rec, &error)) {
    std::fprintf(stderr, "make_seeds: the seed recording does not load: %s\n", error.c_str());
    return 1;
  }
  std::ifstream in(log, std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::remove(log.c_str());
  write_file(dir + "/event_log/recording", bytes);
  write_file(dir + "/hal_recording/recording", bytes, 0, true);
  write_file(dir + "/hal_recording/recording_truncated_allowed",
             std::vector<std::uint8_t>(bytes.begin(), bytes.end() - 20), 1, true);
  for (std::size_t i = 0; i < records.size(); ++i)
    write_file(dir + "/hal_record_codec/record" + std::to_string(i), records[i].second, records[i].first, true);
  std::printf("make_seeds: %zu events, %zu records, %zu bytes of recording\n", events.size(), records.size(),
              bytes.size());
  return 0;
}
