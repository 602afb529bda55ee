#include "runtime/devices/device_layout.hpp"

#include <cstdio>

namespace rtfuse {

const char* const kCanBusKeys[] = {"frames_received", "syncs_sent",   "send_failures", "malformed_frames",
                                   "unexpected_cob_ids", "error_frames", "bus_off_events"};
const int kCanBusKeyCount = sizeof(kCanBusKeys) / sizeof(kCanBusKeys[0]);

const char* const kEncoderNodeKeys[] = {"counts",        "tpdos",        "heartbeats",  "emcy",
                                        "last_emcy_code", "silent_events", "stuck_events", "jump_events",
                                        "recoveries",    "nmt_starts"};
const int kEncoderNodeKeyCount = sizeof(kEncoderNodeKeys) / sizeof(kEncoderNodeKeys[0]);

const char* const kWheelOdometryKeys[] = {"twists", "no_side", "reseeds"};
const int kWheelOdometryKeyCount = sizeof(kWheelOdometryKeys) / sizeof(kWheelOdometryKeys[0]);

const char* const kImuKeys[] = {"samples",   "reads",     "nacks",         "bus_errors",         "timeouts",
                                "frozen",    "saturated", "impossible",    "missing_edges",      "out_of_order_edges",
                                "reinits",   "filter_rejects", "temperature_mdegc"};
const int kImuKeyCount = sizeof(kImuKeys) / sizeof(kImuKeys[0]);

// fps_milli: the rate measured from the capture stamps, in 1/1000 fps.
// pairs_digest: StereoCameraStats::pairs_digest's bits as an int64.
const char* const kCameraKeys[] = {"frames",    "fps_milli",       "dropped", "sequence_gaps",
                                   "rejected_size", "rejected_corrupted", "pool_full", "timeouts",
                                   "lost",      "reopen_attempts", "reopens", "errors",
                                   "pairs_digest"};
const int kCameraKeyCount = sizeof(kCameraKeys) / sizeof(kCameraKeys[0]);
// fps_milli: measurements per second from the capture stamps, x1000;
// residual_milli_px: the last motion's inlier RMS, 1/1000 px; time_us: the
// last pair's processing time on the camera thread, and the most so far;
// latency_us: the last twist's age when pushed (capture to ring).
const char* const kVoKeys[] = {"pairs",      "motions",      "fps_milli",   "skipped",         "too_few_matches",
                               "no_consensus", "implausible", "restarts",    "matches",         "inliers",
                               "residual_milli_px", "time_us", "max_time_us", "latency_us"};
const int kVoKeyCount = sizeof(kVoKeys) / sizeof(kVoKeys[0]);
static_assert(sizeof(kVoKeys) / sizeof(kVoKeys[0]) <= kMaxDeviceValues, "more VO keys than a device holds");
// The receiver's epochs and faults (drivers::GnssReceiverStats); hdop_milli
// the last epoch's HDOP x1000 (-1 unknown).
const char* const kGnssKeys[] = {"epochs",      "fixes",      "no_fix",        "two_d",      "dead_reckoning",
                                 "time_jumps",  "refused",    "lost_epochs",   "bytes",      "read_errors",
                                 "silent_events", "reopens",  "satellites",    "hdop_milli"};
const int kGnssKeyCount = sizeof(kGnssKeys) / sizeof(kGnssKeys[0]);
static_assert(sizeof(kGnssKeys) / sizeof(kGnssKeys[0]) <= kMaxDeviceValues, "more GNSS keys than a device holds");
// The navsat transform's refusals by reason (est::NavsatStats).
const char* const kNavsatKeys[] = {"accepted", "no_fix",        "invalid_position", "invalid_covariance",
                                   "waiting_for_heading", "jumps", "reanchors"};
const int kNavsatKeyCount = sizeof(kNavsatKeys) / sizeof(kNavsatKeys[0]);
// Every slot a configuration can ask for: CAN bus and nodes, wheel
// odometry, IMU, camera, VO, a GNSS receiver, the navsat transforms.
static_assert(1 + kMaxWheelNodes + 4 + 1 + kMaxNavsatSensors <= kMaxDevices, "kMaxDevices is too small");
static_assert(sizeof(kCameraKeys) / sizeof(kCameraKeys[0]) <= kMaxDeviceValues, "more camera keys than a device holds");
static_assert(sizeof(kImuKeys) / sizeof(kImuKeys[0]) <= kMaxDeviceValues, "more IMU keys than a device holds");
static_assert(sizeof(kEncoderNodeKeys) / sizeof(kEncoderNodeKeys[0]) <= kMaxDeviceValues,
              "more encoder node keys than a device holds");
static_assert(sizeof(kCanBusKeys) / sizeof(kCanBusKeys[0]) <= kMaxDeviceValues, "more CAN bus keys than a device holds");

DeviceSlots device_slots(const RuntimeConfig& cfg) noexcept {
  DeviceSlots s;
  const HardwareConfig& hw = cfg.hardware;
  if (hw.can.enabled) {
    s.can_bus = s.count++;
    s.first_node = s.count;
    s.count += hw.can.num_nodes;
  }
  if (hw.wheel_sensor >= 0) s.wheel_odometry = s.count++;
  if (hw.mpu.enabled) s.imu = s.count++;
  if (hw.camera.enabled) s.camera = s.count++;
  if (hw.camera.enabled && hw.vo.enabled && hw.vo_sensor >= 0) s.vo = s.count++;
  if (hw.gnss.enabled) s.gnss = s.count++;
  for (int i = 0; i < cfg.num_sensors; ++i) {
    if (cfg.sensors[static_cast<std::size_t>(i)].params.kind != est::SensorKind::kNavSatFix) continue;
    if (s.num_navsat == kMaxNavsatSensors) break;  // the loader refuses more
    if (s.first_navsat < 0) s.first_navsat = s.count;
    ++s.num_navsat;
    ++s.count;
  }
  return s;
}

namespace {

void keys(DeviceStatus& d, const char* const* k, int n) noexcept {
  d.num_values = 0;
  for (int i = 0; i < n; ++i) d.add(k[i], 0);
}

}  // namespace

int describe_devices(const RuntimeConfig& cfg, DeviceStatus* out, int max) noexcept {
  const DeviceSlots slots = device_slots(cfg);
  if (slots.count > max) return 0;
  const HardwareConfig& hw = cfg.hardware;
  char buf[160];
  for (int i = 0; i < slots.count; ++i) out[i] = DeviceStatus{};
  if (slots.can_bus >= 0) {
    DeviceStatus& d = out[slots.can_bus];
    d.name = "can bus";
    d.hardware_id = hw.can.interface.c_str();
    keys(d, kCanBusKeys, kCanBusKeyCount);
    for (int n = 0; n < hw.can.num_nodes; ++n) {
      const CanNodeSection& node = hw.can.nodes[static_cast<std::size_t>(n)];
      DeviceStatus& e = out[slots.first_node + n];
      std::snprintf(buf, sizeof buf, "wheel %s node %d", node.side == WheelSideConfig::kLeft ? "left" : "right",
                    node.node_id);
      e.name = buf;
      std::snprintf(buf, sizeof buf, "%s node 0x%02X", hw.can.interface.c_str(), node.node_id);
      e.hardware_id = buf;
      keys(e, kEncoderNodeKeys, kEncoderNodeKeyCount);
    }
  }
  if (slots.wheel_odometry >= 0) {
    DeviceStatus& d = out[slots.wheel_odometry];
    d.name = "wheel odometry";
    d.hardware_id = hw.can.interface.c_str();
    keys(d, kWheelOdometryKeys, kWheelOdometryKeyCount);
  }
  if (slots.imu >= 0) {
    DeviceStatus& d = out[slots.imu];
    d.name = "imu";
    std::snprintf(buf, sizeof buf, "%s 0x%02X", hw.mpu.device.c_str(), hw.mpu.address);
    d.hardware_id = buf;
    keys(d, kImuKeys, kImuKeyCount);
  }
  if (slots.camera >= 0) {
    DeviceStatus& d = out[slots.camera];
    d.name = "camera";
    std::snprintf(buf, sizeof buf, "%s %s@%d", hw.camera.device.c_str(), hw.camera.resolution.c_str(), hw.camera.fps);
    d.hardware_id = buf;
    keys(d, kCameraKeys, kCameraKeyCount);
  }
  if (slots.vo >= 0) {
    DeviceStatus& d = out[slots.vo];
    d.name = "visual odometry";
    std::snprintf(buf, sizeof buf, "%s %s", hw.camera.device.c_str(), hw.camera.frame.c_str());
    d.hardware_id = buf;
    keys(d, kVoKeys, kVoKeyCount);
  }
  if (slots.gnss >= 0) {
    DeviceStatus& d = out[slots.gnss];
    d.name = "gnss";
    std::snprintf(buf, sizeof buf, "%s %s@%d", hw.gnss.device.c_str(),
                  hw.gnss.protocol == GnssProtocolConfig::kUbx ? "ubx" : "nmea", hw.gnss.baud);
    d.hardware_id = buf;
    keys(d, kGnssKeys, kGnssKeyCount);
  }
  int k = 0;
  for (int i = 0; i < cfg.num_sensors && k < slots.num_navsat; ++i) {
    const SensorConfig& c = cfg.sensors[static_cast<std::size_t>(i)];
    if (c.params.kind != est::SensorKind::kNavSatFix) continue;
    DeviceStatus& d = out[slots.first_navsat + k++];
    std::snprintf(buf, sizeof buf, "navsat %s", qualified_sensor_name(cfg, i).c_str());
    d.name = buf;
    d.hardware_id = c.channel.empty() ? c.name.c_str() : c.channel.c_str();
    keys(d, kNavsatKeys, kNavsatKeyCount);
  }
  return slots.count;
}

}  // namespace rtfuse
