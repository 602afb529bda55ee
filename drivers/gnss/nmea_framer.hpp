#pragma once
// NMEA 0183 sentences out of a byte stream: "$" address "," fields "*" two
// hex digits, then CR LF (or either alone: receivers differ). Only whole
// sentences with a correct checksum come out; everything else is counted,
// never thrown away silently. A receiver that restarts or a UART that drops
// bytes cuts a sentence: the next "$" starts a new one and the cut one is
// counted. Bytes between sentences (UBX binary on a shared port, line noise)
// are skipped and counted. No allocation: one sentence buffer.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/time.hpp"

namespace rtfuse::drivers {

struct NmeaFramerStats {
  std::int64_t sentences = 0;          // whole, checksum correct
  std::int64_t bad_checksum = 0;
  std::int64_t missing_checksum = 0;   // no "*hh" before the line end
  std::int64_t overlong = 0;           // longer than kMaxSentence before its line end
  std::int64_t cut = 0;                // a "$" or a control byte inside a sentence
  std::int64_t skipped_bytes = 0;      // outside any sentence
};

class NmeaFramer {
 public:
  // The standard allows 82 characters with "$" and CR LF; receivers'
  // proprietary sentences (u-blox PUBX,00) run longer.
  static constexpr std::size_t kMaxSentence = 160;

  struct Sentence {
    std::string_view text;  // from the first character after "$" to before "*": valid until the next push()
    TimeNs stamp = 0;       // receive time of its "$"
  };

  // Feeds one byte received at `stamp`. True when it completed a valid
  // sentence, then in *out.
  bool push(std::uint8_t byte, TimeNs stamp, Sentence* out) noexcept;

  const NmeaFramerStats& stats() const noexcept { return stats_; }

 private:
  bool finish(Sentence* out) noexcept;

  char buf_[kMaxSentence] = {};
  std::size_t len_ = 0;
  bool in_sentence_ = false;
  bool overlong_ = false;
  TimeNs start_ = 0;
  NmeaFramerStats stats_;
};

}  // namespace rtfuse::drivers
