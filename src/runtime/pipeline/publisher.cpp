#include "runtime/pipeline/publisher.hpp"

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "geometry/rotation.hpp"
#include "runtime/devices/device_layout.hpp"
#include "runtime/devices/device_registry.hpp"
#include "navigation/stop_reason.hpp"
#include "rtfuse/diagnostics_t.hpp"
#include "rtfuse/filter_state_t.hpp"
#include "rtfuse/nav_status_t.hpp"
#include "rtfuse/navsat_fix_t.hpp"
#include "rtfuse/odometry_t.hpp"
#include "rtfuse/pose_with_covariance_stamped_t.hpp"
#include "rtfuse/tf_t.hpp"
#include "rtfuse/twist_stamped_t.hpp"
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

// One instance's estimate in a snapshot: the first's is the snapshot's own
// fields, the others' their InstanceSnapshot.
struct Estimate {
  std::int64_t stamp_ns;
  bool publishable;  // initialised, and anchored to the map when it must be
  const double* state;
  const double* covariance;
};

Estimate estimate_of(const Snapshot& s, int k) noexcept {
  if (k == 0) return {s.stamp_ns, s.initialized && !s.awaiting_fix, s.state, s.covariance};
  const InstanceSnapshot& in = s.instances[k];
  return {in.stamp_ns, in.initialized && !in.awaiting_fix, in.state, in.covariance};
}

void fill_pose(const Estimate& e, rtfuse::pose_with_covariance_t& p) noexcept {
  p.pose.position.x = e.state[0];
  p.pose.position.y = e.state[1];
  p.pose.position.z = e.state[2];
  const Eigen::Quaterniond q = geometry::quaternion_from_rpy(e.state[3], e.state[4], e.state[5]);
  p.pose.orientation.x = q.x();
  p.pose.orientation.y = q.y();
  p.pose.orientation.z = q.z();
  p.pose.orientation.w = q.w();
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) p.covariance[r * 6 + c] = e.covariance[r * kN + c];
}

void fill_twist(const Estimate& e, rtfuse::twist_with_covariance_t& t) noexcept {
  t.twist.linear.x = e.state[6];
  t.twist.linear.y = e.state[7];
  t.twist.linear.z = e.state[8];
  t.twist.angular.x = e.state[9];
  t.twist.angular.y = e.state[10];
  t.twist.angular.z = e.state[11];
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) t.covariance[r * 6 + c] = e.covariance[(6 + r) * kN + 6 + c];
}

// A filter instance's outputs.
struct InstanceOutputs {
  bool enabled = false;
  // tf carries map -> odom (a map instance chained to a local one) instead
  // of world -> base_link.
  bool tf_map_odom = false;
  Name odometry_channel, pose_channel, state_channel, fix_channel;
  Output<rtfuse::odometry_t> odometry;
  Output<rtfuse::pose_with_covariance_stamped_t> pose;
  Output<rtfuse::tf_t> tf;
  Output<rtfuse::filter_state_t> state;
  Output<rtfuse::navsat_fix_t> fix;
};

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

  int publish_instance(const Snapshot& s, int k, std::uint32_t bits, TimeNs now, MessageSink& sink) noexcept;

  PublishConfig cfg;  // owns the channel strings the outputs point into
  int num_sensors = 0;
  int num_devices = 0;
  int num_instances = 1;
  InstanceOutputs instances[kMaxInstances];
  Output<rtfuse::diagnostics_t> diagnostics;
  Output<rtfuse::odometry_t> wheel_odometry;  // raw dead reckoning from the encoders
  std::int64_t last_wheel_stamp = -1;
  Name wheel_channel;
  Output<rtfuse::twist_stamped_t> cmd_vel;
  Output<rtfuse::nav_status_t> nav_status;
  Name cmd_vel_channel, nav_status_channel;
  std::array<std::int64_t, kMaxSensors> rejections_at_last_diagnostics{};
  std::int64_t encode_failures = 0;
};

Publisher::Publisher(const RuntimeConfig& c) : impl_(std::make_unique<Impl>(c)) {
  Impl& m = *impl_;
  const std::string base = c.base_link_frame.c_str();
  m.num_instances = c.num_instances < 1 ? 1 : (c.num_instances > kMaxInstances ? kMaxInstances : c.num_instances);
  int local = -1;  // the instance map instances chain to (FusionCore's rule)
  for (int k = 0; k < m.num_instances && local < 0; ++k) {
    if (instance_world_frame(c, k) != c.map_frame) local = k;
  }
  for (int k = 0; k < m.num_instances; ++k) {
    InstanceOutputs& o = m.instances[k];
    const InstanceConfig& ic = c.instances[static_cast<std::size_t>(k)];
    const std::string world = instance_world_frame(c, k).c_str();
    o.enabled = true;
    o.tf_map_odom = world == c.map_frame.view() && local >= 0 && local != k;
    o.odometry_channel = k == 0 ? m.cfg.odometry_channel : ic.odometry_channel;
    o.pose_channel = k == 0 ? m.cfg.pose_channel : ic.pose_channel;
    o.state_channel = k == 0 ? m.cfg.state_channel : ic.state_channel;
    o.fix_channel = ic.filtered_fix_channel;

    o.odometry.channel = o.odometry_channel.c_str();
    o.odometry.schedule.set_rate(k == 0 ? m.cfg.odometry_rate_hz : ic.odometry_rate_hz);
    o.odometry.msg.header.frame_id = world;
    o.odometry.msg.child_frame_id = base;
    o.odometry.finalize();

    o.pose.channel = o.pose_channel.c_str();
    o.pose.schedule.set_rate(k == 0 ? m.cfg.pose_rate_hz : ic.pose_rate_hz);
    o.pose.msg.header.frame_id = world;
    o.pose.finalize();

    // Every instance's transform goes on the one tf channel, as every
    // robot_localization node publishes to /tf.
    o.tf.channel = m.cfg.tf_channel.c_str();
    o.tf.schedule.set_rate(m.cfg.publish_tf ? (k == 0 ? m.cfg.tf_rate_hz : ic.tf_rate_hz) : 0.0);
    o.tf.msg.num_transforms = 1;
    o.tf.msg.transforms.resize(1);
    o.tf.msg.transforms[0].header.frame_id = world;
    o.tf.msg.transforms[0].child_frame_id = o.tf_map_odom ? c.odom_frame.c_str() : base;
    o.tf.msg.transforms[0].transform.rotation.w = 1.0;
    o.tf.finalize();

    o.state.channel = o.state_channel.c_str();
    o.state.schedule.set_rate(k == 0 ? m.cfg.state_rate_hz : ic.state_rate_hz);
    o.state.msg.header.frame_id = world;
    o.state.msg.child_frame_id = base;
    o.state.finalize();

    bool has_navsat = false;
    for (int i = 0; i < c.num_sensors; ++i) {
      const SensorConfig& sc = c.sensors[static_cast<std::size_t>(i)];
      has_navsat |= sc.instance == k && sc.params.kind == est::SensorKind::kNavSatFix;
    }
    o.fix.channel = o.fix_channel.c_str();
    o.fix.schedule.set_rate(has_navsat ? ic.filtered_fix_rate_hz : 0.0);
    o.fix.msg.header.frame_id = world;
    // As navsat_transform_node reports its filtered fix.
    o.fix.msg.status = rtfuse::navsat_fix_t::STATUS_GBAS_FIX;
    o.fix.msg.service = rtfuse::navsat_fix_t::SERVICE_GPS;
    o.fix.msg.position_covariance_type = rtfuse::navsat_fix_t::COVARIANCE_TYPE_KNOWN;
    o.fix.finalize();
  }

  m.diagnostics.channel = m.cfg.diagnostics_channel.c_str();
  m.diagnostics.schedule.set_rate(m.cfg.diagnostics_rate_hz);
  const int n = c.num_sensors < 0 ? 0 : (c.num_sensors > kMaxSensors ? kMaxSensors : c.num_sensors);
  m.num_sensors = n;
  m.diagnostics.msg.num_sensors = n;
  m.diagnostics.msg.sensors.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    auto& st = m.diagnostics.msg.sensors[static_cast<std::size_t>(i)];
    st.name = qualified_sensor_name(c, i).c_str();
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
  m.wheel_odometry.schedule.set_rate(source_sensor(c, "wheel_odometry") >= 0 ? w.raw_rate_hz : 0.0);
  m.wheel_odometry.msg.header.frame_id = c.odom_frame.c_str();
  m.wheel_odometry.msg.child_frame_id = base;
  // Dead reckoning has no pose covariance worth the name: say "unknown" the
  // way robot_localization users read it, a huge variance.
  for (int i = 0; i < 6; ++i) m.wheel_odometry.msg.pose.covariance[i * 7] = 1e6;
  m.wheel_odometry.finalize();

  const NavigationSection& nav = c.hardware.navigation;
  m.cmd_vel_channel = nav.cmd_vel_channel;
  m.nav_status_channel = nav.status_channel;
  m.cmd_vel.channel = m.cmd_vel_channel.c_str();
  m.cmd_vel.msg.header.frame_id = base;
  m.cmd_vel.finalize();
  m.nav_status.channel = m.nav_status_channel.c_str();
  m.nav_status.msg.header.frame_id = c.world_frame.c_str();
  // Room for the longest texts, so assigning them never allocates.
  auto& st = m.nav_status.msg;
  st.goal_state.assign(16, ' ');
  st.goal_error.assign(sizeof(NavSnapshot::goal_error), ' ');
  st.stop_reason.assign(24, ' ');
  m.nav_status.finalize();
  st.goal_state = "none";
  st.goal_error.clear();
  st.stop_reason = "no_goal";
}

Publisher::~Publisher() = default;

int Publisher::Impl::publish_instance(const Snapshot& s, int k, std::uint32_t bits, TimeNs now,
                                      MessageSink& sink) noexcept {
  InstanceOutputs& io = instances[k];
  const Estimate e = estimate_of(s, k);
  const InstanceSnapshot& in = s.instances[k];
  int sent = 0;
  // The estimate's own time, not the publishing time: consumers interpolate
  // and look up transforms by it, as they would with robot_localization.
  const std::int64_t utime = ns_to_utime(e.stamp_ns);

  if (bits & kOdometry) {
    auto& o = io.odometry.msg;
    o.header.utime = utime;
    o.header.seq = io.odometry.next_seq();
    fill_pose(e, o.pose);
    fill_twist(e, o.twist);
    sent += emit(io.odometry, now, sink);
  }

  if (bits & kPose) {
    auto& o = io.pose.msg;
    o.header.utime = utime;
    o.header.seq = io.pose.next_seq();
    fill_pose(e, o.pose);
    sent += emit(io.pose, now, sink);
  }

  if (bits & kTf) {
    auto& t = io.tf.msg.transforms[0];
    t.header.utime = utime;
    t.header.seq = io.tf.next_seq();
    if (io.tf_map_odom) {
      t.transform.translation.x = in.map_odom_translation[0];
      t.transform.translation.y = in.map_odom_translation[1];
      t.transform.translation.z = in.map_odom_translation[2];
      t.transform.rotation.x = in.map_odom_rotation[0];
      t.transform.rotation.y = in.map_odom_rotation[1];
      t.transform.rotation.z = in.map_odom_rotation[2];
      t.transform.rotation.w = in.map_odom_rotation[3];
    } else {
      t.transform.translation.x = e.state[0];
      t.transform.translation.y = e.state[1];
      t.transform.translation.z = e.state[2];
      const Eigen::Quaterniond q = geometry::quaternion_from_rpy(e.state[3], e.state[4], e.state[5]);
      t.transform.rotation.x = q.x();
      t.transform.rotation.y = q.y();
      t.transform.rotation.z = q.z();
      t.transform.rotation.w = q.w();
    }
    sent += emit(io.tf, now, sink);
  }

  if (bits & kState) {
    auto& o = io.state.msg;
    o.header.utime = utime;
    o.header.seq = io.state.next_seq();
    o.initialized = true;
    for (int i = 0; i < kN; ++i) o.state[i] = e.state[i];
    for (int i = 0; i < kN * kN; ++i) o.covariance[i] = e.covariance[i];
    sent += emit(io.state, now, sink);
  }

  if (bits & kFilteredFix) {
    auto& o = io.fix.msg;
    o.header.utime = utime;
    o.header.seq = io.fix.next_seq();
    o.latitude = in.latitude_deg;
    o.longitude = in.longitude_deg;
    o.altitude = in.altitude_m;
    for (int i = 0; i < 9; ++i) o.position_covariance[i] = in.fix_covariance[i];
    sent += emit(io.fix, now, sink);
  }
  return sent;
}

std::int64_t Publisher::encode_failures() const { return impl_->encode_failures; }

std::uint32_t Publisher::schedule(const Snapshot& s, TimeNs now) noexcept {
  Impl& m = *impl_;
  std::uint32_t due = 0;
  const int instances = s.num_instances < m.num_instances ? s.num_instances : m.num_instances;
  for (int k = 0; k < instances; ++k) {
    InstanceOutputs& o = m.instances[k];
    const InstanceSnapshot& in = s.instances[k];
    if (!estimate_of(s, k).publishable) continue;
    std::uint32_t bits = 0;
    if (o.odometry.schedule.due(now)) bits |= kOdometry;
    if (o.pose.schedule.due(now)) bits |= kPose;
    // No map -> odom until both ends exist (nothing bogus before a fix).
    if ((!o.tf_map_odom || in.has_map_odom) && o.tf.schedule.due(now)) bits |= kTf;
    if (o.state.schedule.due(now)) bits |= kState;
    if (in.has_filtered_fix && o.fix.schedule.due(now)) bits |= kFilteredFix;
    due |= bits << (k * kInstanceShift);
  }
  const WheelOdometrySnapshot& w = s.wheel_odometry;
  if (w.valid && w.stamp_ns != m.last_wheel_stamp && m.wheel_odometry.schedule.due(now)) {
    m.last_wheel_stamp = w.stamp_ns;
    due |= kWheelOdometry;
  }
  if (m.diagnostics.schedule.due(now)) due |= kDiagnostics;
  if (s.nav.active && s.nav.command_due) due |= kNavigation;
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
  for (int k = 0; k < m.num_instances; ++k) {
    const std::uint32_t bits =
        (due >> (k * kInstanceShift)) & 0xffu & ~(kWheelOdometry | kDiagnostics | kNavigation);
    if (bits != 0) sent += m.publish_instance(s, k, bits, now, sink);
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

  if (due & kNavigation) {
    const NavSnapshot& n = s.nav;
    // Commands and status are stamped with the tick that computed them: a
    // base compares it with its clock to refuse a late command.
    const std::int64_t utime = ns_to_utime(s.tick_time_ns);
    if (n.send_command) {
      auto& c = m.cmd_vel.msg;
      c.header.utime = utime;
      c.header.seq = m.cmd_vel.next_seq();
      c.twist.linear.x = n.linear_mps;
      c.twist.angular.z = n.angular_rps;
      sent += m.emit(m.cmd_vel, now, sink);
    }
    auto& st = m.nav_status.msg;
    st.header.utime = utime;
    st.header.seq = m.nav_status.next_seq();
    st.goal_seq = n.goal_seq;
    st.goal_x = n.goal_x;
    st.goal_y = n.goal_y;
    st.goal_state.assign(to_string(n.goal_state));
    st.goal_error.assign(n.goal_error);
    st.linear_mps = n.linear_mps;
    st.angular_rps = n.angular_rps;
    st.stop_reason.assign(navigation::to_string(static_cast<navigation::StopReason>(n.stop_reason)));
    st.plan_seq = n.plan_seq;
    st.path_points = n.path_points;
    st.remaining_m = n.remaining_m;
    st.cross_track_m = n.cross_track_m;
    st.plans = n.plans;
    st.plan_failures = n.plan_failures;
    st.replans_blocked = n.replans_blocked;
    st.replans_off_path = n.replans_off_path;
    sent += m.emit(m.nav_status, now, sink);
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
