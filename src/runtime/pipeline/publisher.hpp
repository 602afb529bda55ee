#pragma once
// Turns the loop's Snapshot into the LCM outputs (per filter instance:
// odometry, pose, tf, full filter state, the filtered fix; and diagnostics)
// at their configured rates.
//
// Everything that allocates happens in the constructor: one generated message
// object per output with its strings already set, and one byte buffer each.
// poll() only overwrites numbers, encodes into those buffers and hands the
// bytes to a MessageSink (lcm_publish from the caller's buffer in the daemon,
// a capture in tests), so it may run on any thread that must not allocate.
#include <cstdint>
#include <memory>

#include "core/time.hpp"
#include "runtime/config/config.hpp"
#include "runtime/fusion/snapshot.hpp"
#include "transport/message_sink.hpp"

namespace rtfuse {

using MessageSink = transport::MessageSink;

class Publisher {
 public:
  explicit Publisher(const RuntimeConfig& cfg);
  ~Publisher();
  Publisher(const Publisher&) = delete;
  Publisher& operator=(const Publisher&) = delete;

  enum OutputBit : std::uint32_t {
    kOdometry = 1u << 0,
    kPose = 1u << 1,
    kTf = 1u << 2,
    kState = 1u << 3,
    kWheelOdometry = 1u << 4,
    kDiagnostics = 1u << 5,
    kFilteredFix = 1u << 6,
    // The navigator's status and, when it sends one, its command
    // (Snapshot::nav), on the ticks it computed them.
    kNavigation = 1u << 7,
  };
  // Instance k's outputs (odometry, pose, tf, state, filtered fix) are the
  // first instance's bits shifted by k * kInstanceShift; wheel odometry,
  // diagnostics and navigation are the process's, at their own bits.
  static constexpr int kInstanceShift = 8;
  static_assert(kMaxInstances * kInstanceShift <= 32, "the due mask is 32 bits");
  // Which outputs are due at `now` for this snapshot (all of them on the
  // first call), consuming their slots. State outputs wait for
  // s.initialized; diagnostics do not. The daemon's loop calls it on tick
  // time, so the set of published snapshots is a function of the ticks
  // alone and a replay reproduces it exactly.
  std::uint32_t schedule(const Snapshot& s, TimeNs now) noexcept;
  // Encodes and hands to the sink the outputs in `due`; returns how many
  // messages the sink accepted. `now` stamps diagnostics only.
  int publish(const Snapshot& s, std::uint32_t due, TimeNs now, MessageSink& sink) noexcept;
  // schedule() then publish(), on one thread (replay, tests).
  int poll(const Snapshot& s, TimeNs now, MessageSink& sink) noexcept;

  // Messages that did not fit their buffer (never expected: sizes are fixed).
  std::int64_t encode_failures() const;

 private:
  struct Impl;  // the lcm-gen types stay out of this header
  std::unique_ptr<Impl> impl_;
};

}  // namespace rtfuse
