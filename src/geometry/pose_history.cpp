#include "geometry/pose_history.hpp"

#include <cstdint>

namespace rtfuse::geometry {

const char* to_string(PoseLookup l) noexcept {
  switch (l) {
    case PoseLookup::kOk: return "ok";
    case PoseLookup::kEmpty: return "no pose yet";
    case PoseLookup::kNotYet: return "after the newest pose";
    case PoseLookup::kTooOld: return "before the oldest pose kept";
  }
  return "unknown";
}

PoseHistory::PoseHistory(int capacity)
    : capacity_(capacity < 2 ? 2 : capacity), entries_(new Entry[static_cast<std::size_t>(capacity_)]) {}

const PoseHistory::Entry& PoseHistory::nth(int i) const noexcept { return entries_[(head_ + i) % capacity_]; }

TimeNs PoseHistory::newest_stamp() const noexcept { return size_ == 0 ? 0 : nth(size_ - 1).stamp; }
TimeNs PoseHistory::oldest_stamp() const noexcept { return size_ == 0 ? 0 : nth(0).stamp; }

bool PoseHistory::add(TimeNs stamp, const RigidTransform& pose, TimeNs known_at) noexcept {
  if (size_ > 0 && stamp <= newest_stamp()) return false;
  if (size_ == capacity_) {
    head_ = (head_ + 1) % capacity_;
    --size_;
  }
  Entry& e = entries_[(head_ + size_) % capacity_];
  e.stamp = stamp;
  e.known_at = known_at;
  e.pose = pose;
  ++size_;
  return true;
}

PoseLookup PoseHistory::at(TimeNs stamp, RigidTransform* out, TimeNs as_of) const noexcept {
  // The entries known by as_of: a prefix, known_at increasing.
  int known = size_;
  if (known > 0 && nth(known - 1).known_at > as_of) {
    int lo = 0, hi = known - 1;  // the first entry known after as_of
    while (lo < hi) {
      const int mid = (lo + hi) / 2;
      if (nth(mid).known_at > as_of) {
        hi = mid;
      } else {
        lo = mid + 1;
      }
    }
    known = lo;
  }
  if (known == 0) return size_ == 0 ? PoseLookup::kEmpty : (stamp < oldest_stamp() ? PoseLookup::kTooOld : PoseLookup::kNotYet);
  if (stamp > nth(known - 1).stamp) return PoseLookup::kNotYet;
  if (stamp < oldest_stamp()) return PoseLookup::kTooOld;
  // The first entry at or after stamp, by bisection over the ring's order.
  int lo = 0, hi = known - 1;
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (nth(mid).stamp < stamp) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  const Entry& b = nth(lo);
  if (b.stamp == stamp || lo == 0) {
    *out = b.pose;
    return PoseLookup::kOk;
  }
  const Entry& a = nth(lo - 1);
  const double s = static_cast<double>(stamp - a.stamp) / static_cast<double>(b.stamp - a.stamp);
  out->translation = a.pose.translation + s * (b.pose.translation - a.pose.translation);
  // The shorter way round: q and -q are one rotation.
  const double sign = a.pose.rotation.dot(b.pose.rotation) < 0.0 ? -1.0 : 1.0;
  Eigen::Vector4d q = (1.0 - s) * a.pose.rotation.coeffs() + (s * sign) * b.pose.rotation.coeffs();
  q /= q.norm();
  out->rotation.coeffs() = q;
  return PoseLookup::kOk;
}

}  // namespace rtfuse::geometry
