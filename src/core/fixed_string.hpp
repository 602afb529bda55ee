#pragma once
// A string with its storage inline, for names (frames, channels, sensors)
// that must live in fixed-size, trivially copyable structures.
#include <cstddef>
#include <cstring>
#include <string_view>

namespace rtfuse {

template <std::size_t MaxLen>
class FixedString {
 public:
  constexpr FixedString() = default;
  // Truncates silently: use assign() where an over-long name must be an error.
  // (A null pointer is taken as the empty string rather than undefined behaviour.)
  FixedString(const char* s)  // NOLINT(google-explicit-constructor)
      : FixedString(s ? std::string_view(s) : std::string_view()) {}
  explicit FixedString(std::string_view s) { assign(s.substr(0, s.size() < MaxLen ? s.size() : MaxLen)); }

  // Returns false (and stores nothing) when s does not fit.
  bool assign(std::string_view s) noexcept {
    if (s.size() > MaxLen) return false;
    // memcpy from a null source is undefined even for zero bytes (default string_view).
    if (!s.empty()) std::memcpy(data_, s.data(), s.size());
    data_[s.size()] = '\0';
    size_ = s.size();
    return true;
  }

  static constexpr std::size_t max_size() { return MaxLen; }
  std::size_t size() const noexcept { return size_; }
  bool empty() const noexcept { return size_ == 0; }
  const char* c_str() const noexcept { return data_; }
  std::string_view view() const noexcept { return {data_, size_}; }
  operator std::string_view() const noexcept { return view(); }  // NOLINT

  friend bool operator==(const FixedString& a, const FixedString& b) { return a.view() == b.view(); }
  friend bool operator!=(const FixedString& a, const FixedString& b) { return !(a == b); }
  friend bool operator==(const FixedString& a, std::string_view b) { return a.view() == b; }
  friend bool operator!=(const FixedString& a, std::string_view b) { return a.view() != b; }
  friend bool operator==(std::string_view a, const FixedString& b) { return a == b.view(); }
  friend bool operator!=(std::string_view a, const FixedString& b) { return a != b.view(); }
  // Without these, `name == "literal"` is ambiguous between the two overloads above
  // (both need one user-defined conversion).
  friend bool operator==(const FixedString& a, const char* b) { return a.view() == std::string_view(b); }
  friend bool operator!=(const FixedString& a, const char* b) { return !(a == b); }
  friend bool operator==(const char* a, const FixedString& b) { return b == a; }
  friend bool operator!=(const char* a, const FixedString& b) { return !(b == a); }

 private:
  char data_[MaxLen + 1] = {};
  std::size_t size_ = 0;
};

}  // namespace rtfuse
