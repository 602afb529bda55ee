#pragma once
// A drive of the bus-level simulated robot: the path it drives (or, in a
// commanded drive, its base's limits and the goals a navigator is given),
// the robot as it really is (geometry, encoders, calibration error), the
// wheel slip, the encoder dropouts and the IMU, read from a scenario TOML
// file (config/scenarios/*.toml documents every key).
//
// Units inside are SI and radians; the file uses the units its key names
// say (angle_deg, yaw_rate_dps...). Configuration time only: loading
// allocates freely.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/time.hpp"
#include "drivers/wheel/drive_kinematics.hpp"
#include "sim/devices/mpu_register_file.hpp"
#include "sim/obstacle_box.hpp"

namespace rtfuse::sim {

constexpr int kMaxSimWheels = 4;
constexpr int kMaxSlipEpisodes = 16;
constexpr int kMaxDropouts = 16;
constexpr int kMaxGnssOutages = 16;
constexpr int kMaxDriveGoals = 64;

enum class SegmentType : std::uint8_t { kStraight, kArc, kSpin, kFigureEight, kStop };

// One [[path]] entry. Positive angles and yaw rates turn left
// (counter-clockwise seen from above), as ROS's z-up convention has it.
struct PathSegment {
  SegmentType type = SegmentType::kStop;
  double length_m = 0.0;        // straight (duration_s is turned into length = speed * duration)
  double speed_mps = 0.0;       // straight, arc, figure eight: cruise speed, > 0
  double radius_m = 0.0;        // arc: its radius (also from speed / yaw_rate); figure eight: tightest radius
  double angle_rad = 0.0;       // arc, spin: signed heading change
  double yaw_rate_rad_s = 0.0;  // spin: cruise yaw rate, > 0
  double duration_s = 0.0;      // stop
  int laps = 0;                 // figure eight
  bool right_first = false;     // figure eight: first lobe turns right
  int line = 0;                 // where the entry starts in the file, for planning errors
  int column = 0;
};

struct MotionLimits {
  double max_accel_mps2 = 0.5;
  double max_yaw_accel_rad_s2 = 1.5;
};

// The base moves as the wheel odometry assumes it does.
using drivers::DriveKinematics;

// Wheel order everywhere in the simulator: differential [left, right];
// skid steer [left front, left rear, right front, right rear].
struct SimWheel {
  std::uint8_t node_id = 1;
  bool left = true;
  double radius_error = 0.0;  // true radius = nominal * (1 + radius_error)
};

struct RobotBody {
  DriveKinematics kinematics = DriveKinematics::kDifferential;
  double track_width_m = 0.5;  // skid steer: the effective track (wheels scrub in turns)
  double wheel_radius_m = 0.1;  // nominal, what the robot's config says
  double counts_per_rev = 4096;  // encoder counts per encoder shaft revolution
  double gear_ratio = 1.0;       // encoder shaft revolutions per wheel revolution
  int encoder_bits = 32;         // the position wraps at 2^bits
  bool encoder_signed = false;   // wraps to [-2^(bits-1), 2^(bits-1)) instead of [0, 2^bits)
  bool invert_left = false;      // the encoder counts down driving forward (mirrored motor)
  bool invert_right = false;
  TimeNs heartbeat_period_ns = 100'000'000;
  int wheel_count = 2;
  std::array<SimWheel, kMaxSimWheels> wheels{};
};

struct SlipEpisode {
  double start_s = 0.0;
  double duration_s = 0.0;
  std::uint8_t wheel_mask = 0;  // bit i: wheel i (order as RobotBody::wheels)
  double fraction = 0.0;        // the wheel rolls (1 + fraction) times the ground distance
};

struct WheelSlip {
  double noise_fraction = 0.0;  // 1-sigma of the continuous slip, per wheel
  double correlation_time_s = 1.0;
  int episode_count = 0;
  std::array<SlipEpisode, kMaxSlipEpisodes> episodes{};
};

struct EncoderDropout {
  std::uint8_t node_id = 0;
  double start_s = 0.0;
  double duration_s = 0.0;
};


struct SimImuConfig {
  MpuChip model = MpuChip::kMpu6050;
  std::uint8_t address = 0x68;
  double rate_hz = 200.0;                        // data-ready edges per second
  int gyro_range_dps = 500;                      // what the robot's driver is expected to configure
  int accel_range_g = 4;
  double gyro_noise_density = 8.7e-5;            // rad/s/sqrt(Hz)
  double accel_noise_density = 3.9e-3;           // m/s^2/sqrt(Hz)
  std::array<double, 3> gyro_bias_rad_s{};       // in the IMU frame
  std::array<double, 3> accel_bias_mps2{};
  std::array<double, 3> xyz_m{};                 // IMU origin in base_link
  std::array<double, 3> rpy_rad{};               // IMU axes in base_link (tf2 roll-pitch-yaw)
  double temperature_c = 30.0;
  // A rolling base shakes its IMU: white noise per sample and axis on top of
  // the chip's own, 1-sigma vibration_* once the fastest wheel rolls at
  // vibration_speed_mps or faster, growing linearly from nothing at rest.
  // A Clearpath Jackal's IMU in robot_localization's test2.bag, per 50 Hz
  // sample, high-passed: 0.15-0.9 m/s^2 and 0.005-0.06 rad/s per axis at
  // 0.3-2 m/s, 0.02-0.05 m/s^2 and 0.004 rad/s at rest. 0: a vibration-free
  // mount.
  double vibration_accel_mps2 = 0.0;
  double vibration_gyro_rad_s = 0.0;
  double vibration_speed_mps = 0.3;
};

struct GnssOutage {
  double start_s = 0.0;
  double duration_s = 0.0;
};

// [gnss]: a u-blox receiver on the robot, its antenna's error as a 1 m-class
// receiver has it: a bias that wanders slowly (first-order Gauss-Markov per
// axis), white noise on top, now and then a multipath jump of a few epochs,
// and outages (a bridge, a tunnel) where it reports no fix.
struct SimGnssConfig {
  bool enabled = false;
  double rate_hz = 5.0;
  // Where the drive's origin is on the earth; the world frame's x axis
  // points east, y north.
  double latitude_deg = 47.3977;
  double longitude_deg = 8.5456;
  double altitude_m = 488.0;
  double latency_s = 0.1;            // from the epoch to its first byte
  double bias_sigma_m = 0.7;         // horizontal, per axis
  double vertical_bias_sigma_m = 1.5;
  double bias_time_s = 60.0;         // correlation time
  double noise_m = 0.25;             // white, horizontal, per axis
  double vertical_noise_m = 0.5;
  double multipath_per_hour = 20.0;  // jumps
  double multipath_m = 12.0;         // their size
  int multipath_epochs = 3;          // their length
  int satellites = 14;
  std::array<double, 3> antenna_xyz_m{};  // in base_link
  int outage_count = 0;
  std::array<GnssOutage, kMaxGnssOutages> outages{};
};

// [drive] mode: a scripted [[path]], or a base that follows velocity
// commands (commanded_base.hpp).
enum class DriveMode : std::uint8_t { kPath, kCommanded };

// [base]: the commanded base's drive. A command (v, w) asks each side for
// v -/+ w * track / 2; the wheels go no faster than max_wheel_speed and
// change speed no faster than max_wheel_accel.
struct BaseLimits {
  double max_wheel_speed_mps = 1.0;
  double max_wheel_accel_mps2 = 1.0;
  // A command acts this long after it was issued (the bus and the motor
  // controller's cycle).
  double command_latency_s = 0.02;
  // With no command newer than this in effect, the base stops by itself.
  double command_timeout_s = 0.5;
};

// [[goal]]: where the navigator is sent, in order, odom frame.
struct DriveGoal {
  double x_m = 0.0, y_m = 0.0;
  bool has_yaw = false;
  double yaw_rad = 0.0;  // the heading to arrive with, when has_yaw
  double tolerance_m = 0.3;
  int line = 0;  // where the entry starts in the file
};

struct DriveScenario {
  std::string source;   // the file it came from
  DriveMode mode = DriveMode::kPath;
  double duration_s = 0.0;  // the run; 0 = as long as the path takes
  std::uint64_t seed = 1;
  MotionLimits limits;
  std::vector<PathSegment> path;
  RobotBody robot;
  WheelSlip slip;
  int dropout_count = 0;
  std::array<EncoderDropout, kMaxDropouts> dropouts{};
  SimImuConfig imu;
  SimGnssConfig gnss;
  // [[obstacle]]: solids inside the drive area; the path keeps its distance.
  std::vector<ObstacleBox> obstacles;
  // A commanded drive's (mode kCommanded; duration_s is then set, path empty).
  BaseLimits base;
  std::vector<DriveGoal> goals;
};

// Reads and validates a scenario. On failure returns false and sets *error
// to every problem found, one per line, as "file:line:column: key: message".
bool load_drive_scenario(const std::string& path, DriveScenario* out, std::string* error);
// The same from text; source_name stands in for the file name in errors.
bool load_drive_scenario_string(std::string_view toml_text, const std::string& source_name, DriveScenario* out,
                                std::string* error);

const char* to_string(SegmentType type) noexcept;

}  // namespace rtfuse::sim
