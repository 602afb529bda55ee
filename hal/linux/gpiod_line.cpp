#include "hal/linux/gpiod_line.hpp"
#include "hal/linux/errno_text.hpp"

#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <utility>

namespace rtfuse::hal {
namespace {

constexpr const char kLabelPrefix[] = "label:";
constexpr std::size_t kLabelPrefixLen = sizeof kLabelPrefix - 1;

bool is_label(const std::string& chip) { return chip.compare(0, kLabelPrefixLen, kLabelPrefix) == 0; }

TimeNs abs_diff(TimeNs a, TimeNs b) noexcept { return a > b ? a - b : b - a; }

void format_into(char (&dst)[256], const char* fmt, ...) noexcept __attribute__((format(printf, 2, 3)));
void format_into(char (&dst)[256], const char* fmt, ...) noexcept {
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(dst, sizeof dst, fmt, ap);
  va_end(ap);
}

// Chip + line lookup shared by inputs and outputs; on success the caller owns
// the chip (closing it releases the line).
bool open_line(const std::string& chip, unsigned offset, gpiod_chip** chip_out, gpiod_line** line_out,
               std::string* error) {
  errno = 0;
  gpiod_chip* c = is_label(chip) ? gpiod_chip_open_by_label(chip.c_str() + kLabelPrefixLen)
                                 : gpiod_chip_open_lookup(chip.c_str());
  if (c == nullptr) {
    // Should a libgpiod path return null without setting errno, the most
    // likely cause is still "no such chip".
    const int err = errno != 0 ? errno : ENOENT;
    if (error) *error = describe_gpiod_failure(chip, offset, GpiodStage::kChip, err);
    return false;
  }
  gpiod_line* l = gpiod_chip_get_line(c, offset);
  if (l == nullptr) {
    const int err = errno != 0 ? errno : EINVAL;
    if (error) *error = describe_gpiod_failure(chip, offset, GpiodStage::kLine, err);
    gpiod_chip_close(c);
    return false;
  }
  *chip_out = c;
  *line_out = l;
  return true;
}

}  // namespace

TimeNs gpio_event_stamp_to_monotonic(TimeNs stamp, TimeNs monotonic_now, TimeNs realtime_now) noexcept {
  if (abs_diff(stamp, monotonic_now) <= abs_diff(stamp, realtime_now)) return stamp;
  return stamp - (realtime_now - monotonic_now);
}

std::string describe_gpiod_failure(const std::string& chip, unsigned offset, GpiodStage stage, int err) {
  const char* what = stage == GpiodStage::kChip   ? "cannot open chip"
                     : stage == GpiodStage::kLine ? "cannot get line"
                                                  : "cannot request line for consumer 'rtfuse'";
  std::string msg = "gpio " + chip + " line " + std::to_string(offset) + ": " + what + ": " +
                    ErrnoText(err).text;
  const bool label = is_label(chip);
  const std::string bare = label ? chip.substr(kLabelPrefixLen) : chip;
  switch (stage) {
    case GpiodStage::kChip:
      if (err == ENOENT) {
        msg += label ? "; no GPIO chip labelled '" + bare +
                           "': is the GPIO driver loaded? list chips and their labels with gpiodetect"
                     : "; no GPIO chip '" + bare + "': is the GPIO driver loaded? list chips with gpiodetect";
      } else if (err == EACCES || err == EPERM) {
        msg += "; add the user to group gpio or add a udev rule giving that group access to /dev/gpiochip*";
      } else if (err == ENOTTY || err == ENODEV) {
        msg += "; '" + bare + "' is not a GPIO character device: list chips with gpiodetect";
      }
      break;
    case GpiodStage::kLine:
      if (err == EINVAL) {
        msg += "; the chip has no line " + std::to_string(offset) + ": gpioinfo lists its lines";
      }
      break;
    case GpiodStage::kRequest:
      if (err == EBUSY) {
        msg += "; line in use by another consumer: gpioinfo shows who";
      } else if (err == EACCES || err == EPERM) {
        msg += "; add the user to group gpio or add a udev rule giving that group access to /dev/gpiochip*";
      } else if (err == ENXIO || err == EIO || err == EINVAL) {
        msg += "; the chip may not support this request on this line (edge events need an interrupt-capable line)";
      }
      break;
  }
  return msg;
}

// --- GpiodEdgeSource ---------------------------------------------------------

std::unique_ptr<GpiodEdgeSource> GpiodEdgeSource::open(const std::string& chip, unsigned offset, EdgeKind kind,
                                                       std::string* error) {
  gpiod_chip* c = nullptr;
  gpiod_line* l = nullptr;
  if (!open_line(chip, offset, &c, &l, error)) return nullptr;
  int rc = -1;
  switch (kind) {
    case EdgeKind::kRising: rc = gpiod_line_request_rising_edge_events(l, kConsumer); break;
    case EdgeKind::kFalling: rc = gpiod_line_request_falling_edge_events(l, kConsumer); break;
    case EdgeKind::kBoth: rc = gpiod_line_request_both_edges_events(l, kConsumer); break;
  }
  if (rc < 0) {
    const int err = errno;
    if (error) *error = describe_gpiod_failure(chip, offset, GpiodStage::kRequest, err);
    gpiod_chip_close(c);
    return nullptr;
  }
  return adopt(c, l, chip + " line " + std::to_string(offset));
}

std::unique_ptr<GpiodEdgeSource> GpiodEdgeSource::adopt(gpiod_chip* chip, gpiod_line* line, std::string name,
                                                        const GpiodOps& ops) {
  return std::unique_ptr<GpiodEdgeSource>(new GpiodEdgeSource(chip, line, std::move(name), ops));
}

GpiodEdgeSource::GpiodEdgeSource(gpiod_chip* chip, gpiod_line* line, std::string name, const GpiodOps& ops)
    : chip_(chip), line_(line), name_(std::move(name)), ops_(ops) {}

GpiodEdgeSource::~GpiodEdgeSource() {
  if (chip_ != nullptr) gpiod_chip_close(chip_);
}

TimeNs GpiodEdgeSource::clock_ns(clockid_t clock) const noexcept {
  timespec ts{};
  ops_.clock_gettime(clock, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * kNsPerSec + ts.tv_nsec;
}

HalStatus GpiodEdgeSource::wait_edge(TimeNs timeout_ns, GpioEdge* out) noexcept {
  if (out == nullptr) {
    format_into(last_error_, "gpio %s: wait_edge without an output edge", name_.c_str());
    return HalStatus::kIoError;
  }
  TimeNs remaining = timeout_ns > 0 ? timeout_ns : 0;
  const TimeNs deadline = clock_ns(CLOCK_MONOTONIC) + remaining;
  for (;;) {
    const timespec ts = ns_to_timespec(remaining);
    const int rc = ops_.event_wait(line_, &ts);
    if (rc > 0) break;
    if (rc == 0) {
      format_into(last_error_, "gpio %s: no edge within %lld ns", name_.c_str(), static_cast<long long>(timeout_ns));
      return HalStatus::kTimeout;
    }
    const int err = errno;
    if (err == EINTR) {
      const TimeNs left = deadline - clock_ns(CLOCK_MONOTONIC);
      remaining = left > 0 ? left : 0;
      continue;
    }
    format_into(last_error_, "gpio %s: waiting for an edge failed: %s", name_.c_str(),
                ErrnoText(err).text);
    return err == ENODEV ? HalStatus::kClosed : HalStatus::kIoError;
  }
  gpiod_line_event ev{};
  if (ops_.event_read(line_, &ev) < 0) {
    const int err = errno;
    format_into(last_error_, "gpio %s: reading the edge event failed: %s", name_.c_str(),
                ErrnoText(err).text);
    return err == ENODEV ? HalStatus::kClosed : HalStatus::kIoError;
  }
  bool rising = false;
  if (ev.event_type == GPIOD_LINE_EVENT_RISING_EDGE) {
    rising = true;
  } else if (ev.event_type != GPIOD_LINE_EVENT_FALLING_EDGE) {
    format_into(last_error_, "gpio %s: event of unknown type %d", name_.c_str(), ev.event_type);
    return HalStatus::kMalformed;
  }
  const TimeNs stamp = static_cast<TimeNs>(ev.ts.tv_sec) * kNsPerSec + ev.ts.tv_nsec;
  const TimeNs mono = clock_ns(CLOCK_MONOTONIC);
  const TimeNs real = clock_ns(CLOCK_REALTIME);
  out->stamp = gpio_event_stamp_to_monotonic(stamp, mono, real);
  out->rising = rising;
  return HalStatus::kOk;
}

// --- GpiodOutput -------------------------------------------------------------

std::unique_ptr<GpiodOutput> GpiodOutput::open(const std::string& chip, unsigned offset, bool initial,
                                               std::string* error) {
  gpiod_chip* c = nullptr;
  gpiod_line* l = nullptr;
  if (!open_line(chip, offset, &c, &l, error)) return nullptr;
  if (gpiod_line_request_output(l, GpiodEdgeSource::kConsumer, initial ? 1 : 0) < 0) {
    const int err = errno;
    if (error) *error = describe_gpiod_failure(chip, offset, GpiodStage::kRequest, err);
    gpiod_chip_close(c);
    return nullptr;
  }
  return adopt(c, l, chip + " line " + std::to_string(offset));
}

std::unique_ptr<GpiodOutput> GpiodOutput::adopt(gpiod_chip* chip, gpiod_line* line, std::string name,
                                                const GpiodOps& ops) {
  return std::unique_ptr<GpiodOutput>(new GpiodOutput(chip, line, std::move(name), ops));
}

GpiodOutput::GpiodOutput(gpiod_chip* chip, gpiod_line* line, std::string name, const GpiodOps& ops)
    : chip_(chip), line_(line), name_(std::move(name)), ops_(ops) {}

GpiodOutput::~GpiodOutput() {
  if (chip_ != nullptr) gpiod_chip_close(chip_);
}

HalStatus GpiodOutput::set(bool high) noexcept {
  if (ops_.set_value(line_, high ? 1 : 0) < 0) {
    const int err = errno;
    format_into(last_error_, "gpio %s: setting the line %s failed: %s", name_.c_str(), high ? "high" : "low",
                ErrnoText(err).text);
    return err == ENODEV ? HalStatus::kClosed : HalStatus::kIoError;
  }
  return HalStatus::kOk;
}

}  // namespace rtfuse::hal
