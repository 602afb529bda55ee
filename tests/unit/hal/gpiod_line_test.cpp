// libgpiod v1 backend: the real open failures this machine can produce (no
// gpiochip at all), the messages for the ones it cannot, the kernel-stamp
// clock conversion, and wait_edge/set through scripted libgpiod calls.
#include "hal/linux/gpiod_line.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <string>

#include "support/alloc_counter.hpp"

namespace rtfuse::hal {
namespace gpiod_line_test {

constexpr TimeNs kMs = 1'000'000;

bool gpiochip0_exists() { return ::access("/dev/gpiochip0", F_OK) == 0; }

// --- open: real failures -------------------------------------------------------

TEST(GpiodOpen, EdgeSourceOnMissingChipNamesChipAndGpiodetect) {
  if (gpiochip0_exists()) GTEST_SKIP() << "this machine has /dev/gpiochip0";
  std::string error;
  auto src = GpiodEdgeSource::open("gpiochip0", 17, EdgeKind::kRising, &error);
  EXPECT_EQ(src, nullptr);
  EXPECT_EQ(error,
            "gpio gpiochip0 line 17: cannot open chip: No such file or directory; no GPIO chip 'gpiochip0': is the "
            "GPIO driver loaded? list chips with gpiodetect");
}

TEST(GpiodOpen, OutputOnMissingChipPathFails) {
  if (gpiochip0_exists()) GTEST_SKIP() << "this machine has /dev/gpiochip0";
  std::string error;
  auto out = GpiodOutput::open("/dev/gpiochip0", 3, true, &error);
  EXPECT_EQ(out, nullptr);
  EXPECT_EQ(error,
            "gpio /dev/gpiochip0 line 3: cannot open chip: No such file or directory; no GPIO chip '/dev/gpiochip0': "
            "is the GPIO driver loaded? list chips with gpiodetect");
}

TEST(GpiodOpen, MissingLabelSaysLabelled) {
  std::string error;
  auto src = GpiodEdgeSource::open("label:rtfuse-no-such-label", 5, EdgeKind::kBoth, &error);
  EXPECT_EQ(src, nullptr);
  EXPECT_EQ(error,
            "gpio label:rtfuse-no-such-label line 5: cannot open chip: No such file or directory; no GPIO chip "
            "labelled 'rtfuse-no-such-label': is the GPIO driver loaded? list chips and their labels with gpiodetect");
}

TEST(GpiodOpen, NonGpioDeviceIsRejected) {
  std::string error;
  auto out = GpiodOutput::open("/dev/null", 0, false, &error);
  EXPECT_EQ(out, nullptr);
  EXPECT_EQ(error,
            "gpio /dev/null line 0: cannot open chip: Inappropriate ioctl for device; '/dev/null' is not a GPIO "
            "character device: list chips with gpiodetect");
}

// --- messages for errnos this machine cannot produce ----------------------------

TEST(GpiodMessages, BusyLineSaysWhoToAsk) {
  EXPECT_EQ(describe_gpiod_failure("gpiochip0", 12, GpiodStage::kRequest, EBUSY),
            "gpio gpiochip0 line 12: cannot request line for consumer 'rtfuse': Device or resource busy; line in use "
            "by another consumer: gpioinfo shows who");
}

TEST(GpiodMessages, OffsetBeyondChip) {
  EXPECT_EQ(describe_gpiod_failure("label:tegra-gpio", 300, GpiodStage::kLine, EINVAL),
            "gpio label:tegra-gpio line 300: cannot get line: Invalid argument; the chip has no line 300: gpioinfo "
            "lists its lines");
}

TEST(GpiodMessages, PermissionDenied) {
  EXPECT_EQ(describe_gpiod_failure("gpiochip1", 0, GpiodStage::kChip, EACCES),
            "gpio gpiochip1 line 0: cannot open chip: Permission denied; add the user to group gpio or add a udev "
            "rule giving that group access to /dev/gpiochip*");
}

// --- kernel stamp -> CLOCK_MONOTONIC ------------------------------------------------

// A machine up for 3 days whose wall clock is set (2024).
constexpr TimeNs kMonoNow = 3 * 86'400 * 1'000'000'000LL + 123'456'789;
constexpr TimeNs kRealNow = 1'717'000'000'000'000'000LL + 987'654'321;

TEST(GpioStampConversion, MonotonicStampKept) {
  EXPECT_EQ(gpio_event_stamp_to_monotonic(kMonoNow - 250'000, kMonoNow, kRealNow), kMonoNow - 250'000);
  EXPECT_EQ(gpio_event_stamp_to_monotonic(kMonoNow, kMonoNow, kRealNow), kMonoNow);
  // Old edges (a backlog read late) are still monotonic.
  EXPECT_EQ(gpio_event_stamp_to_monotonic(kMonoNow - 5000 * kMs, kMonoNow, kRealNow), kMonoNow - 5000 * kMs);
}

TEST(GpioStampConversion, RealtimeStampConvertedByTheClockOffset) {
  // Pre-5.7 kernels: the same edge 250 us ago, stamped on the wall clock.
  EXPECT_EQ(gpio_event_stamp_to_monotonic(kRealNow - 250'000, kMonoNow, kRealNow), kMonoNow - 250'000);
  EXPECT_EQ(gpio_event_stamp_to_monotonic(kRealNow, kMonoNow, kRealNow), kMonoNow);
  EXPECT_EQ(gpio_event_stamp_to_monotonic(kRealNow - 5000 * kMs, kMonoNow, kRealNow), kMonoNow - 5000 * kMs);
}

TEST(GpioStampConversion, UnsetWallClockCloseToMonotonic) {
  // Wall clock never set: realtime is 1970 + a little more than uptime.
  const TimeNs mono = 100'000 * kMs;
  const TimeNs real = mono + 2'000 * kMs;
  EXPECT_EQ(gpio_event_stamp_to_monotonic(mono - kMs, mono, real), mono - kMs);
  EXPECT_EQ(gpio_event_stamp_to_monotonic(real - kMs, mono, real), mono - kMs);
  // Exactly between the two: kept as monotonic (the clock of current kernels).
  EXPECT_EQ(gpio_event_stamp_to_monotonic(mono + 1'000 * kMs, mono, real), mono + 1'000 * kMs);
}

// --- wait_edge / set through scripted libgpiod calls ----------------------------------

namespace fake {
struct WaitStep {
  int rc;               // return of gpiod_line_event_wait
  int err;              // errno when rc < 0
  TimeNs advance_mono;  // the monotonic clock moves by this during the wait
};
constexpr int kMax = 16;
WaitStep waits[kMax];
int nwaits = 0;
int wait_calls = 0;
timespec wait_timeouts[kMax];
gpiod_line* seen_line = nullptr;

int read_rc = 0;
int read_err = 0;
int read_calls = 0;
gpiod_line_event event{};

TimeNs mono = kMonoNow;
TimeNs real = kRealNow;

int set_rc = 0;
int set_err = 0;
int set_values[kMax];
int set_calls = 0;

void reset() {
  nwaits = 0;
  wait_calls = 0;
  seen_line = nullptr;
  read_rc = 0;
  read_err = 0;
  read_calls = 0;
  event = gpiod_line_event{};
  mono = kMonoNow;
  real = kRealNow;
  set_rc = 0;
  set_err = 0;
  set_calls = 0;
}

timespec to_ts(TimeNs t) { return ns_to_timespec(t); }

int event_wait(gpiod_line* line, const timespec* timeout) {
  seen_line = line;
  const int i = wait_calls < kMax ? wait_calls : kMax - 1;
  wait_timeouts[i] = *timeout;
  ++wait_calls;
  const WaitStep s = i < nwaits ? waits[i] : WaitStep{1, 0, 0};
  mono += s.advance_mono;
  real += s.advance_mono;
  if (s.rc < 0) errno = s.err;
  return s.rc;
}

int event_read(gpiod_line*, gpiod_line_event* ev) {
  ++read_calls;
  if (read_rc < 0) {
    errno = read_err;
    return -1;
  }
  *ev = event;
  return 0;
}

int set_value(gpiod_line*, int value) {
  set_values[set_calls < kMax ? set_calls : kMax - 1] = value;
  ++set_calls;
  if (set_rc < 0) errno = set_err;
  return set_rc;
}

int clock_gettime(clockid_t clock, timespec* ts) {
  *ts = to_ts(clock == CLOCK_MONOTONIC ? mono : real);
  return 0;
}

GpiodOps ops() {
  GpiodOps o;
  o.event_wait = &event_wait;
  o.event_read = &event_read;
  o.set_value = &set_value;
  o.clock_gettime = &clock_gettime;
  return o;
}
}  // namespace fake

// Identity only: the fakes never dereference it.
gpiod_line* dummy_line() {
  static char storage;
  return reinterpret_cast<gpiod_line*>(&storage);
}

class GpiodEdgeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    fake::reset();
    src_ = GpiodEdgeSource::adopt(nullptr, dummy_line(), "gpiochip0 line 17", fake::ops());
  }
  std::unique_ptr<GpiodEdgeSource> src_;
};

TEST_F(GpiodEdgeTest, RisingEdgeWithMonotonicStamp) {
  fake::event.event_type = GPIOD_LINE_EVENT_RISING_EDGE;
  fake::event.ts = fake::to_ts(kMonoNow - 300'000);
  GpioEdge e;
  ASSERT_EQ(src_->wait_edge(5 * kMs, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, kMonoNow - 300'000);
  EXPECT_TRUE(e.rising);
  EXPECT_EQ(fake::seen_line, dummy_line());
  ASSERT_EQ(fake::wait_calls, 1);
  EXPECT_EQ(fake::wait_timeouts[0].tv_sec, 0);
  EXPECT_EQ(fake::wait_timeouts[0].tv_nsec, 5'000'000);
  EXPECT_EQ(fake::read_calls, 1);
}

TEST_F(GpiodEdgeTest, FallingEdgeWithRealtimeStampIsConverted) {
  fake::event.event_type = GPIOD_LINE_EVENT_FALLING_EDGE;
  fake::event.ts = fake::to_ts(kRealNow - 40'000);
  GpioEdge e;
  ASSERT_EQ(src_->wait_edge(kMs, &e), HalStatus::kOk);
  EXPECT_EQ(e.stamp, kMonoNow - 40'000);
  EXPECT_FALSE(e.rising);
}

TEST_F(GpiodEdgeTest, LongTimeoutSplitsIntoSecondsAndNanoseconds) {
  fake::event.event_type = GPIOD_LINE_EVENT_RISING_EDGE;
  fake::event.ts = fake::to_ts(kMonoNow);
  GpioEdge e;
  ASSERT_EQ(src_->wait_edge(2'500 * kMs, &e), HalStatus::kOk);
  EXPECT_EQ(fake::wait_timeouts[0].tv_sec, 2);
  EXPECT_EQ(fake::wait_timeouts[0].tv_nsec, 500'000'000);
}

TEST_F(GpiodEdgeTest, TimeoutReadsNothingAndLeavesEdgeAlone) {
  fake::waits[0] = {0, 0, 3 * kMs};
  fake::nwaits = 1;
  GpioEdge e;
  e.stamp = 42;
  EXPECT_EQ(src_->wait_edge(3 * kMs, &e), HalStatus::kTimeout);
  EXPECT_EQ(fake::read_calls, 0);
  EXPECT_EQ(e.stamp, 42);
  EXPECT_STREQ(src_->last_error(), "gpio gpiochip0 line 17: no edge within 3000000 ns");
}

TEST_F(GpiodEdgeTest, ZeroAndNegativeTimeoutsPoll) {
  fake::waits[0] = {0, 0, 0};
  fake::waits[1] = {0, 0, 0};
  fake::nwaits = 2;
  GpioEdge e;
  EXPECT_EQ(src_->wait_edge(0, &e), HalStatus::kTimeout);
  EXPECT_EQ(src_->wait_edge(-5, &e), HalStatus::kTimeout);
  ASSERT_EQ(fake::wait_calls, 2);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(fake::wait_timeouts[i].tv_sec, 0);
    EXPECT_EQ(fake::wait_timeouts[i].tv_nsec, 0);
  }
}

TEST_F(GpiodEdgeTest, SignalResumesWaitWithTheTimeLeft) {
  fake::waits[0] = {-1, EINTR, 2 * kMs};
  fake::waits[1] = {-1, EINTR, 2'500'000};
  fake::waits[2] = {1, 0, 0};
  fake::nwaits = 3;
  fake::event.event_type = GPIOD_LINE_EVENT_RISING_EDGE;
  fake::event.ts = fake::to_ts(kMonoNow + 4 * kMs);
  GpioEdge e;
  ASSERT_EQ(src_->wait_edge(5 * kMs, &e), HalStatus::kOk);
  ASSERT_EQ(fake::wait_calls, 3);
  EXPECT_EQ(fake::wait_timeouts[0].tv_nsec, 5'000'000);
  EXPECT_EQ(fake::wait_timeouts[1].tv_nsec, 3'000'000);
  EXPECT_EQ(fake::wait_timeouts[2].tv_nsec, 500'000);
  EXPECT_EQ(e.stamp, kMonoNow + 4 * kMs);
}

TEST_F(GpiodEdgeTest, SignalPastTheDeadlineEndsInAPollThenTimeout) {
  fake::waits[0] = {-1, EINTR, 7 * kMs};
  fake::waits[1] = {0, 0, 0};
  fake::nwaits = 2;
  GpioEdge e;
  EXPECT_EQ(src_->wait_edge(5 * kMs, &e), HalStatus::kTimeout);
  ASSERT_EQ(fake::wait_calls, 2);
  EXPECT_EQ(fake::wait_timeouts[1].tv_sec, 0);
  EXPECT_EQ(fake::wait_timeouts[1].tv_nsec, 0);
}

TEST_F(GpiodEdgeTest, WaitFailureMapsErrno) {
  fake::waits[0] = {-1, ENODEV, 0};
  fake::waits[1] = {-1, EBADF, 0};
  fake::nwaits = 2;
  GpioEdge e;
  EXPECT_EQ(src_->wait_edge(kMs, &e), HalStatus::kClosed);
  EXPECT_STREQ(src_->last_error(), "gpio gpiochip0 line 17: waiting for an edge failed: No such device");
  EXPECT_EQ(src_->wait_edge(kMs, &e), HalStatus::kIoError);
  EXPECT_STREQ(src_->last_error(), "gpio gpiochip0 line 17: waiting for an edge failed: Bad file descriptor");
  EXPECT_EQ(fake::read_calls, 0);
}

TEST_F(GpiodEdgeTest, ReadFailureIsAnIoError) {
  fake::read_rc = -1;
  fake::read_err = EIO;
  GpioEdge e;
  e.stamp = 7;
  EXPECT_EQ(src_->wait_edge(kMs, &e), HalStatus::kIoError);
  EXPECT_EQ(e.stamp, 7);
  EXPECT_STREQ(src_->last_error(), "gpio gpiochip0 line 17: reading the edge event failed: Input/output error");
}

TEST_F(GpiodEdgeTest, UnknownEventTypeIsMalformed) {
  fake::event.event_type = 9;
  fake::event.ts = fake::to_ts(kMonoNow);
  GpioEdge e;
  e.stamp = 7;
  EXPECT_EQ(src_->wait_edge(kMs, &e), HalStatus::kMalformed);
  EXPECT_EQ(e.stamp, 7);
  EXPECT_STREQ(src_->last_error(), "gpio gpiochip0 line 17: event of unknown type 9");
}

TEST_F(GpiodEdgeTest, SteadyStateWaitDoesNotAllocate) {
  fake::event.event_type = GPIOD_LINE_EVENT_RISING_EDGE;
  fake::event.ts = fake::to_ts(kRealNow);
  GpioEdge e;
  ASSERT_EQ(src_->wait_edge(kMs, &e), HalStatus::kOk);  // warm-up
  fake::waits[0] = {-1, EINTR, 0};
  fake::waits[1] = {0, 0, 0};
  fake::waits[2] = {-1, EIO, 0};
  fake::nwaits = 3;
  fake::wait_calls = 0;
  std::size_t allocations = 0;
  {
    rtfuse::test::AllocScope scope;
    for (int i = 0; i < 200; ++i) (void)src_->wait_edge(kMs, &e);
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(e.stamp, kMonoNow);
}

TEST(GpiodOutputTest, SetPassesLevels) {
  fake::reset();
  auto out = GpiodOutput::adopt(nullptr, dummy_line(), "gpiochip0 line 3", fake::ops());
  EXPECT_EQ(out->set(true), HalStatus::kOk);
  EXPECT_EQ(out->set(false), HalStatus::kOk);
  EXPECT_EQ(out->set(true), HalStatus::kOk);
  ASSERT_EQ(fake::set_calls, 3);
  EXPECT_EQ(fake::set_values[0], 1);
  EXPECT_EQ(fake::set_values[1], 0);
  EXPECT_EQ(fake::set_values[2], 1);
}

TEST(GpiodOutputTest, SetFailureMapsErrnoAndDoesNotAllocate) {
  fake::reset();
  auto out = GpiodOutput::adopt(nullptr, dummy_line(), "gpiochip0 line 3", fake::ops());
  fake::set_rc = -1;
  fake::set_err = EPERM;
  EXPECT_EQ(out->set(false), HalStatus::kIoError);
  EXPECT_STREQ(out->last_error(), "gpio gpiochip0 line 3: setting the line low failed: Operation not permitted");
  fake::set_err = ENODEV;
  std::size_t allocations = 0;
  int closed = 0;
  {
    rtfuse::test::AllocScope scope;
    for (int i = 0; i < 100; ++i) closed += out->set(i % 2 == 0) == HalStatus::kClosed ? 1 : 0;
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(closed, 100);
  EXPECT_STREQ(out->last_error(), "gpio gpiochip0 line 3: setting the line low failed: No such device");
}

}  // namespace gpiod_line_test
}  // namespace rtfuse::hal
