#pragma once
// A SerialPort without a device, for tests and the simulator: a test or a
// simulated receiver feeds bytes with the time they come off the wire, and
// read() hands them out once the Clock has reached that time (a SimClock
// jumps to the next arrival, a MonotonicClock sleeps until it), stamped with
// their arrival as a backend with perfect timestamps would.
//
// The receive queue is a fixed ring, like a UART FIFO: bytes that do not fit
// are dropped and counted, not queued. What the host writes is kept for the
// test or the simulated receiver to inspect. Allocation happens in the
// constructor only. Not thread-safe: feed and read from one thread.
#include <cstdint>
#include <memory>

#include "hal/clock.hpp"
#include "hal/serial_port.hpp"

namespace rtfuse::hal::mock {

struct MockSerialPortCapacity {
  int rx_bytes = 4096;       // fed but not yet read; more are dropped
  int written_bytes = 4096;  // kept for written(); a write that does not fit times out
};

class MockSerialPort final : public SerialPort {
 public:
  explicit MockSerialPort(Clock& clock, MockSerialPortCapacity capacity = {});
  MockSerialPort(const MockSerialPort&) = delete;
  MockSerialPort& operator=(const MockSerialPort&) = delete;

  // --- what the host receives ---------------------------------------------
  // Queues size bytes arriving at `arrival` (clock time). A wire delivers in
  // order, so an arrival before the last one fed is taken as that one. False
  // when not all of them fit (the rest is dropped and counted, as a UART
  // FIFO overruns) or while unplugged (nothing is there to receive them).
  bool feed(const std::uint8_t* data, int size, TimeNs arrival) noexcept;
  // Bytes fed and not yet read, due or not.
  int pending() const noexcept { return rx_count_; }
  // feed() calls that dropped bytes, and the bytes dropped.
  std::int64_t overruns() const noexcept { return overruns_; }
  std::int64_t dropped_bytes() const noexcept { return dropped_bytes_; }

  // --- what the host wrote ------------------------------------------------
  const std::uint8_t* written() const noexcept { return written_.get(); }
  int written_size() const noexcept { return written_size_; }
  void clear_written() noexcept { written_size_ = 0; }

  // --- faults -------------------------------------------------------------
  // The device goes away: read() and write() give kClosed and the queued
  // bytes are lost with it, as with a hung-up tty.
  void unplug() noexcept;
  // It is back (and reopened): bytes fed from now on are received.
  void replug() noexcept { unplugged_ = false; }
  bool unplugged() const noexcept { return unplugged_; }

  // --- hal::SerialPort ----------------------------------------------------
  // Returns the bytes whose arrival <= now, *stamp the arrival of the first.
  // With nothing due and timeout_ns > 0 it sleeps on the clock until the
  // next arrival or the timeout, whichever comes first.
  int read(std::uint8_t* out, int max, TimeNs timeout_ns, TimeNs* stamp, HalStatus* status) noexcept override;
  HalStatus write(const std::uint8_t* data, int size) noexcept override;
  const char* last_error() const noexcept override { return last_error_; }
  // Back once replugged, as a tty node reappears.
  bool reopen() noexcept override { return !unplugged_; }

 private:
  // Copies out the bytes due by now; 0 if none.
  int take_due(std::uint8_t* out, int max, TimeNs now, TimeNs* stamp) noexcept;

  Clock& clock_;
  const char* last_error_ = "";
  bool unplugged_ = false;

  // Byte i of the queue and its arrival share an index.
  std::unique_ptr<std::uint8_t[]> rx_bytes_;
  std::unique_ptr<TimeNs[]> rx_arrival_;
  int rx_capacity_;
  int rx_head_ = 0;
  int rx_count_ = 0;
  TimeNs last_arrival_ = INT64_MIN;
  std::int64_t overruns_ = 0;
  std::int64_t dropped_bytes_ = 0;

  std::unique_ptr<std::uint8_t[]> written_;
  int written_capacity_;
  int written_size_ = 0;
};

}  // namespace rtfuse::hal::mock
