#include "transport/nav_messages.hpp"

#include <cmath>
#include <exception>
#include <limits>

#include "rtfuse/nav_stop_t.hpp"
#include "rtfuse/path_t.hpp"
#include "rtfuse/pose_stamped_t.hpp"
#include "transport/encode_buffer.hpp"
#include "transport/lcm_wire.hpp"

namespace rtfuse::transport {
namespace {

// Below this a goal's quaternion says "no heading": ROS tools send all
// zeros when a user clicks a point without dragging a direction.
constexpr double kNoHeadingNorm = 1e-9;

// fingerprint, header.utime, header.seq, then header.frame_id; a stop has
// its reason after the boolean.
constexpr int kFrameIdAt = 8 + 8 + 4;

template <class Msg>
DecodeResult decode_nav_bytes(Msg& msg, const void* data, int size, int* after_frame) noexcept {
  if (data == nullptr || size < 8) return DecodeResult::kMalformed;
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  if (wire::load_i64(bytes) != Msg::getHash()) return DecodeResult::kWrongType;
  const int after = wire::after_string(bytes, size, kFrameIdAt, std::numeric_limits<std::int32_t>::max());
  if (after < 0) return DecodeResult::kMalformed;
  *after_frame = after;
  try {
    if (msg.decode(data, 0, size) < 0) return DecodeResult::kMalformed;
  } catch (const std::exception&) {
    return DecodeResult::kMalformed;
  }
  if (!utime_in_range(msg.header.utime)) return DecodeResult::kMalformed;
  return DecodeResult::kOk;
}

// The heading of the segment a -> b; 0 for a point on itself.
double segment_yaw(const PathPoint2& a, const PathPoint2& b) noexcept {
  const double dx = b.x - a.x;
  const double dy = b.y - a.y;
  return dx == 0.0 && dy == 0.0 ? 0.0 : std::atan2(dy, dx);
}

}  // namespace

struct NavInputDecoder::Impl {
  rtfuse::pose_stamped_t goal{};
  rtfuse::nav_stop_t stop{};
};

NavInputDecoder::NavInputDecoder() : impl_(std::make_unique<Impl>()) {
  impl_->goal.header.frame_id.reserve(kStringReserve);
  impl_->stop.header.frame_id.reserve(kStringReserve);
  impl_->stop.reason.reserve(kStringReserve);
}
NavInputDecoder::~NavInputDecoder() = default;

DecodeResult NavInputDecoder::decode_goal(const void* data, int size, NavGoal* out) noexcept {
  rtfuse::pose_stamped_t& m = impl_->goal;
  int after = 0;
  const DecodeResult r = decode_nav_bytes(m, data, size, &after);
  if (r != DecodeResult::kOk) return r;
  const auto& p = m.pose.position;
  const auto& q = m.pose.orientation;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(q.x) ||
      !std::isfinite(q.y) || !std::isfinite(q.z) || !std::isfinite(q.w)) {
    return DecodeResult::kNonFinite;
  }
  if (m.header.frame_id.empty()) return DecodeResult::kUnknownFrame;
  const double norm2 = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
  NavGoal g;
  g.stamp = utime_to_ns(m.header.utime);
  g.x = p.x;
  g.y = p.y;
  g.has_yaw = norm2 > kNoHeadingNorm;
  if (g.has_yaw) {
    // The yaw of the rotation (ZYX), unchanged by the quaternion's scale.
    g.yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), q.w * q.w + q.x * q.x - q.y * q.y - q.z * q.z);
    if (!std::isfinite(g.yaw)) return DecodeResult::kNonFinite;
  }
  *out = g;
  return DecodeResult::kOk;
}

const std::string& NavInputDecoder::goal_frame() const noexcept { return impl_->goal.header.frame_id; }

DecodeResult NavInputDecoder::decode_stop(const void* data, int size, NavStop* out) noexcept {
  rtfuse::nav_stop_t& m = impl_->stop;
  int after = 0;
  DecodeResult r = decode_nav_bytes(m, data, size, &after);
  if (r == DecodeResult::kOk) {
    // The reason's string follows the one-byte boolean: check it too before
    // trusting lcm-gen's copy (decode_nav_bytes has already decoded, but a
    // reason with an embedded NUL would re-encode shorter).
    const auto* bytes = static_cast<const std::uint8_t*>(data);
    if (wire::after_string(bytes, size, after + 1, std::numeric_limits<std::int32_t>::max()) < 0) {
      r = DecodeResult::kMalformed;
    }
  }
  if (r != DecodeResult::kOk) return r;
  out->stamp = utime_to_ns(m.header.utime);
  out->stop = m.stop;
  return DecodeResult::kOk;
}

const std::string& NavInputDecoder::stop_reason() const noexcept { return impl_->stop.reason; }

struct PathEncoder::Impl {
  rtfuse::path_t msg{};
  std::unique_ptr<std::uint8_t[]> bytes;
  int capacity = 0;
  int max_points = 0;
  std::uint32_t seq = 0;
  std::int64_t failures = 0;
};

PathEncoder::PathEncoder(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
PathEncoder::~PathEncoder() = default;

std::unique_ptr<PathEncoder> PathEncoder::create(int max_points, const std::string& frame_id, std::string* error) {
  // 56 bytes a pose: a million points is 56 MB, far past any grid path.
  constexpr int kMaxPoints = 1 << 20;
  if (max_points <= 0 || max_points > kMaxPoints) {
    if (error != nullptr) {
      *error = "path: " + std::to_string(max_points) + " points; a path holds 1 to " + std::to_string(kMaxPoints);
    }
    return nullptr;
  }
  auto impl = std::make_unique<Impl>();
  impl->max_points = max_points;
  impl->msg.header.frame_id = frame_id;
  impl->msg.poses.assign(static_cast<std::size_t>(max_points), rtfuse::pose_t{});
  impl->msg.num_poses = max_points;
  impl->capacity = impl->msg.getEncodedSize();
  impl->bytes.reset(new std::uint8_t[static_cast<std::size_t>(impl->capacity)]());
  // Once here, so lcm-gen's lazily computed hash is not computed while publishing.
  impl->msg.encode(impl->bytes.get(), 0, impl->capacity);
  return std::unique_ptr<PathEncoder>(new PathEncoder(std::move(impl)));
}

EncodedMessage PathEncoder::encode(const PathPoint2* points, int count, std::int32_t goal_seq, double cost,
                                   TimeNs stamp) noexcept {
  Impl& m = *impl_;
  bool ok = count >= 0 && count <= m.max_points && (points != nullptr || count == 0) && std::isfinite(cost);
  for (int i = 0; ok && i < count; ++i) ok = std::isfinite(points[i].x) && std::isfinite(points[i].y);
  if (!ok) {
    ++m.failures;
    return EncodedMessage{};
  }
  double length = 0.0;
  for (int i = 0; i < count; ++i) {
    rtfuse::pose_t& p = m.msg.poses[static_cast<std::size_t>(i)];
    p.position.x = points[i].x;
    p.position.y = points[i].y;
    p.position.z = 0.0;
    const double yaw = count < 2 ? 0.0
                       : i + 1 < count ? segment_yaw(points[i], points[i + 1])
                                       : segment_yaw(points[i - 1], points[i]);
    p.orientation.x = 0.0;
    p.orientation.y = 0.0;
    p.orientation.z = std::sin(0.5 * yaw);
    p.orientation.w = std::cos(0.5 * yaw);
    if (i > 0) {
      const double dx = points[i].x - points[i - 1].x;
      const double dy = points[i].y - points[i - 1].y;
      length += std::sqrt(dx * dx + dy * dy);
    }
  }
  m.msg.header.utime = ns_to_utime(stamp);
  m.msg.header.seq = static_cast<std::int32_t>(m.seq++);
  m.msg.goal_seq = goal_seq;
  m.msg.cost = cost;
  m.msg.length_m = length;
  m.msg.num_poses = count;
  const int size = encode_into(m.msg, m.bytes.get(), m.capacity);
  if (size <= 0) {
    ++m.failures;
    return EncodedMessage{};
  }
  return EncodedMessage{m.bytes.get(), size};
}

std::int64_t PathEncoder::encode_failures() const noexcept { return impl_->failures; }

}  // namespace rtfuse::transport
