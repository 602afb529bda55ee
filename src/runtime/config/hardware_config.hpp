#pragma once
// The devices the process drives itself, as the TOML describes them
// ([hardware], [can], [[can.node]], [wheel_odometry], [mpu]). Plain values
// only; runtime/hardware.cpp turns them into the drivers' own configs.
// Schema: docs/configuration.md.
#include <array>
#include <cstdint>
#include <string>

#include "core/fixed_string.hpp"

namespace rtfuse {

using HwName = FixedString<63>;  // the same type as config.hpp's Name

// Where the bus primitives come from: the kernel (SocketCAN, i2c-dev,
// libgpiod), the bus-level simulated robot, or nothing (LCM inputs only).
enum class HalBackend : std::uint8_t { kNone, kLinux, kSim };

enum class WheelSideConfig : std::uint8_t { kLeft, kRight };
enum class KinematicsConfig : std::uint8_t { kDifferential, kSkidSteer };
enum class MpuModelConfig : std::uint8_t { kAuto, kMpu6050, kMpu6500, kMpu9250 };
enum class AttitudeAlgorithmConfig : std::uint8_t { kMadgwick, kMahony };
enum class GnssProtocolConfig : std::uint8_t { kUbx, kNmea };

constexpr int kMaxWheelNodes = 8;

struct CanNodeSection {
  std::uint8_t node_id = 1;
  WheelSideConfig side = WheelSideConfig::kLeft;
  int sign = 1;                      // -1 for the mirrored motor
  std::uint32_t tpdo_cob_id = 0;     // 0: TPDO1 = 0x180 + node_id
  std::uint8_t position_offset = 0;  // first byte of the position in the TPDO
  std::uint8_t position_bits = 32;   // 8, 16, 24 or 32
  bool position_signed = false;
};

struct CanSection {
  bool enabled = false;
  HwName interface{"can0"};
  std::uint32_t sync_cob_id = 0x080;
  double heartbeat_timeout_s = 0.5;  // 0: no heartbeat supervision
  int tpdo_timeout_syncs = 5;
  double stuck_time_s = 0.5;
  double max_wheel_speed_mps = 5.0;  // beyond this a counter step is a glitch
  std::array<CanNodeSection, kMaxWheelNodes> nodes{};
  int num_nodes = 0;
};

struct WheelOdometrySection {
  KinematicsConfig kinematics = KinematicsConfig::kDifferential;
  double track_width_m = 0.5;
  double wheel_radius_m = 0.1;
  double counts_per_rev = 4096;
  double gear_ratio = 1.0;
  double skid_track_factor = 1.0;
  double speed_noise_mps = 0.01;
  double yaw_rate_noise_rad_s = 0.02;
  double slip = 0.02;              // 1-sigma fractional speed error
  double lateral_noise_mps = 0.01; // vy: the non-holonomic constraint, held loosely
  HwName raw_channel{"rtfuse/wheel_odometry"};  // dead-reckoned odometry_t
  double raw_rate_hz = 50.0;                    // 0: not published
};

struct AttitudeSection {
  AttitudeAlgorithmConfig algorithm = AttitudeAlgorithmConfig::kMadgwick;
  double beta = 0.1;    // Madgwick gain
  double zeta = 0.005;  // Madgwick gyro-bias gain
  double kp = 1.0;      // Mahony proportional gain
  double ki = 0.02;     // Mahony integral gain (gyro bias)
};

struct MpuSection {
  bool enabled = false;
  HwName device{"/dev/i2c-1"};
  std::uint8_t address = 0x68;
  MpuModelConfig model = MpuModelConfig::kAuto;
  int sample_rate_divider = 4;  // 1 kHz / (1 + 4) = 200 Hz with the DLPF on
  int dlpf = 3;
  int gyro_range_dps = 500;
  int accel_range_g = 4;
  HwName data_ready_chip;       // gpiochip label or path; "" = no line, poll
  int data_ready_line = -1;
  double poll_rate_hz = 200.0;  // without a data-ready line
  HwName frame{"imu_link"};     // mounting: static transform base_link -> frame
  int frozen_reads = 10;
  double gyro_noise_rad_s = 0.005;   // per-sample 1-sigma
  double accel_noise_mps2 = 0.05;
  AttitudeSection attitude;
};

// [camera]: a ZED-class stereo camera on V4L2 (or the simulated robot's).
struct CameraSection {
  bool enabled = false;
  HwName device{"/dev/video0"};
  std::string calibration_file;  // the factory SN<serial>.conf (resolved path)
  // The calibration file's bytes when they come from elsewhere than the file
  // (the embedded config's, a recording's), or once read at start-up (see
  // runtime/camera_calibration.hpp); "" = read calibration_file.
  std::string calibration_text;
  std::int64_t serial = 0;       // 0: any; else the file must be this camera's
  HwName resolution{"VGA"};      // 2K, FHD, HD, VGA
  int fps = 30;
  int buffers = 4;               // V4L2 mmap buffers
  int pool_frames = 4;           // rectified pairs lent to consumers
  HwName frame{"camera_optical"};  // the left eye's optical frame: static transform base_link -> frame
  double reopen_backoff_s = 0.25;  // first wait before reopening an unplugged camera
  double reopen_backoff_max_s = 8.0;
  HwName info_channel{"rtfuse/camera/info"};        // camera_info_t of the rectified left eye
  HwName preview_channel{"rtfuse/camera/preview"};  // image_t, both eyes side by side
  double preview_rate_hz = 1.0;  // 0: no preview
  int preview_downscale = 2;
};

// [vo]: stereo visual odometry on the camera's thread (vision/stereo_odometry),
// feeding the [[sensor]] with source = "stereo_vo" a twist of camera.frame.
struct VoSection {
  bool enabled = false;
  bool half_resolution = true;     // detect and match at half size (VGA and up)
  int ransac_iterations = 200;
  double inlier_threshold_px = 2.0;
  int min_inliers = 20;            // fewer: no measurement (a plain wall, a covered lens)
  int bucket_size_px = 50;         // matches spread over buckets of this size
  int bucket_max = 2;              // kept per bucket
  // A longer interval between two processed pairs (frames lost, the camera
  // unplugged) starts the odometry again instead of bridging it.
  double max_interval_s = 0.25;
  // Faster than this is a wrong solution, not a robot: rejected and counted.
  double max_speed_mps = 10.0;
  double max_turn_rate_rad_s = 6.0;
  // The egomotion's covariance (s^2 (J^T J)^-1) counts every inlier as an
  // independent measurement, which neighbouring features are not: on the
  // simulated robot at VGA the twists scatter about 4x its sigma while the
  // robot moves. It is multiplied by this, and the sigmas below are added
  // in quadrature.
  double covariance_scale = 16.0;
  double min_linear_sigma_mps = 0.005;
  double min_angular_sigma_rad_s = 0.002;
};

// [gnss]: a GNSS receiver on a serial port (UART or USB CDC-ACM), feeding
// the [[sensor]] with source = "gnss" (a navsat sensor) its fixes.
struct GnssSection {
  bool enabled = false;
  HwName device{"/dev/ttyACM0"};
  int baud = 115200;  // a USB CDC-ACM port ignores it; a UART needs the receiver's
  GnssProtocolConfig protocol = GnssProtocolConfig::kUbx;
  bool use_rmc = true;   // NMEA: wait for RMC in each epoch
  bool use_gst = false;  // NMEA: wait for GST (the receiver's error estimate)
  // The receiver sends an epoch this long after it (u-blox: 50-200 ms, the
  // more the higher the rate and the longer the messages): the fix is fused
  // at its epoch, through the filter's lagged-data history.
  double latency_s = 0.1;
  double silent_after_s = 2.0;  // no byte for this long: the receiver is silent
  double reopen_backoff_s = 0.5;  // first wait before reopening an unplugged receiver
  double reopen_backoff_max_s = 8.0;
};

struct HardwareConfig {
  HalBackend backend = HalBackend::kNone;
  std::string scenario;  // backend "sim": the drive scenario file (resolved path)
  CanSection can;
  WheelOdometrySection wheel_odometry;
  MpuSection mpu;
  CameraSection camera;
  VoSection vo;
  GnssSection gnss;
  int wheel_sensor = -1;  // index of the [[sensor]] with source = "wheel_odometry"
  int mpu_sensor = -1;    // index of the [[sensor]] with source = "mpu"
  int vo_sensor = -1;     // index of the [[sensor]] with source = "stereo_vo"
  int gnss_sensor = -1;   // index of the [[sensor]] with source = "gnss"
};

}  // namespace rtfuse
