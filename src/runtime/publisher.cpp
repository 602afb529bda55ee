#include "runtime/publisher.hpp"

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "geometry/rotation.hpp"
#include "runtime/device_layout.hpp"
#include "rtfuse/diagnostics_t.hpp"
#include "rtfuse/filter_state_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "rtfuse/pose_with_covariance_stamped_t.hpp"
#include "rtfuse/tf_t.hpp"
#include "transport/encode_buffer.hpp"

namespace rtfuse {
namespace {

constexpr int kN = 15;        // states
constexpr int kMargin = 64;   // bytes beyond getEncodedSize(): sizes are fixed, this is belt and braces

// Fixed-rate schedule on the caller's clock. The next slot advances by whole
// periods from the previous slot, not from `now`, so a 30 Hz output polled at
// 1 kHz averages 30 Hz instead of drifting down to 1/ceil(period).
class Schedule {
 public:
  void set_rate(double rate_hz) {
    period_ = 0;
    if (std::isfinite(rate_hz) && rate_hz > 0.0) {
      const TimeNs p = sec_to_ns(1.0 / rate_hz);
      period_ = p > 0 ? p : 1;
    }
  }
  bool enabled() const noexcept { return period_ > 0; }

  // True (and the slot consumed) when a message is due at now.
  bool due(TimeNs now) noexcept {
    if (!enabled()) return false;
    // First call, or the clock went back (a replay restarted): publish now.
    if (!started_ || now < next_ - period_) {
      started_ = true;
      next_ = now + period_;
      return true;
    }
    if (now < next_) return false;
    next_ += period_;
    // After a stall, skip the missed slots rather than send a burst.
    if (now >= next_) next_ = now + period_;
    return true;
  }

 private:
  TimeNs period_ = 0;  // 0: disabled
  TimeNs next_ = 0;
  bool started_ = false;
};

template <class Msg>
struct Output {
  Msg msg{};
  std::vector<std::uint8_t> bytes;
  Schedule schedule;
  const char* channel = "";
  std::uint32_t seq = 0;  // unsigned: wraps instead of overflowing after years

  // Called once the strings and array sizes are final. Encoding once here
  // also runs lcm-gen's lazily computed static hashes off the hot path.
  void finalize() {
    bytes.assign(static_cast<std::size_t>(msg.getEncodedSize() + kMargin), 0);
    msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  }
  std::int32_t next_seq() noexcept { return static_cast<std::int32_t>(seq++); }
};

double cov(const Snapshot& s, int row, int col) noexcept { return s.covariance[row * kN + col]; }

void fill_pose(const Snapshot& s, rtfuse::pose_with_covariance_t& p) noexcept {
  p.pose.position.x = s.state[0];
  p.pose.position.y = s.state[1];
  p.pose.position.z = s.state[2];
  const Eigen::Quaterniond q = geometry::quaternion_from_rpy(s.state[3], s.state[4], s.state[5]);
  p.pose.orientation.x = q.x();
  p.pose.orientation.y = q.y();
  p.pose.orientation.z = q.z();
  p.pose.orientation.w = q.w();
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) p.covariance[r * 6 + c] = cov(s, r, c);
}

void fill_twist(const Snapshot& s, rtfuse::twist_with_covariance_t& t) noexcept {
  t.twist.linear.x = s.state[6];
  t.twist.linear.y = s.state[7];
  t.twist.linear.z = s.state[8];
  t.twist.angular.x = s.state[9];
  t.twist.angular.y = s.state[10];
  t.twist.angular.z = s.state[11];
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) t.covariance[r * 6 + c] = cov(s, 6 + r, 6 + c);
}

}  // namespace

struct Publisher::Impl {
  explicit Impl(const RuntimeConfig& c) : cfg(c.publish) {}

  template <class Msg>
  int emit(Output<Msg>& out, TimeNs now, MessageSink& sink) noexcept {
    const int n = transport::encode_into(out.msg, out.bytes.data(), static_cast<int>(out.bytes.size()));
    if (n < 0) {
      ++encode_failures;
      return 0;
    }
    return sink.publish(out.channel, out.bytes.data(), n, now) ? 1 : 0;
  }

  PublishConfig cfg;  // owns the channel strings the outputs point into
  int num_sensors = 0;
  int num_devices = 0;
  Output<rtfuse::odometry_t> odometry;
  Output<rtfuse::pose_with_covariance_stamped_t> pose;
  Output<rtfuse::tf_t> tf;
  Output<rtfuse::filter_state_t> state;
  Output<rtfuse::diagnostics_t> diagnostics;
  Output<rtfuse::odometry_t> wheel_odometry;  // raw dead reckoning from the encoders
  std::int64_t last_wheel_stamp = -1;
  HwName wheel_channel;
  std::array<std::int64_t, kMaxSensors> rejections_at_last_diagnostics{};
  std::int64_t encode_failures = 0;
};

Publisher::Publisher(const RuntimeConfig& c) : impl_(std::make_unique<Impl>(c)) {
  Impl& m = *impl_;
  const std::string world = c.world_frame.c_str();
  const std::string base = c.base_link_frame.c_str();

  m.odometry.channel = m.cfg.odometry_channel.c_str();
  m.odometry.schedule.set_rate(m.cfg.odometry_rate_hz);
  m.odometry.msg.header.frame_id = world;
  m.odometry.msg.child_frame_id = base;
  m.odometry.finalize();

  m.pose.channel = m.cfg.pose_channel.c_str();
  m.pose.schedule.set_rate(m.cfg.pose_rate_hz);
  m.pose.msg.header.frame_id = world;
  m.pose.finalize();

  m.tf.channel = m.cfg.tf_channel.c_str();
  m.tf.schedule.set_rate(m.cfg.publish_tf ? m.cfg.tf_rate_hz : 0.0);
  m.tf.msg.num_transforms = 1;
  m.tf.msg.transforms.resize(1);
  m.tf.msg.transforms[0].header.frame_id = world;
  m.tf.msg.transforms[0].child_frame_id = base;
  m.tf.msg.transforms[0].transform.rotation.w = 1.0;
  m.tf.finalize();

  m.state.channel = m.cfg.state_channel.c_str();
  m.state.schedule.set_rate(m.cfg.state_rate_hz);
  m.state.msg.header.frame_id = world;
  m.state.msg.child_frame_id = base;
  m.state.finalize();

  m.diagnostics.channel = m.cfg.diagnostics_channel.c_str();
  m.diagnostics.schedule.set_rate(m.cfg.diagnostics_rate_hz);
  const int n = c.num_sensors < 0 ? 0 : (c.num_sensors > kMaxSensors ? kMaxSensors : c.num_sensors);
  m.num_sensors = n;
  m.diagnostics.msg.num_sensors = n;
  m.diagnostics.msg.sensors.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    auto& st = m.diagnostics.msg.sensors[static_cast<std::size_t>(i)];
    st.name = c.sensors[static_cast<std::size_t>(i)].name.c_str();
    st.channel = c.sensors[static_cast<std::size_t>(i)].channel.c_str();
    st.level = rtfuse::sensor_status_t::STALE;
  }
  DeviceStatus layout[kMaxDevices];
  m.num_devices = describe_devices(c, layout, kMaxDevices);
  m.diagnostics.msg.num_devices = m.num_devices;
  m.diagnostics.msg.devices.resize(static_cast<std::size_t>(m.num_devices));
  for (int i = 0; i < m.num_devices; ++i) {
    auto& d = m.diagnostics.msg.devices[static_cast<std::size_t>(i)];
    d.name = layout[i].name.c_str();
    d.hardware_id = layout[i].hardware_id.c_str();
    d.level = rtfuse::sensor_status_t::STALE;
    d.num_values = layout[i].num_values;
    d.keys.resize(static_cast<std::size_t>(layout[i].num_values));
    d.values.assign(static_cast<std::size_t>(layout[i].num_values), 0);
    for (int k = 0; k < layout[i].num_values; ++k) d.keys[static_cast<std::size_t>(k)] = layout[i].keys[k];
    // Sized for the longest state word and message so the buffer and the
    // strings' capacities never have to grow in poll().
    d.state.assign(decltype(layout[i].state)::max_size(), ' ');
    d.message.assign(DeviceMessage::max_size(), ' ');
  }
  m.diagnostics.finalize();
  for (auto& d : m.diagnostics.msg.devices) {
    d.state = "starting";
    d.message.clear();  // keeps the capacity
  }

  const WheelOdometrySection& w = c.hardware.wheel_odometry;
  m.wheel_channel = w.raw_channel;
  m.wheel_odometry.channel = m.wheel_channel.c_str();
  m.wheel_odometry.schedule.set_rate(c.hardware.wheel_sensor >= 0 ? w.raw_rate_hz : 0.0);
  m.wheel_odometry.msg.header.frame_id = c.odom_frame.c_str();
  m.wheel_odometry.msg.child_frame_id = base;
  // Dead reckoning has no pose covariance worth the name: say "unknown" the
  // way robot_localization users read it, a huge variance.
  for (int i = 0; i < 6; ++i) m.wheel_odometry.msg.pose.covariance[i * 7] = 1e6;
  m.wheel_odometry.finalize();
}

Publisher::~Publisher() = default;

std::int64_t Publisher::encode_failures() const { return impl_->encode_failures; }

std::uint32_t Publisher::schedule(const Snapshot& s, TimeNs now) noexcept {
  Impl& m = *impl_;
  std::uint32_t due = 0;
  if (s.initialized && m.odometry.schedule.due(now)) due |= kOdometry;
  if (s.initialized && m.pose.schedule.due(now)) due |= kPose;
  if (s.initialized && m.tf.schedule.due(now)) due |= kTf;
  if (s.initialized && m.state.schedule.due(now)) due |= kState;
  const WheelOdometrySnapshot& w = s.wheel_odometry;
  if (w.valid && w.stamp_ns != m.last_wheel_stamp && m.wheel_odometry.schedule.due(now)) {
    m.last_wheel_stamp = w.stamp_ns;
    due |= kWheelOdometry;
  }
  if (m.diagnostics.schedule.due(now)) due |= kDiagnostics;
  return due;
}

int Publisher::poll(const Snapshot& s, TimeNs now, MessageSink& sink) noexcept {
  return publish(s, schedule(s, now), now, sink);
}

int Publisher::publish(const Snapshot& s, std::uint32_t due, TimeNs now, MessageSink& sink) noexcept {
  Impl& m = *impl_;
  int sent = 0;
  // The estimate's own time, not the publishing time: consumers interpolate
  // and look up transforms by it, as they would with robot_localization.
  const std::int64_t utime = ns_to_utime(s.stamp_ns);

  if (due & kOdometry) {
    auto& o = m.odometry.msg;
    o.header.utime = utime;
    o.header.seq = m.odometry.next_seq();
    fill_pose(s, o.pose);
    fill_twist(s, o.twist);
    sent += m.emit(m.odometry, now, sink);
  }

  if (due & kPose) {
    auto& o = m.pose.msg;
    o.header.utime = utime;
    o.header.seq = m.pose.next_seq();
    fill_pose(s, o.pose);
    sent += m.emit(m.pose, now, sink);
  }

  if (due & kTf) {
    auto& t = m.tf.msg.transforms[0];
    t.header.utime = utime;
    t.header.seq = m.tf.next_seq();
    t.transform.translation.x = s.state[0];
    t.transform.translation.y = s.state[1];
    t.transform.translation.z = s.state[2];
    const Eigen::Quaterniond q = geometry::quaternion_from_rpy(s.state[3], s.state[4], s.state[5]);
    t.transform.rotation.x = q.x();
    t.transform.rotation.y = q.y();
    t.transform.rotation.z = q.z();
    t.transform.rotation.w = q.w();
    sent += m.emit(m.tf, now, sink);
  }

  if (due & kState) {
    auto& o = m.state.msg;
    o.header.utime = utime;
    o.header.seq = m.state.next_seq();
    o.initialized = s.initialized;
    for (int i = 0; i < kN; ++i) o.state[i] = s.state[i];
    for (int i = 0; i < kN * kN; ++i) o.covariance[i] = s.covariance[i];
    sent += m.emit(m.state, now, sink);
  }

  const WheelOdometrySnapshot& w = s.wheel_odometry;
  if (due & kWheelOdometry) {
    auto& o = m.wheel_odometry.msg;
    o.header.utime = ns_to_utime(w.stamp_ns);
    o.header.seq = m.wheel_odometry.next_seq();
    o.pose.pose.position.x = w.x;
    o.pose.pose.position.y = w.y;
    o.pose.pose.orientation.z = std::sin(0.5 * w.yaw);
    o.pose.pose.orientation.w = std::cos(0.5 * w.yaw);
    o.twist.twist.linear.x = w.vx;
    o.twist.twist.angular.z = w.vyaw;
    o.twist.covariance[0] = w.var_vx;
    o.twist.covariance[35] = w.var_vyaw;
    sent += m.emit(m.wheel_odometry, now, sink);
  }

  if (due & kDiagnostics) {
    auto& d = m.diagnostics.msg;
    // Diagnostics describe the process now, not the estimate.
    d.header.utime = ns_to_utime(now);
    d.header.seq = m.diagnostics.next_seq();
    d.loop.rate_hz = s.loop.rate_hz;
    d.loop.period_ns = s.loop.period_ns;
    d.loop.ticks = s.loop.ticks;
    d.loop.overruns = s.loop.overruns;
    d.loop.jitter_mean_ns = s.loop.jitter_mean_ns;
    d.loop.jitter_max_ns = s.loop.jitter_max_ns;
    d.loop.tick_duration_mean_ns = s.loop.tick_duration_mean_ns;
    d.loop.tick_duration_max_ns = s.loop.tick_duration_max_ns;
    d.loop.measurements_fused = s.loop.measurements_fused;
    d.loop.lagged_replays = s.loop.lagged_replays;
    d.unknown_channel_messages = s.unknown_channel_messages;
    d.set_pose_count = s.set_pose_count;
    d.set_pose_rejected = s.set_pose_rejected;
    d.set_pose_ignored = s.set_pose_ignored;
    for (int i = 0; i < m.num_sensors; ++i) {
      const SensorStats& in = s.sensors[i];
      auto& out = d.sensors[static_cast<std::size_t>(i)];
      out.last_stamp_utime = ns_to_utime(in.last_stamp_ns);
      out.rate_hz = in.rate_hz;
      out.received = in.received;
      out.accepted = in.accepted;
      out.rejected_mahalanobis = in.rejected_mahalanobis;
      out.rejected_invalid = in.rejected_invalid;
      out.rejected_stale = in.rejected_stale;
      out.rejected_overflow = in.rejected_overflow;
      out.rejected_rate = in.rejected_rate;
      out.rejected_oversize = in.rejected_oversize;
      out.decode_errors = in.decode_errors;
      out.yaw_conflicts = in.yaw_conflicts;
      out.timeouts = in.timeouts;
      out.timed_out = in.timed_out;
      // WARN compares with the previous message so that one bad burst does
      // not keep a sensor yellow for the rest of the run.
      const std::int64_t rejected = rejected_total(in);
      auto& previous = m.rejections_at_last_diagnostics[static_cast<std::size_t>(i)];
      if (in.received == 0) {
        out.level = rtfuse::sensor_status_t::STALE;
      } else if (in.timed_out) {
        out.level = rtfuse::sensor_status_t::ERROR;
      } else if (rejected != previous) {
        out.level = rtfuse::sensor_status_t::WARN;
      } else {
        out.level = rtfuse::sensor_status_t::OK;
      }
      previous = rejected;
    }
    for (int i = 0; i < m.num_devices && i < s.num_devices; ++i) {
      const DeviceStatus& in = s.devices[i];
      auto& out = d.devices[static_cast<std::size_t>(i)];
      out.level = static_cast<std::int8_t>(in.level);
      out.state.assign(in.state.c_str());
      out.message.assign(in.message.c_str(), in.message.size());
      const int n = in.num_values < out.num_values ? in.num_values : out.num_values;
      for (int k = 0; k < n; ++k) out.values[static_cast<std::size_t>(k)] = in.values[k];
    }
    sent += m.emit(m.diagnostics, now, sink);
  }
  return sent;
}

}  // namespace rtfuse
