#pragma once
// The recent poses of one frame, stamped, and the pose at any stamp between
// them: what a consumer that works later than the loop (the mapper) needs
// to place a measurement taken at a past instant. Positions are linearly
// interpolated and rotations normalised-linearly (nlerp): over the few
// milliseconds between two estimates it equals slerp to far below a
// voxel, and it needs no transcendental function, so every machine gives
// the same bits.
//
// Each pose also carries when it became known (the loop tick that
// computed it), so a lookup can be made "as of" an instant: a consumer that
// runs late gets the answer it would have got on time, which is what makes
// a replay stepped in lockstep agree with a live thread bit for bit.
//
// A fixed ring, allocated in the constructor; add() and at() allocate
// nothing. One writer and one reader at a time (the caller's thread).
#include <cstdint>
#include <memory>

#include "core/time.hpp"
#include "geometry/rigid_transform.hpp"

namespace rtfuse::geometry {

enum class PoseLookup : std::uint8_t {
  kOk,
  kEmpty,    // nothing added yet
  kNotYet,   // after the newest pose: wait for more
  kTooOld,   // before the oldest pose kept: it is gone
};

const char* to_string(PoseLookup l) noexcept;

class PoseHistory {
 public:
  explicit PoseHistory(int capacity);

  // A pose at stamp, known from known_at on; stamps and known_at must
  // increase (an equal or older stamp is ignored and false returned: the
  // estimate did not move on).
  bool add(TimeNs stamp, const RigidTransform& pose, TimeNs known_at) noexcept;
  // The pose at stamp between the two poses that bracket it, of those known
  // by as_of.
  PoseLookup at(TimeNs stamp, RigidTransform* out, TimeNs as_of = kForever) const noexcept;

  static constexpr TimeNs kForever = INT64_MAX;

  int size() const noexcept { return size_; }
  int capacity() const noexcept { return capacity_; }
  TimeNs newest_stamp() const noexcept;
  TimeNs oldest_stamp() const noexcept;
  void clear() noexcept { size_ = 0; }

 private:
  struct Entry {
    TimeNs stamp = 0;
    TimeNs known_at = 0;
    RigidTransform pose;
  };
  const Entry& nth(int i) const noexcept;  // 0: oldest

  int capacity_;
  std::unique_ptr<Entry[]> entries_;
  int head_ = 0;  // index of the oldest
  int size_ = 0;
};

}  // namespace rtfuse::geometry
