#pragma once
// GPIO lines through libgpiod v1 (the API Jetson L4T images ship; v2 is not
// source compatible). A chip is named by path, name or number ("/dev/gpiochip0",
// "gpiochip0", "0", anything gpiod_chip_open_lookup accepts) or by label
// ("label:tegra-gpio"): labels survive probe-order changes between boots,
// chip numbers do not.
//
// Edge timestamps: the v1 character-device uAPI stamps line events with
// CLOCK_REALTIME on kernels before 5.7 (Jetson L4T 32.x runs 4.9) and with
// CLOCK_MONOTONIC from 5.7 on (kernel commit 26d060e47e25; the v2 uAPI is
// monotonic unless asked otherwise). Kernel version numbers lie on
// vendor kernels with backports, so each stamp is classified instead: it is
// taken as monotonic when it is closer to monotonic-now than to realtime-now,
// otherwise shifted by (realtime-now − monotonic-now). The two clocks are
// decades apart on any machine whose wall clock is set, and an edge is read
// microseconds to milliseconds after it happened, so the choice is
// unambiguous there. On a board whose wall clock was never set the two are
// close, and either reading is then off by at most that small offset.
// A step of the wall clock (NTP, settimeofday) between the edge and the read
// moves a realtime stamp by the same step: no userspace fix exists for that.
#include <gpiod.h>

#include <ctime>
#include <memory>
#include <string>

#include "hal/gpio.hpp"

namespace rtfuse::hal {

// Kernel edge stamp (either clock, see above) -> CLOCK_MONOTONIC ns, given
// both clocks read just after the event was read.
TimeNs gpio_event_stamp_to_monotonic(TimeNs stamp, TimeNs monotonic_now, TimeNs realtime_now) noexcept;

// The libgpiod calls a line makes after it is requested. Production uses
// libgpiod itself; tests substitute scripted ones (no gpiochip on CI machines).
struct GpiodOps {
  int (*event_wait)(gpiod_line* line, const timespec* timeout) = &gpiod_line_event_wait;
  int (*event_read)(gpiod_line* line, gpiod_line_event* event) = &gpiod_line_event_read;
  int (*set_value)(gpiod_line* line, int value) = &gpiod_line_set_value;
  int (*clock_gettime)(clockid_t clock, timespec* ts) = &::clock_gettime;
};

// Where opening a line failed; chooses the hint in the message.
enum class GpiodStage { kChip, kLine, kRequest };

// "gpio <chip> line <offset>: <what failed>: <strerror>; <fix>". Used by
// open() and directly testable for errnos this machine cannot produce.
std::string describe_gpiod_failure(const std::string& chip, unsigned offset, GpiodStage stage, int err);

class GpiodEdgeSource final : public GpioEdgeSource {
 public:
  static constexpr const char* kConsumer = "rtfuse";

  static std::unique_ptr<GpiodEdgeSource> open(const std::string& chip, unsigned offset, EdgeKind kind,
                                               std::string* error);
  // Takes ownership of chip (closed in the destructor; may be null in tests,
  // as may line when ops never dereference it).
  static std::unique_ptr<GpiodEdgeSource> adopt(gpiod_chip* chip, gpiod_line* line, std::string name,
                                                const GpiodOps& ops = GpiodOps{});

  ~GpiodEdgeSource() override;
  GpiodEdgeSource(const GpiodEdgeSource&) = delete;
  GpiodEdgeSource& operator=(const GpiodEdgeSource&) = delete;

  // A signal interrupting the wait resumes it with the time left, so an
  // edge-less timeout always means the full timeout passed.
  HalStatus wait_edge(TimeNs timeout_ns, GpioEdge* out) noexcept override;
  const char* last_error() const noexcept override { return last_error_; }

 private:
  GpiodEdgeSource(gpiod_chip* chip, gpiod_line* line, std::string name, const GpiodOps& ops);
  TimeNs clock_ns(clockid_t clock) const noexcept;

  gpiod_chip* chip_;
  gpiod_line* line_;
  std::string name_;
  GpiodOps ops_;
  char last_error_[256] = {};
};

class GpiodOutput final : public GpioOutput {
 public:
  static std::unique_ptr<GpiodOutput> open(const std::string& chip, unsigned offset, bool initial,
                                           std::string* error);
  static std::unique_ptr<GpiodOutput> adopt(gpiod_chip* chip, gpiod_line* line, std::string name,
                                            const GpiodOps& ops = GpiodOps{});

  ~GpiodOutput() override;
  GpiodOutput(const GpiodOutput&) = delete;
  GpiodOutput& operator=(const GpiodOutput&) = delete;

  HalStatus set(bool high) noexcept override;
  const char* last_error() const noexcept override { return last_error_; }

 private:
  GpiodOutput(gpiod_chip* chip, gpiod_line* line, std::string name, const GpiodOps& ops);

  gpiod_chip* chip_;
  gpiod_line* line_;
  std::string name_;
  GpiodOps ops_;
  char last_error_[256] = {};
};

}  // namespace rtfuse::hal
