#pragma once
// Divergence reports are written into fixed buffers on the replaying thread
// (never allocating): snprintf appended piece by piece, never past the end.
#include <algorithm>
#include <cstdarg>
#include <cstddef>
#include <cstdio>

namespace rtfuse::hal::replay {

class ReportText {
 public:
  ReportText(char* buf, std::size_t size) : buf_(buf), size_(size) {
    if (size_ > 0) buf_[0] = '\0';
  }
  __attribute__((format(printf, 2, 3))) void add(const char* fmt, ...) {
    if (pos_ + 1 >= size_) return;
    va_list args;
    va_start(args, fmt);
    const int n = std::vsnprintf(buf_ + pos_, size_ - pos_, fmt, args);
    va_end(args);
    if (n > 0) pos_ = std::min(size_ - 1, pos_ + static_cast<std::size_t>(n));
  }
  int length() const { return static_cast<int>(pos_); }

 private:
  char* buf_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace rtfuse::hal::replay
