#pragma once
// The lcm-logger file format, read and written directly. LCM's own C eventlog
// API mallocs every event and reports a truncated log the same way as a clean
// end, so replay could silently drop the tail of a recording; this one reuses
// its buffers and names exactly what is wrong and where.
//
// Each event, big-endian: uint32 sync 0xEDA1DA01, int64 event number,
// int64 timestamp (µs), int32 channel length, int32 data length, then the
// channel bytes (no terminator) and the data bytes.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>

namespace rtfuse::transport {

constexpr std::uint32_t kEventLogSyncWord = 0xEDA1DA01u;
constexpr std::size_t kEventHeaderSize = 28;
// Far above anything rtfuse logs (a camera frame is a few MiB) yet small enough
// that a corrupt length cannot make the reader reserve gigabytes.
constexpr std::int64_t kMaxEventDataSize = 256 * 1024 * 1024;
constexpr std::int64_t kMaxEventChannelSize = 4096;

// Views into the reader's buffer: valid until the next call to next().
struct LogEvent {
  std::int64_t event_number = 0;
  std::int64_t timestamp_us = 0;
  std::string_view channel;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

enum class ReadStatus { kEvent, kEnd, kError };

class EventLogReader {
 public:
  EventLogReader() = default;
  ~EventLogReader();
  EventLogReader(const EventLogReader&) = delete;
  EventLogReader& operator=(const EventLogReader&) = delete;

  bool open(const std::string& path, std::string* error);
  // kEnd only at a clean event boundary; a log cut anywhere else is kError.
  // Once kEnd or kError is returned, every later call returns the same.
  ReadStatus next(LogEvent* ev, std::string* error);
  void close();

  const std::string& path() const { return path_; }
  // Byte offset of the next event to be read.
  std::uint64_t offset() const { return offset_; }
  // Events returned so far (also the index of the next one).
  std::int64_t events_read() const { return index_; }

 private:
  ReadStatus fail(std::string* error, std::string message);
  bool ensure_capacity(std::size_t size);

  std::FILE* file_ = nullptr;
  std::string path_;
  std::uint64_t offset_ = 0;
  std::int64_t index_ = 0;
  ReadStatus sticky_ = ReadStatus::kEvent;
  std::string sticky_error_;
  // Channel then data of the current event; grows to the largest event only.
  std::unique_ptr<std::uint8_t[]> buffer_;
  std::size_t capacity_ = 0;
};

class EventLogWriter {
 public:
  static constexpr std::size_t kBufferSize = 64 * 1024;

  EventLogWriter() = default;
  ~EventLogWriter();  // closes (and flushes) if still open
  EventLogWriter(const EventLogWriter&) = delete;
  EventLogWriter& operator=(const EventLogWriter&) = delete;

  // Creates or truncates the file.
  bool open(const std::string& path, std::string* error);
  // Events are numbered from 0 in write order. Rejects an empty or over-long
  // channel and over-large data, so every log written can be read back.
  bool write(std::int64_t timestamp_us, std::string_view channel, const void* data,
             std::size_t size, std::string* error);
  bool flush(std::string* error);
  // Flushes and closes; false when the final flush or close failed.
  bool close(std::string* error = nullptr);

  bool is_open() const { return fd_ >= 0; }
  std::int64_t events_written() const { return next_event_; }

 private:
  bool append(const void* bytes, std::size_t size, std::string* error);
  bool write_all(const std::uint8_t* bytes, std::size_t size, std::string* error);

  int fd_ = -1;
  std::string path_;
  std::int64_t next_event_ = 0;
  std::unique_ptr<std::uint8_t[]> buffer_;
  std::size_t used_ = 0;
};

}  // namespace rtfuse::transport
