// I2cDevBus: the real open failures this machine can produce (no /dev/i2c-*),
// and everything after open through a scripted ioctl that records the exact
// i2c_rdwr_ioctl_data the kernel would receive.
#include "hal/linux/i2c_dev_bus.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/i2c-dev.h>
#include <linux/i2c.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "support/alloc_counter.hpp"

namespace rtfuse::hal {
namespace i2c_dev_bus_test {

// Scripted ioctl. Plain globals: the seam is a function pointer, and the
// recording must not allocate (the allocation test runs through it).
namespace fake {
struct Msg {
  std::uint16_t addr;
  std::uint16_t flags;
  std::uint16_t len;
  std::uint8_t bytes[2];  // first bytes of a write message
};
struct Call {
  int fd;
  unsigned long request;
  std::uint32_t nmsgs;
  Msg msgs[2];
  // I2C_SLAVE: the address; I2C_SMBUS: the transaction.
  unsigned long slave;
  std::uint8_t smbus_read_write;
  std::uint8_t smbus_command;
  std::uint32_t smbus_size;
  std::uint8_t smbus_len;   // block[0] as sent (I2C block)
  std::uint8_t smbus_byte;  // data.byte as sent (byte data write)
};
constexpr int kShort = -1;  // script entry: report one message fewer than asked
constexpr int kMaxCalls = 64;

Call calls[kMaxCalls];
int ncalls = 0;
int script[kMaxCalls];  // errno per call, 0 = success; past the end: success
int nscript = 0;
bool fill_on_failure = false;  // scribble into the read buffer even when failing
bool short_block = false;      // an I2C block read answers one byte fewer than asked
unsigned long funcs = 0;
int funcs_errno = 0;

void reset() {
  ncalls = 0;
  nscript = 0;
  fill_on_failure = false;
  short_block = false;
  funcs = 0;
  funcs_errno = 0;
}

void set_script(std::initializer_list<int> errnos) {
  nscript = 0;
  for (int e : errnos) script[nscript++] = e;
}

std::uint8_t pattern(int i) { return static_cast<std::uint8_t>(0xA0 + i); }

int ioctl(int fd, unsigned long request, void* arg) {
  if (request == I2C_FUNCS) {
    if (funcs_errno != 0) {
      errno = funcs_errno;
      return -1;
    }
    *static_cast<unsigned long*>(arg) = funcs;
    return 0;
  }
  const int idx = ncalls;
  Call& c = calls[ncalls < kMaxCalls ? ncalls++ : kMaxCalls - 1];
  c = Call{};
  c.fd = fd;
  c.request = request;
  const int e = idx < nscript ? script[idx] : 0;
  if (request == I2C_SLAVE) {
    c.slave = reinterpret_cast<unsigned long>(arg);
    if (e == 0) return 0;
    errno = e;
    return -1;
  }
  if (request == I2C_SMBUS) {
    auto* args = static_cast<i2c_smbus_ioctl_data*>(arg);
    c.smbus_read_write = args->read_write;
    c.smbus_command = args->command;
    c.smbus_size = args->size;
    c.smbus_len = args->data->block[0];
    c.smbus_byte = args->data->byte;
    const bool block_read = args->read_write == I2C_SMBUS_READ && args->size == I2C_SMBUS_I2C_BLOCK_DATA;
    if (block_read && (e == 0 || fill_on_failure)) {
      for (int b = 0; b < args->data->block[0]; ++b) args->data->block[1 + b] = pattern(args->command + b);
      if (short_block) args->data->block[0] = static_cast<__u8>(args->data->block[0] - 1);
    }
    if (e == 0) return 0;
    errno = e;
    return -1;
  }
  auto* data = static_cast<i2c_rdwr_ioctl_data*>(arg);
  c.nmsgs = data->nmsgs;
  for (std::uint32_t i = 0; i < data->nmsgs && i < 2; ++i) {
    const i2c_msg& m = data->msgs[i];
    c.msgs[i].addr = m.addr;
    c.msgs[i].flags = m.flags;
    c.msgs[i].len = m.len;
    if ((m.flags & I2C_M_RD) == 0) {
      for (int b = 0; b < 2 && b < m.len; ++b) c.msgs[i].bytes[b] = m.buf[b];
    }
  }
  if (e == 0 || fill_on_failure) {
    for (std::uint32_t i = 0; i < data->nmsgs; ++i) {
      if (data->msgs[i].flags & I2C_M_RD) {
        for (int b = 0; b < data->msgs[i].len; ++b) data->msgs[i].buf[b] = pattern(b);
      }
    }
  }
  if (e == 0) return static_cast<int>(data->nmsgs);
  if (e == kShort) return static_cast<int>(data->nmsgs) - 1;
  errno = e;
  return -1;
}
}  // namespace fake

class I2cDevBusTest : public ::testing::Test {
 protected:
  void SetUp() override {
    fake::reset();
    fd_ = ::open("/dev/null", O_RDWR | O_CLOEXEC);
    ASSERT_GE(fd_, 0);
  }
  std::unique_ptr<I2cDevBus> make(int attempts = 3, I2cTransferMode mode = I2cTransferMode::kI2c) {
    I2cRetryPolicy p;
    p.attempts = attempts;
    return I2cDevBus::adopt(fd_, "/dev/i2c-test", p, &fake::ioctl, mode);
  }
  std::unique_ptr<I2cDevBus> make_smbus(int attempts = 3) { return make(attempts, I2cTransferMode::kSmbus); }
  int fd_ = -1;  // owned by the bus once adopted
};

bool device_exists(const char* path) { return ::access(path, F_OK) == 0; }

// --- open: real failures --------------------------------------------------------

TEST(I2cDevBusOpen, DevicePathFromNumberNameOrPath) {
  EXPECT_EQ(I2cDevBus::device_path("1"), "/dev/i2c-1");
  EXPECT_EQ(I2cDevBus::device_path("12"), "/dev/i2c-12");
  EXPECT_EQ(I2cDevBus::device_path("i2c-7"), "/dev/i2c-7");
  EXPECT_EQ(I2cDevBus::device_path("/dev/i2c-3"), "/dev/i2c-3");
}

TEST(I2cDevBusOpen, MissingBusByNumberFailsWithModuleHint) {
  if (device_exists("/dev/i2c-1")) GTEST_SKIP() << "/dev/i2c-1 exists on this machine";
  std::string error;
  auto bus = I2cDevBus::open("1", I2cRetryPolicy{}, &error);
  EXPECT_EQ(bus, nullptr);
  EXPECT_EQ(error,
            "cannot open I2C bus /dev/i2c-1: No such file or directory; no /dev/i2c-1: load the i2c-dev module "
            "(modprobe i2c-dev) and check the bus number with i2cdetect -l");
  EXPECT_NE(error.find("i2c-dev"), std::string::npos);
  EXPECT_NE(error.find("No such file or directory"), std::string::npos);
}

TEST(I2cDevBusOpen, MissingBusByPathFailsNamingThatPath) {
  if (device_exists("/dev/i2c-42")) GTEST_SKIP() << "/dev/i2c-42 exists on this machine";
  std::string error;
  EXPECT_EQ(I2cDevBus::open("/dev/i2c-42", I2cRetryPolicy{}, &error), nullptr);
  EXPECT_EQ(error,
            "cannot open I2C bus /dev/i2c-42: No such file or directory; no /dev/i2c-42: load the i2c-dev module "
            "(modprobe i2c-dev) and check the bus number with i2cdetect -l");
}

TEST(I2cDevBusOpen, NodeThatIsNotAnAdapterIsRejectedAtOpen) {
  std::string error;
  EXPECT_EQ(I2cDevBus::open("/dev/null", I2cRetryPolicy{}, &error), nullptr);
  // The kernel answers ENOTTY; qemu-user, which has no translation for the
  // i2c-dev ioctls, answers ENOSYS before the kernel sees the call. Either
  // way the errno text is passed on.
  const std::string head = "/dev/null is not an I2C adapter (I2C_FUNCS failed: ";
  const std::string tail = "); pass an i2c-dev node such as /dev/i2c-1 (list buses with i2cdetect -l)";
  EXPECT_TRUE(error == head + std::strerror(ENOTTY) + tail || error == head + std::strerror(ENOSYS) + tail) << error;
}

TEST(I2cDevBusOpen, PermissionDeniedNamesGroupAndUdev) {
  // Tests here run as root, so EACCES cannot be produced for real.
  EXPECT_EQ(I2cDevBus::describe_open_failure("/dev/i2c-1", EACCES),
            "cannot open I2C bus /dev/i2c-1: Permission denied; add the user to group i2c (usermod -aG i2c $USER, "
            "then log in again) or add a udev rule giving that group access to /dev/i2c-1");
}

TEST(I2cDevBusOpen, OtherErrnoGivesTextWithoutGuessedFix) {
  EXPECT_EQ(I2cDevBus::describe_open_failure("/dev/i2c-1", EBUSY),
            "cannot open I2C bus /dev/i2c-1: Device or resource busy");
}

TEST(I2cDevBusOpen, CheckAdapterPrefersPlainI2c) {
  fake::reset();
  fake::funcs = I2C_FUNC_I2C | I2C_FUNC_SMBUS_EMUL;
  std::string error;
  I2cTransferMode mode = I2cTransferMode::kSmbus;
  EXPECT_TRUE(I2cDevBus::check_adapter(3, "/dev/i2c-1", &fake::ioctl, &mode, &error));
  EXPECT_EQ(mode, I2cTransferMode::kI2c);
  EXPECT_EQ(error, "");
}

TEST(I2cDevBusOpen, CheckAdapterFallsBackToSmbusOnSmbusOnlyAdapters) {
  fake::reset();
  // What i2c-stub reports by default.
  fake::funcs = I2C_FUNC_SMBUS_QUICK | I2C_FUNC_SMBUS_BYTE | I2C_FUNC_SMBUS_BYTE_DATA | I2C_FUNC_SMBUS_WORD_DATA |
                I2C_FUNC_SMBUS_I2C_BLOCK;
  std::string error;
  I2cTransferMode mode = I2cTransferMode::kI2c;
  EXPECT_TRUE(I2cDevBus::check_adapter(3, "/dev/i2c-1", &fake::ioctl, &mode, &error));
  EXPECT_EQ(mode, I2cTransferMode::kSmbus);
  EXPECT_STREQ(to_string(mode), "SMBus (I2C block reads, byte writes)");
  EXPECT_STREQ(to_string(I2cTransferMode::kI2c), "I2C (combined I2C_RDWR transfers)");
}

TEST(I2cDevBusOpen, CheckAdapterRejectsAdaptersWithoutBlockReads) {
  fake::reset();
  fake::funcs = I2C_FUNC_SMBUS_BYTE_DATA | I2C_FUNC_SMBUS_WORD_DATA;
  std::string error;
  I2cTransferMode mode = I2cTransferMode::kI2c;
  EXPECT_FALSE(I2cDevBus::check_adapter(3, "/dev/i2c-1", &fake::ioctl, &mode, &error));
  EXPECT_EQ(error,
            "/dev/i2c-1 can do neither plain I2C transfers (I2C_RDWR) nor SMBus I2C-block reads with byte-data "
            "writes, which this backend needs to read register bursts; use another bus (i2cdetect -F shows what "
            "each adapter does)");
}

// --- transfers ------------------------------------------------------------------

TEST_F(I2cDevBusTest, ReadIsOneCombinedTransferWriteRegThenReadN) {
  auto bus = make();
  std::uint8_t buf[14] = {};
  ASSERT_EQ(bus->read_registers(0x68, 0x3B, buf, 14), HalStatus::kOk);
  ASSERT_EQ(fake::ncalls, 1);
  const fake::Call& c = fake::calls[0];
  EXPECT_EQ(c.fd, fd_);
  EXPECT_EQ(c.request, static_cast<unsigned long>(I2C_RDWR));
  ASSERT_EQ(c.nmsgs, 2u);
  EXPECT_EQ(c.msgs[0].addr, 0x68);
  EXPECT_EQ(c.msgs[0].flags, 0);
  EXPECT_EQ(c.msgs[0].len, 1);
  EXPECT_EQ(c.msgs[0].bytes[0], 0x3B);
  EXPECT_EQ(c.msgs[1].addr, 0x68);
  EXPECT_EQ(c.msgs[1].flags, I2C_M_RD);
  EXPECT_EQ(c.msgs[1].len, 14);
  for (int i = 0; i < 14; ++i) EXPECT_EQ(buf[i], fake::pattern(i)) << i;
  EXPECT_EQ(bus->retries(), 0);
}

TEST_F(I2cDevBusTest, ReadOfMaximumLength) {
  auto bus = make();
  std::uint8_t buf[64] = {};
  ASSERT_EQ(bus->read_registers(0x0C, 0x00, buf, 64), HalStatus::kOk);
  EXPECT_EQ(fake::calls[0].msgs[1].len, 64);
  EXPECT_EQ(buf[63], fake::pattern(63));
}

TEST_F(I2cDevBusTest, WriteIsOneMessageOfRegisterAndValue) {
  auto bus = make();
  ASSERT_EQ(bus->write_register(0x68, 0x6B, 0x80), HalStatus::kOk);
  ASSERT_EQ(fake::ncalls, 1);
  const fake::Call& c = fake::calls[0];
  EXPECT_EQ(c.request, static_cast<unsigned long>(I2C_RDWR));
  ASSERT_EQ(c.nmsgs, 1u);
  EXPECT_EQ(c.msgs[0].addr, 0x68);
  EXPECT_EQ(c.msgs[0].flags, 0);
  EXPECT_EQ(c.msgs[0].len, 2);
  EXPECT_EQ(c.msgs[0].bytes[0], 0x6B);
  EXPECT_EQ(c.msgs[0].bytes[1], 0x80);
}

// --- SMBus mode (SMBus-only adapters) ---------------------------------------------

TEST_F(I2cDevBusTest, SmbusReadIsOneI2cBlockReadAfterSelectingTheAddress) {
  auto bus = make_smbus();
  EXPECT_EQ(bus->mode(), I2cTransferMode::kSmbus);
  std::uint8_t buf[14] = {};
  ASSERT_EQ(bus->read_registers(0x68, 0x3B, buf, 14), HalStatus::kOk);
  ASSERT_EQ(fake::ncalls, 2);
  EXPECT_EQ(fake::calls[0].request, static_cast<unsigned long>(I2C_SLAVE));
  EXPECT_EQ(fake::calls[0].slave, 0x68u);
  const fake::Call& c = fake::calls[1];
  EXPECT_EQ(c.request, static_cast<unsigned long>(I2C_SMBUS));
  EXPECT_EQ(c.smbus_read_write, I2C_SMBUS_READ);
  EXPECT_EQ(c.smbus_command, 0x3B);
  EXPECT_EQ(c.smbus_size, static_cast<std::uint32_t>(I2C_SMBUS_I2C_BLOCK_DATA));
  EXPECT_EQ(c.smbus_len, 14);
  for (int i = 0; i < 14; ++i) EXPECT_EQ(buf[i], fake::pattern(0x3B + i)) << i;
  // The address stays selected: the next transfer to it is one call.
  ASSERT_EQ(bus->read_registers(0x68, 0x75, buf, 1), HalStatus::kOk);
  EXPECT_EQ(fake::ncalls, 3);
  EXPECT_EQ(fake::calls[2].request, static_cast<unsigned long>(I2C_SMBUS));
  // Another device is selected first.
  ASSERT_EQ(bus->read_registers(0x0C, 0x00, buf, 1), HalStatus::kOk);
  ASSERT_EQ(fake::ncalls, 5);
  EXPECT_EQ(fake::calls[3].slave, 0x0Cu);
}

TEST_F(I2cDevBusTest, SmbusReadsLongerThan32BytesAreSplitAtSuccessiveRegisters) {
  auto bus = make_smbus();
  std::uint8_t buf[64] = {};
  ASSERT_EQ(bus->read_registers(0x68, 0x10, buf, 40), HalStatus::kOk);
  ASSERT_EQ(fake::ncalls, 3);
  EXPECT_EQ(fake::calls[1].smbus_command, 0x10);
  EXPECT_EQ(fake::calls[1].smbus_len, 32);
  EXPECT_EQ(fake::calls[2].smbus_command, 0x30);
  EXPECT_EQ(fake::calls[2].smbus_len, 8);
  for (int i = 0; i < 40; ++i) EXPECT_EQ(buf[i], fake::pattern(0x10 + i)) << i;
  EXPECT_EQ(buf[40], 0);
}

TEST_F(I2cDevBusTest, SmbusWriteIsByteData) {
  auto bus = make_smbus();
  ASSERT_EQ(bus->write_register(0x68, 0x6B, 0x80), HalStatus::kOk);
  ASSERT_EQ(fake::ncalls, 2);
  const fake::Call& c = fake::calls[1];
  EXPECT_EQ(c.request, static_cast<unsigned long>(I2C_SMBUS));
  EXPECT_EQ(c.smbus_read_write, I2C_SMBUS_WRITE);
  EXPECT_EQ(c.smbus_command, 0x6B);
  EXPECT_EQ(c.smbus_size, static_cast<std::uint32_t>(I2C_SMBUS_BYTE_DATA));
  EXPECT_EQ(c.smbus_byte, 0x80);
}

TEST_F(I2cDevBusTest, SmbusNacksAreRetriedAndFailuresLeaveTheBufferAlone) {
  auto bus = make_smbus(3);
  fake::set_script({0, ENXIO, 0});  // select, NACK, success
  std::uint8_t buf[2] = {};
  ASSERT_EQ(bus->read_registers(0x68, 0x41, buf, 2), HalStatus::kOk);
  EXPECT_EQ(bus->retries(), 1);
  fake::ncalls = 0;
  fake::set_script({ENXIO, ENXIO, ENXIO});
  fake::fill_on_failure = true;
  buf[0] = 7;
  EXPECT_EQ(bus->read_registers(0x68, 0x41, buf, 2), HalStatus::kNack);
  EXPECT_EQ(fake::ncalls, 3);
  EXPECT_EQ(buf[0], 7);
  EXPECT_STREQ(bus->last_error(),
               "/dev/i2c-test: read addr 0x68 reg 0x41 failed on attempt 3 of 3: No such device or address (no acknowledge (NACK))");
}

TEST_F(I2cDevBusTest, SmbusShortBlockIsAnIoError) {
  auto bus = make_smbus();
  fake::short_block = true;
  std::uint8_t buf[14] = {};
  EXPECT_EQ(bus->read_registers(0x68, 0x3B, buf, 14), HalStatus::kIoError);
  EXPECT_STREQ(bus->last_error(), "/dev/i2c-test: read addr 0x68 reg 0x3b: the adapter returned 13 of 14 bytes");
  EXPECT_EQ(buf[0], 0);
}

TEST_F(I2cDevBusTest, SmbusAddressClaimedByAKernelDriverSaysSo) {
  auto bus = make_smbus();
  fake::set_script({EBUSY});
  std::uint8_t buf[1] = {};
  EXPECT_EQ(bus->read_registers(0x68, 0x75, buf, 1), HalStatus::kIoError);
  EXPECT_STREQ(bus->last_error(),
               "/dev/i2c-test: read addr 0x68 reg 0x75: selecting the address (I2C_SLAVE) failed: Device or resource "
               "busy; a kernel driver has claimed it: unbind that driver (see /sys/bus/i2c/devices)");
  // Not selected: the next call tries again.
  ASSERT_EQ(bus->read_registers(0x68, 0x75, buf, 1), HalStatus::kOk);
  EXPECT_EQ(fake::calls[1].request, static_cast<unsigned long>(I2C_SLAVE));
}

TEST_F(I2cDevBusTest, SmbusSteadyStateTransfersDoNotAllocate) {
  auto bus = make_smbus(3);
  std::uint8_t buf[14] = {};
  fake::set_script({0, ENXIO, 0});
  (void)bus->read_registers(0x68, 0x3B, buf, 14);
  fake::ncalls = 0;
  fake::set_script({ENXIO, 0, ETIMEDOUT, 0});
  std::size_t allocations = 0;
  {
    rtfuse::test::AllocScope scope;
    for (int i = 0; i < 100; ++i) {
      (void)bus->read_registers(0x68, 0x3B, buf, 14);
      (void)bus->write_register(0x68, 0x6B, static_cast<std::uint8_t>(i));
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
}

struct ErrnoCase {
  const char* name;
  int err;
  HalStatus status;
  int calls_with_three_attempts;
};

class I2cErrnoMapping : public I2cDevBusTest, public ::testing::WithParamInterface<ErrnoCase> {};

TEST_P(I2cErrnoMapping, ReadMapsErrnoAndRetriesOnlyNackAndBusError) {
  const ErrnoCase p = GetParam();
  auto bus = make(3);
  fake::set_script({p.err, p.err, p.err, p.err});
  fake::fill_on_failure = true;
  std::uint8_t buf[4] = {1, 2, 3, 4};
  EXPECT_EQ(bus->read_registers(0x68, 0x75, buf, 4), p.status);
  EXPECT_EQ(fake::ncalls, p.calls_with_three_attempts);
  EXPECT_EQ(bus->retries(), 0);  // nothing recovered
  // The contract: nothing reaches the caller's buffer unless kOk, even when
  // the kernel half-filled the transfer buffer.
  EXPECT_EQ(buf[0], 1);
  EXPECT_EQ(buf[3], 4);
}

TEST_P(I2cErrnoMapping, WriteMapsErrnoTheSameWay) {
  const ErrnoCase p = GetParam();
  auto bus = make(3);
  fake::set_script({p.err, p.err, p.err, p.err});
  EXPECT_EQ(bus->write_register(0x68, 0x6B, 0x00), p.status);
  EXPECT_EQ(fake::ncalls, p.calls_with_three_attempts);
}

INSTANTIATE_TEST_SUITE_P(Errnos, I2cErrnoMapping,
                         ::testing::Values(ErrnoCase{"ENXIO", ENXIO, HalStatus::kNack, 3},
                                           ErrnoCase{"EREMOTEIO", EREMOTEIO, HalStatus::kNack, 3},
                                           ErrnoCase{"ETIMEDOUT", ETIMEDOUT, HalStatus::kTimeout, 1},
                                           ErrnoCase{"EIO", EIO, HalStatus::kBusError, 3},
                                           ErrnoCase{"EAGAIN", EAGAIN, HalStatus::kBusError, 3},
                                           ErrnoCase{"ENODEV", ENODEV, HalStatus::kClosed, 1},
                                           ErrnoCase{"EINVAL", EINVAL, HalStatus::kIoError, 1},
                                           ErrnoCase{"EOPNOTSUPP", EOPNOTSUPP, HalStatus::kIoError, 1}),
                         [](const ::testing::TestParamInfo<ErrnoCase>& info) { return std::string(info.param.name); });

TEST_F(I2cDevBusTest, RecoveredNacksAreCountedAndLeaveTheirText) {
  auto bus = make(3);
  fake::set_script({ENXIO, ENXIO, 0});
  std::uint8_t buf[2] = {};
  EXPECT_EQ(bus->read_registers(0x68, 0x3B, buf, 2), HalStatus::kOk);
  EXPECT_EQ(fake::ncalls, 3);
  EXPECT_EQ(bus->retries(), 2);
  EXPECT_EQ(buf[1], fake::pattern(1));
  EXPECT_STREQ(bus->last_error(),
               "/dev/i2c-test: read addr 0x68 reg 0x3b failed on attempt 2 of 3: No such device or address "
               "(no acknowledge (NACK))");
}

TEST_F(I2cDevBusTest, RetriesAccumulateAcrossCalls) {
  auto bus = make(4);
  fake::set_script({EIO, 0, EAGAIN, EIO, EIO, 0, 0});
  EXPECT_EQ(bus->write_register(0x10, 0x01, 0x02), HalStatus::kOk);   // 1 recovered
  EXPECT_EQ(bus->write_register(0x10, 0x01, 0x02), HalStatus::kOk);   // 3 recovered
  EXPECT_EQ(bus->write_register(0x10, 0x01, 0x02), HalStatus::kOk);   // clean
  EXPECT_EQ(fake::ncalls, 7);
  EXPECT_EQ(bus->retries(), 4);
}

TEST_F(I2cDevBusTest, ExhaustedRetriesReportTheLastAttempt) {
  auto bus = make(3);
  fake::set_script({EREMOTEIO, EREMOTEIO, EREMOTEIO, 0});
  std::uint8_t buf[1] = {};
  EXPECT_EQ(bus->read_registers(0x69, 0x75, buf, 1), HalStatus::kNack);
  EXPECT_EQ(fake::ncalls, 3);
  EXPECT_EQ(bus->retries(), 0);
  EXPECT_STREQ(bus->last_error(),
               "/dev/i2c-test: read addr 0x69 reg 0x75 failed on attempt 3 of 3: Remote I/O error "
               "(no acknowledge (NACK))");
}

TEST_F(I2cDevBusTest, TimeoutIsNotRetried) {
  auto bus = make(5);
  fake::set_script({ETIMEDOUT, 0});
  EXPECT_EQ(bus->write_register(0x68, 0x19, 0x07), HalStatus::kTimeout);
  EXPECT_EQ(fake::ncalls, 1);
  EXPECT_STREQ(bus->last_error(),
               "/dev/i2c-test: write addr 0x68 reg 0x19 failed on attempt 1 of 5: Connection timed out (timeout)");
}

TEST_F(I2cDevBusTest, BusErrorTextNamesTheErrno) {
  auto bus = make(1);
  fake::set_script({EAGAIN});
  EXPECT_EQ(bus->write_register(0x68, 0x19, 0x07), HalStatus::kBusError);
  EXPECT_STREQ(bus->last_error(),
               "/dev/i2c-test: write addr 0x68 reg 0x19 failed on attempt 1 of 1: Resource temporarily unavailable "
               "(bus error)");
}

TEST_F(I2cDevBusTest, ShortTransferIsAnIoErrorAndNotRetried) {
  auto bus = make(3);
  fake::set_script({fake::kShort, 0});
  std::uint8_t buf[6] = {9, 9, 9, 9, 9, 9};
  EXPECT_EQ(bus->read_registers(0x68, 0x43, buf, 6), HalStatus::kIoError);
  EXPECT_EQ(fake::ncalls, 1);
  EXPECT_EQ(buf[0], 9);
  EXPECT_STREQ(bus->last_error(), "/dev/i2c-test: read addr 0x68 reg 0x43: short transfer (1 of 2 messages)");
}

TEST_F(I2cDevBusTest, NonPositiveAttemptsMeanOneTry) {
  auto bus = make(0);
  fake::set_script({ENXIO, 0});
  EXPECT_EQ(bus->write_register(0x68, 0x00, 0x00), HalStatus::kNack);
  EXPECT_EQ(fake::ncalls, 1);
}

TEST_F(I2cDevBusTest, InvalidArgumentsNeverReachTheKernel) {
  auto bus = make();
  std::uint8_t buf[65] = {};
  EXPECT_EQ(bus->read_registers(0x68, 0x00, buf, 0), HalStatus::kIoError);
  EXPECT_STREQ(bus->last_error(), "/dev/i2c-test: read addr 0x68 reg 0x00: length 0 outside 1..64");
  EXPECT_EQ(bus->read_registers(0x68, 0x00, buf, 65), HalStatus::kIoError);
  EXPECT_EQ(bus->read_registers(0x68, 0x00, nullptr, 4), HalStatus::kIoError);
  EXPECT_EQ(bus->read_registers(0x80, 0x00, buf, 4), HalStatus::kIoError);
  EXPECT_STREQ(bus->last_error(), "/dev/i2c-test: read addr 0x80 reg 0x00: not a 7-bit address");
  EXPECT_EQ(bus->write_register(0xFF, 0x00, 0x00), HalStatus::kIoError);
  EXPECT_EQ(fake::ncalls, 0);
}

TEST_F(I2cDevBusTest, DestructorClosesTheAdoptedDescriptor) {
  const int fd = fd_;
  auto bus = make();
  bus.reset();
  errno = 0;
  EXPECT_EQ(::fcntl(fd, F_GETFD), -1);
  EXPECT_EQ(errno, EBADF);
}

TEST_F(I2cDevBusTest, SteadyStateTransfersDoNotAllocate) {
  auto bus = make(3);
  std::uint8_t buf[14] = {};
  // Warm-up outside the scope: first strerror_r may touch locale data.
  fake::set_script({ENXIO, 0, ETIMEDOUT});
  (void)bus->read_registers(0x68, 0x3B, buf, 14);
  (void)bus->write_register(0x68, 0x6B, 0x00);
  fake::ncalls = 0;
  fake::set_script({ENXIO, EIO, 0, 0, ETIMEDOUT, ENODEV, EREMOTEIO, EREMOTEIO, EREMOTEIO, 0});
  std::size_t allocations = 0;
  {
    rtfuse::test::AllocScope scope;
    for (int i = 0; i < 200; ++i) {
      (void)bus->read_registers(0x68, 0x3B, buf, 14);
      (void)bus->write_register(0x68, 0x6B, static_cast<std::uint8_t>(i));
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(bus->retries(), 3);  // 1 in the warm-up, 2 in the scope
}

}  // namespace i2c_dev_bus_test
}  // namespace rtfuse::hal
