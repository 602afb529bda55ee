#include "transport/event_log.hpp"

#include <algorithm>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <new>
#include <utility>

#include "core/time.hpp"

namespace rtfuse::transport {
namespace {

std::uint32_t load_u32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

std::uint64_t load_u64(const std::uint8_t* p) {
  return (std::uint64_t{load_u32(p)} << 32) | load_u32(p + 4);
}

void store_u32(std::uint8_t* p, std::uint32_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 24);
  p[1] = static_cast<std::uint8_t>(v >> 16);
  p[2] = static_cast<std::uint8_t>(v >> 8);
  p[3] = static_cast<std::uint8_t>(v);
}

void store_u64(std::uint8_t* p, std::uint64_t v) {
  store_u32(p, static_cast<std::uint32_t>(v >> 32));
  store_u32(p + 4, static_cast<std::uint32_t>(v));
}

void set_error(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

std::string hex32(std::uint32_t v) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08X", v);
  return text;
}

}  // namespace

// ---------------------------------------------------------------- reader

EventLogReader::~EventLogReader() { close(); }

void EventLogReader::close() {
  if (file_ != nullptr) std::fclose(file_);
  file_ = nullptr;
}

bool EventLogReader::open(const std::string& path, std::string* error) {
  close();
  path_ = path;
  offset_ = 0;
  index_ = 0;
  sticky_ = ReadStatus::kEvent;
  sticky_error_.clear();
  file_ = std::fopen(path.c_str(), "rb");
  if (file_ == nullptr) {
    set_error(error, "cannot open log file " + path + ": " + std::strerror(errno));
    return false;
  }
  // glibc opens a directory for reading; say so now rather than as a read
  // error later.
  struct stat st {};
  if (::fstat(::fileno(file_), &st) == 0 && S_ISDIR(st.st_mode)) {
    close();
    set_error(error, "cannot open log file " + path + ": it is a directory (give the .lcm file in it)");
    return false;
  }
  return true;
}

ReadStatus EventLogReader::fail(std::string* error, std::string message) {
  sticky_ = ReadStatus::kError;
  sticky_error_ = std::move(message);
  set_error(error, sticky_error_);
  return ReadStatus::kError;
}

bool EventLogReader::ensure_capacity(std::size_t size) {
  if (size <= capacity_) return true;
  // Exactly the size needed: the buffer ends as large as the largest event.
  buffer_.reset(new (std::nothrow) std::uint8_t[size]);
  capacity_ = buffer_ ? size : 0;
  return buffer_ != nullptr;
}

ReadStatus EventLogReader::next(LogEvent* ev, std::string* error) {
  if (sticky_ == ReadStatus::kError) {
    set_error(error, sticky_error_);
    return sticky_;
  }
  if (sticky_ == ReadStatus::kEnd) return sticky_;
  if (file_ == nullptr) return fail(error, "event log reader: no file is open");

  // Messages are formatted on error paths only: the happy path never allocates.
  auto prefix = [this]() {
    return "file " + path_ + ": event " + std::to_string(index_) + " at byte " +
           std::to_string(offset_);
  };
  auto read_error = [&](std::uint64_t at) {
    return fail(error, "file " + path_ + ": read error at byte " + std::to_string(at) + ": " +
                           std::strerror(errno));
  };

  std::uint8_t header[kEventHeaderSize];
  const std::size_t got = std::fread(header, 1, sizeof header, file_);
  if (got != sizeof header) {
    if (std::ferror(file_)) return read_error(offset_ + got);
    if (got == 0) {
      sticky_ = ReadStatus::kEnd;
      return sticky_;
    }
    return fail(error, prefix() + " is truncated: " + std::to_string(got) + " of " +
                           std::to_string(kEventHeaderSize) +
                           " header bytes remain (the log ends mid-event)");
  }

  const std::uint32_t sync = load_u32(header);
  if (sync != kEventLogSyncWord) {
    return fail(error, prefix() + " has a bad sync word " + hex32(sync) + " (expected " +
                           hex32(kEventLogSyncWord) + "): not an LCM log, or corrupt from here on");
  }
  const auto event_number = static_cast<std::int64_t>(load_u64(header + 4));
  const auto timestamp = static_cast<std::int64_t>(load_u64(header + 12));
  const auto channel_len = static_cast<std::int32_t>(load_u32(header + 20));
  const auto data_len = static_cast<std::int32_t>(load_u32(header + 24));
  if (!utime_in_range(timestamp)) {
    return fail(error, prefix() + " has the timestamp " + std::to_string(timestamp) +
                           " us, beyond what nanoseconds can hold (+-" + std::to_string(kMaxUtime) +
                           " us): the log is corrupt");
  }
  if (channel_len <= 0 || channel_len > kMaxEventChannelSize) {
    return fail(error, prefix() + " has an invalid channel length " + std::to_string(channel_len) +
                           " (expected 1.." + std::to_string(kMaxEventChannelSize) +
                           "): the log is corrupt");
  }
  if (data_len < 0 || data_len > kMaxEventDataSize) {
    return fail(error, prefix() + " has an invalid data length " + std::to_string(data_len) +
                           " (expected 0.." + std::to_string(kMaxEventDataSize) +
                           "): the log is corrupt");
  }

  const auto channel_size = static_cast<std::size_t>(channel_len);
  const auto data_size = static_cast<std::size_t>(data_len);
  // Before the buffer grows, the file must hold the event: a corrupt length
  // in a short file would otherwise cost up to 256 MiB for nothing (the
  // fuzzer's slowest inputs). fstat only then, so the happy path stays
  // free of system calls beyond the reads.
  struct stat st {};
  if (channel_size + data_size > capacity_ && ::fstat(::fileno(file_), &st) == 0 && S_ISREG(st.st_mode)) {
    const std::uint64_t end = offset_ + kEventHeaderSize + channel_size + data_size;
    if (end > static_cast<std::uint64_t>(st.st_size)) {
      const std::uint64_t body = offset_ + kEventHeaderSize;
      const std::uint64_t left = static_cast<std::uint64_t>(st.st_size) - std::min<std::uint64_t>(st.st_size, body);
      const bool channel_short = channel_size > left;
      return fail(error, prefix() + " is truncated: header says " +
                             std::to_string(channel_short ? channel_size : data_size) +
                             (channel_short ? " channel" : " data") + " bytes, " +
                             std::to_string(channel_short ? left : left - channel_size) +
                             " remain (the log ends mid-event)");
    }
  }
  if (!ensure_capacity(channel_size + data_size)) {
    return fail(error, prefix() + ": out of memory for " +
                           std::to_string(channel_size + data_size) + " bytes");
  }

  const std::size_t got_channel = std::fread(buffer_.get(), 1, channel_size, file_);
  if (got_channel != channel_size) {
    if (std::ferror(file_)) return read_error(offset_ + kEventHeaderSize + got_channel);
    return fail(error, prefix() + " is truncated: header says " + std::to_string(channel_size) +
                           " channel bytes, " + std::to_string(got_channel) +
                           " remain (the log ends mid-event)");
  }
  const std::size_t got_data =
      data_size == 0 ? 0 : std::fread(buffer_.get() + channel_size, 1, data_size, file_);
  if (got_data != data_size) {
    if (std::ferror(file_)) {
      return read_error(offset_ + kEventHeaderSize + channel_size + got_data);
    }
    return fail(error, prefix() + " is truncated: header says " + std::to_string(data_size) +
                           " data bytes, " + std::to_string(got_data) +
                           " remain (the log ends mid-event)");
  }

  ev->event_number = event_number;
  ev->timestamp_us = timestamp;
  ev->channel = std::string_view(reinterpret_cast<const char*>(buffer_.get()), channel_size);
  ev->data = buffer_.get() + channel_size;
  ev->size = data_size;
  offset_ += kEventHeaderSize + channel_size + data_size;
  ++index_;
  return ReadStatus::kEvent;
}

// ---------------------------------------------------------------- writer

EventLogWriter::~EventLogWriter() { close(); }

bool EventLogWriter::open(const std::string& path, std::string* error) {
  close();
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    set_error(error, "cannot create log file " + path + ": " + std::strerror(errno));
    return false;
  }
  if (!buffer_) buffer_.reset(new std::uint8_t[kBufferSize]);
  fd_ = fd;
  path_ = path;
  next_event_ = 0;
  used_ = 0;
  return true;
}

bool EventLogWriter::write_all(const std::uint8_t* bytes, std::size_t size, std::string* error) {
  while (size > 0) {
    const ssize_t n = ::write(fd_, bytes, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      set_error(error, "cannot write log file " + path_ + ": " + std::strerror(errno));
      return false;
    }
    bytes += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

bool EventLogWriter::flush(std::string* error) {
  if (fd_ < 0) {
    set_error(error, "event log writer: no file is open");
    return false;
  }
  const std::size_t pending = used_;
  used_ = 0;
  return write_all(buffer_.get(), pending, error);
}

bool EventLogWriter::append(const void* bytes, std::size_t size, std::string* error) {
  if (size > kBufferSize - used_ && !flush(error)) return false;
  // A chunk larger than the whole buffer (a camera frame) skips the copy.
  if (size > kBufferSize) return write_all(static_cast<const std::uint8_t*>(bytes), size, error);
  if (size > 0) std::memcpy(buffer_.get() + used_, bytes, size);
  used_ += size;
  return true;
}

bool EventLogWriter::write(std::int64_t timestamp_us, std::string_view channel, const void* data,
                           std::size_t size, std::string* error) {
  if (fd_ < 0) {
    set_error(error, "event log writer: no file is open");
    return false;
  }
  if (channel.empty() || channel.size() > static_cast<std::size_t>(kMaxEventChannelSize)) {
    set_error(error, "log file " + path_ + ": channel '" + std::string(channel.substr(0, 64)) +
                         "' has length " + std::to_string(channel.size()) + " (expected 1.." +
                         std::to_string(kMaxEventChannelSize) + ")");
    return false;
  }
  if (size > static_cast<std::size_t>(kMaxEventDataSize) || (size > 0 && data == nullptr)) {
    set_error(error, "log file " + path_ + ": event on channel " + std::string(channel) + " has " +
                         std::to_string(size) + " data bytes (expected 0.." +
                         std::to_string(kMaxEventDataSize) + " and a non-null pointer)");
    return false;
  }
  std::uint8_t header[kEventHeaderSize];
  store_u32(header, kEventLogSyncWord);
  store_u64(header + 4, static_cast<std::uint64_t>(next_event_));
  store_u64(header + 12, static_cast<std::uint64_t>(timestamp_us));
  store_u32(header + 20, static_cast<std::uint32_t>(channel.size()));
  store_u32(header + 24, static_cast<std::uint32_t>(size));
  if (!append(header, sizeof header, error) || !append(channel.data(), channel.size(), error) ||
      !append(data, size, error)) {
    return false;
  }
  ++next_event_;
  return true;
}

bool EventLogWriter::close(std::string* error) {
  if (fd_ < 0) return true;
  bool ok = flush(error);
  if (::close(fd_) != 0 && ok) {
    set_error(error, "cannot close log file " + path_ + ": " + std::strerror(errno));
    ok = false;
  }
  fd_ = -1;
  return ok;
}

}  // namespace rtfuse::transport
