#include "sim/sim_lcm_robot.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "geometry/rotation.hpp"
#include "rtfuse/imu_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "transport/encode_buffer.hpp"
#include "core/physical_constants.hpp"

namespace rtfuse::sim {
namespace {

constexpr TimeNs kNever = std::numeric_limits<TimeNs>::max();
constexpr int kMargin = 64;
// What a wheel-odometry node reports for a pose it only dead-reckons, and for
// the velocities a non-holonomic base asserts are zero.
constexpr double kDeadReckonedPoseVariance = 1e3;
constexpr double kNonHolonomicVariance = 1e-4;
// A zero variance means "unknown" to sensor_msgs consumers; a noise-free
// setting still reports a tiny, honest one.
constexpr double kMinVariance = 1e-9;
// Distance between the wheels of the simulated differential drive (a
// Jackal-sized base). Slip on one wheel turns into a yaw-rate error inversely
// proportional to it: the reason wheel odometry is worst at heading.
constexpr double kTrackWidth = 0.4;

double wrap_yaw(double a) noexcept { return std::remainder(a, 2.0 * kPi); }
double variance(double sigma) noexcept { return std::max(sigma * sigma, kMinVariance); }

// Derives independent stream seeds from the one config seed.
std::uint64_t splitmix64(std::uint64_t x) noexcept {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// Box-Muller over mt19937_64, instead of std::normal_distribution, so that a
// seed gives the same noise with any standard library (replay on a laptop).
class Gaussian {
 public:
  explicit Gaussian(std::uint64_t seed) : rng_(seed) {}
  double operator()() noexcept {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = (static_cast<double>(rng_() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
    const double u2 = static_cast<double>(rng_() >> 11) * 0x1.0p-53;          // [0, 1)
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * kPi * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * kPi * u2);
  }
  double uniform() noexcept { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }
  double sign() noexcept { return (rng_() >> 63) ? 1.0 : -1.0; }

 private:
  std::mt19937_64 rng_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

struct Kinematics {
  double x, y, yaw;  // odom frame
  double v;          // forward speed
  double yaw_rate;
  double accel;      // dv/dt
};

// Lemniscate of Gerono X = a sin(th), Y = a sin(th) cos(th), th = w t, with
// a = 2 * radius so each lobe spans 2r x 2r. Driven at constant w the speed
// varies (0.66x to 1.41x of the mean), which gives the IMU real forward
// accelerations; the speed never reaches zero, so the heading is always the
// direction of travel. Rotated so the robot starts at the origin facing +x,
// as a wheel-odometry frame does.
class FigureEight {
 public:
  FigureEight(double radius, double mean_speed) : a_(2.0 * radius) {
    // Perimeter by Simpson's rule; w then makes the mean speed the asked one.
    constexpr int kSteps = 4096;
    const double h = 2.0 * kPi / kSteps;
    double sum = 0.0;
    for (int i = 0; i <= kSteps; ++i) {
      const double th = i * h;
      const double f = std::hypot(std::cos(th), std::cos(2.0 * th));
      sum += f * ((i == 0 || i == kSteps) ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    const double perimeter = a_ * sum * h / 3.0;
    period_ = mean_speed > 0.0 && perimeter > 0.0 ? perimeter / mean_speed
                                                  : std::numeric_limits<double>::infinity();
    w_ = 2.0 * kPi / period_;  // 0 when standing still
  }

  double period() const noexcept { return period_; }

  Kinematics at(double t) const noexcept {
    const double th = w_ * t;
    const double s1 = std::sin(th), c1 = std::cos(th);
    const double s2 = std::sin(2.0 * th), c2 = std::cos(2.0 * th);
    const double px = a_ * s1, py = 0.5 * a_ * s2;
    const double dx = a_ * w_ * c1, dy = a_ * w_ * c2;
    const double ddx = -a_ * w_ * w_ * s1, ddy = -2.0 * a_ * w_ * w_ * s2;
    // The start heading is atan2(1, 1): rotate everything by -pi/4.
    constexpr double c0 = 0.70710678118654752440, s0 = 0.70710678118654752440;
    Kinematics k{};
    k.x = c0 * px + s0 * py;
    k.y = -s0 * px + c0 * py;
    k.v = std::hypot(dx, dy);
    if (k.v > 1e-12) {
      k.yaw = wrap_yaw(std::atan2(dy, dx) - 0.25 * kPi);
      k.yaw_rate = (dx * ddy - dy * ddx) / (k.v * k.v);
      k.accel = (dx * ddx + dy * ddy) / k.v;
    }
    return k;
  }

 private:
  double a_;
  double period_ = 0.0;
  double w_ = 0.0;
};

// A stream's k-th message is at start + k / rate, computed from k so that
// rounding never accumulates.
struct Stream {
  double rate_hz = 0.0;
  std::int64_t index = 0;
  TimeNs start = 0;
  TimeNs time() const noexcept {
    if (!(rate_hz > 0.0)) return kNever;
    return start + static_cast<TimeNs>(std::llround(static_cast<double>(index) * 1e9 / rate_hz));
  }
};

template <class Msg>
struct Encoded {
  Msg msg{};
  std::vector<std::uint8_t> bytes;
  std::uint32_t seq = 0;
  // Once the strings are set: sizes are fixed from here on, and the first
  // encode runs lcm-gen's lazily computed hash statics off the hot path.
  void finalize() {
    bytes.assign(static_cast<std::size_t>(msg.getEncodedSize() + kMargin), 0);
    msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  }
};

void set_quaternion(rtfuse::quaternion_t& out, double roll, double pitch, double yaw) noexcept {
  const Eigen::Quaterniond q = geometry::quaternion_from_rpy(roll, pitch, yaw);
  out.x = q.x();
  out.y = q.y();
  out.z = q.z();
  out.w = q.w();
}

void set_diagonal(double* m, int n, int i, double v) noexcept { m[i * n + i] = v; }

enum StreamId { kImu = 0, kOdom, kTruth, kStreams };

}  // namespace

struct SimLcmRobot::Impl {
  Impl(const SimLcmConfig& c, TimeNs t0)
      : cfg(c),
        start(t0),
        path(c.figure_eight_radius_m, c.speed_mps),
        imu_noise(splitmix64(c.seed ^ 0x494D55ULL)),
        odom_noise(splitmix64(c.seed ^ 0x4F444FULL)) {
    Gaussian setup(splitmix64(c.seed));
    for (int i = 0; i < 3; ++i) biases.gyro[i] = setup.sign() * c.gyro_bias_rad_s;
    for (int i = 0; i < 3; ++i) biases.accel[i] = setup.sign() * c.accel_bias_mps2;
    for (auto& p : slip_phase) p = 2.0 * kPi * setup.uniform();

    streams[kImu].rate_hz = c.imu_rate_hz;
    streams[kOdom].rate_hz = c.odom_rate_hz;
    streams[kTruth].rate_hz = c.odom_rate_hz;
    for (auto& s : streams) s.start = t0;
  }

  double seconds(TimeNs t) const noexcept { return ns_to_sec(t - start); }

  // Per wheel, two incommensurate sines with weights summing to 1: bounded by
  // wheel_slip and slow (periods of seconds), like floor and load changes.
  double wheel_slip_at(double t, int wheel) const noexcept {
    return cfg.wheel_slip * (0.6 * std::sin(2.0 * kPi * t / 11.0 + slip_phase[2 * wheel]) +
                             0.4 * std::sin(2.0 * kPi * t / 4.3 + slip_phase[2 * wheel + 1]));
  }

  // What the encoders report through the differential-drive kinematics when
  // each wheel's ground speed is off by its own slip fraction.
  LcmSimRobotSlip slip_at(double t, const Kinematics& k) const noexcept {
    LcmSimRobotSlip w{};
    w.left = wheel_slip_at(t, 0);
    w.right = wheel_slip_at(t, 1);
    const double v_left = k.v - 0.5 * kTrackWidth * k.yaw_rate;
    const double v_right = k.v + 0.5 * kTrackWidth * k.yaw_rate;
    w.speed_fraction = k.v > 1e-12 ? 0.5 * (v_right * w.right + v_left * w.left) / k.v : 0.0;
    w.yaw_rate_error = (v_right * w.right - v_left * w.left) / kTrackWidth;
    return w;
  }

  void build_imu(TimeNs stamp) noexcept;
  void build_odom(TimeNs stamp) noexcept;
  void build_truth(TimeNs stamp) noexcept;

  SimLcmConfig cfg;  // owns the channel strings handed out in SimMessage
  TimeNs start;
  FigureEight path;
  Gaussian imu_noise;
  double yaw_error = 0.0;       // the IMU's current yaw error
  TimeNs last_imu_stamp = 0;
  Gaussian odom_noise;
  SimBiases biases{};
  double slip_phase[4] = {};  // left wheel: 0, 1; right wheel: 2, 3
  Stream streams[kStreams];
  Encoded<rtfuse::imu_t> imu;
  Encoded<rtfuse::odometry_t> odom;
  Encoded<rtfuse::odometry_t> truth;
  // The wheel-odometry node's own dead reckoning.
  bool odom_started = false;
  TimeNs odom_last = 0;
  double odom_x = 0.0, odom_y = 0.0, odom_yaw = 0.0;
};

void SimLcmRobot::Impl::build_imu(TimeNs stamp) noexcept {
  const double t = seconds(stamp);
  const Kinematics k = path.at(t);
  auto& m = imu.msg;
  m.header.utime = ns_to_utime(stamp);
  m.header.seq = static_cast<std::int32_t>(imu.seq++);

  const double so = cfg.orientation_noise_rad;
  // First-order Gauss-Markov yaw error: e <- a e + s sqrt(1 - a^2) w keeps its
  // standard deviation at yaw_error however long the drive, as the
  // magnetometer of an AHRS does; between corrections it wanders.
  const double dt = last_imu_stamp == 0 ? 0.0 : ns_to_sec(stamp - last_imu_stamp);
  last_imu_stamp = stamp;
  const double a = std::exp(-dt / cfg.yaw_error_time_s);
  yaw_error = a * yaw_error + cfg.yaw_error_rad * std::sqrt(1.0 - a * a) * imu_noise();
  set_quaternion(m.orientation, so * imu_noise(), so * imu_noise(), wrap_yaw(k.yaw + yaw_error + so * imu_noise()));
  // An honest driver reports the error it knows it has, not the white-noise level.
  set_diagonal(m.orientation_covariance, 3, 2, variance(so) + variance(cfg.yaw_error_rad));

  const double sg = cfg.gyro_noise_rad_s;
  m.angular_velocity.x = biases.gyro[0] + sg * imu_noise();
  m.angular_velocity.y = biases.gyro[1] + sg * imu_noise();
  m.angular_velocity.z = k.yaw_rate + biases.gyro[2] + sg * imu_noise();

  // Specific force in base_link: forward acceleration, centripetal v * yaw
  // rate towards the inside of the turn, and the floor pushing up against g.
  const double sa = cfg.accel_noise_mps2;
  m.linear_acceleration.x = k.accel + biases.accel[0] + sa * imu_noise();
  m.linear_acceleration.y = k.v * k.yaw_rate + biases.accel[1] + sa * imu_noise();
  m.linear_acceleration.z = kStandardGravity + biases.accel[2] + sa * imu_noise();
}

void SimLcmRobot::Impl::build_odom(TimeNs stamp) noexcept {
  const double t = seconds(stamp);
  const Kinematics k = path.at(t);
  const LcmSimRobotSlip slip = slip_at(t, k);
  const double vx = k.v * (1.0 + slip.speed_fraction) + cfg.odom_speed_noise_mps * odom_noise();
  const double vyaw = k.yaw_rate + slip.yaw_rate_error + cfg.odom_yaw_rate_noise_rad_s * odom_noise();

  // Dead reckoning of the measured twist (midpoint heading), as the node on
  // the robot does: its pose drifts without bound, hence the 1e3 variances.
  if (odom_started) {
    const double dt = ns_to_sec(stamp - odom_last);
    const double mid = odom_yaw + 0.5 * vyaw * dt;
    odom_x += vx * std::cos(mid) * dt;
    odom_y += vx * std::sin(mid) * dt;
    odom_yaw = wrap_yaw(odom_yaw + vyaw * dt);
  }
  odom_started = true;
  odom_last = stamp;

  auto& m = odom.msg;
  m.header.utime = ns_to_utime(stamp);
  m.header.seq = static_cast<std::int32_t>(odom.seq++);
  m.pose.pose.position.x = odom_x;
  m.pose.pose.position.y = odom_y;
  set_quaternion(m.pose.pose.orientation, 0.0, 0.0, odom_yaw);
  m.twist.twist.linear.x = vx;
  m.twist.twist.angular.z = vyaw;
}

void SimLcmRobot::Impl::build_truth(TimeNs stamp) noexcept {
  const Kinematics k = path.at(seconds(stamp));
  auto& m = truth.msg;
  m.header.utime = ns_to_utime(stamp);
  m.header.seq = static_cast<std::int32_t>(truth.seq++);
  m.pose.pose.position.x = k.x;
  m.pose.pose.position.y = k.y;
  set_quaternion(m.pose.pose.orientation, 0.0, 0.0, k.yaw);
  m.twist.twist.linear.x = k.v;
  m.twist.twist.angular.z = k.yaw_rate;
}

SimLcmRobot::SimLcmRobot(const SimLcmConfig& cfg, TimeNs start) : impl_(std::make_unique<Impl>(cfg, start)) {
  Impl& m = *impl_;

  m.imu.msg.header.frame_id = "base_link";
  m.imu.msg.orientation.w = 1.0;
  const double so = variance(cfg.orientation_noise_rad);
  const double sg = variance(cfg.gyro_noise_rad_s);
  const double sa = variance(cfg.accel_noise_mps2);
  for (int i = 0; i < 3; ++i) {
    set_diagonal(m.imu.msg.orientation_covariance, 3, i, so);
    set_diagonal(m.imu.msg.angular_velocity_covariance, 3, i, sg);
    set_diagonal(m.imu.msg.linear_acceleration_covariance, 3, i, sa);
  }
  m.imu.finalize();

  m.odom.msg.header.frame_id = "odom";
  m.odom.msg.child_frame_id = "base_link";
  m.odom.msg.pose.pose.orientation.w = 1.0;
  for (int i = 0; i < 6; ++i) {
    set_diagonal(m.odom.msg.pose.covariance, 6, i, kDeadReckonedPoseVariance);
    set_diagonal(m.odom.msg.twist.covariance, 6, i, kNonHolonomicVariance);
  }
  set_diagonal(m.odom.msg.twist.covariance, 6, 0, variance(cfg.odom_speed_noise_mps));
  set_diagonal(m.odom.msg.twist.covariance, 6, 5, variance(cfg.odom_yaw_rate_noise_rad_s));
  m.odom.finalize();

  // Truth: zero covariance, exactly as given.
  m.truth.msg.header.frame_id = "odom";
  m.truth.msg.child_frame_id = "base_link";
  m.truth.msg.pose.pose.orientation.w = 1.0;
  m.truth.finalize();
}

SimLcmRobot::~SimLcmRobot() = default;

TimeNs SimLcmRobot::next_time() const noexcept {
  TimeNs t = kNever;
  for (const auto& s : impl_->streams) t = std::min(t, s.time());
  return t;
}

bool SimLcmRobot::next_due(TimeNs now, SimMessage* out) noexcept {
  Impl& m = *impl_;
  int id = kImu;
  TimeNs stamp = m.streams[kImu].time();
  for (int i = kOdom; i < kStreams; ++i) {
    const TimeNs t = m.streams[i].time();
    if (t < stamp) {  // strict: ties go to the lower stream id
      stamp = t;
      id = i;
    }
  }
  if (stamp == kNever || stamp > now || out == nullptr) return false;

  const std::vector<std::uint8_t>* bytes = nullptr;
  int size = -1;
  switch (id) {
    case kImu:
      m.build_imu(stamp);
      size = transport::encode_into(m.imu.msg, m.imu.bytes.data(), static_cast<int>(m.imu.bytes.size()));
      bytes = &m.imu.bytes;
      out->channel = m.cfg.imu_channel.c_str();
      break;
    case kOdom:
      m.build_odom(stamp);
      size = transport::encode_into(m.odom.msg, m.odom.bytes.data(), static_cast<int>(m.odom.bytes.size()));
      bytes = &m.odom.bytes;
      out->channel = m.cfg.odom_channel.c_str();
      break;
    default:
      m.build_truth(stamp);
      size = transport::encode_into(m.truth.msg, m.truth.bytes.data(), static_cast<int>(m.truth.bytes.size()));
      bytes = &m.truth.bytes;
      out->channel = m.cfg.truth_channel.c_str();
      break;
  }
  ++m.streams[id].index;
  out->data = bytes->data();
  out->size = size < 0 ? 0 : size;  // cannot fail: every size was fixed in the constructor
  out->stamp = stamp;
  return true;
}

TruthPose SimLcmRobot::truth(TimeNs t) const noexcept {
  const Kinematics k = impl_->path.at(impl_->seconds(t));
  return TruthPose{k.x, k.y, k.yaw, k.v, k.yaw_rate};
}

double SimLcmRobot::period_s() const noexcept { return impl_->path.period(); }

LcmSimRobotSlip SimLcmRobot::slip(TimeNs t) const noexcept {
  const double s = impl_->seconds(t);
  return impl_->slip_at(s, impl_->path.at(s));
}

const SimBiases& SimLcmRobot::biases() const noexcept { return impl_->biases; }

}  // namespace rtfuse::sim
