#include "drivers/gnss/nmea_framer.hpp"

namespace rtfuse::drivers {

namespace {

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

}  // namespace

bool NmeaFramer::push(std::uint8_t byte, TimeNs stamp, Sentence* out) noexcept {
  const char c = static_cast<char>(byte);
  if (c == '$') {
    if (in_sentence_) ++stats_.cut;
    in_sentence_ = true;
    overlong_ = false;
    len_ = 0;
    start_ = stamp;
    return false;
  }
  if (!in_sentence_) {
    if (c != '\r' && c != '\n') ++stats_.skipped_bytes;  // the LF of a CR LF is no stray byte
    return false;
  }
  if (c == '\r' || c == '\n') {
    in_sentence_ = false;
    if (overlong_) {
      ++stats_.overlong;
      return false;
    }
    return finish(out);
  }
  if (byte < 0x20 || byte > 0x7e) {  // NMEA is printable ASCII: binary or noise cut the sentence
    in_sentence_ = false;
    ++stats_.cut;
    return false;
  }
  if (len_ == kMaxSentence) {
    overlong_ = true;  // counted at its end, so one long line is one count
    return false;
  }
  buf_[len_++] = c;
  return false;
}

bool NmeaFramer::finish(Sentence* out) noexcept {
  // "...*hh": the checksum is the XOR of every character between "$" and "*".
  if (len_ < 3 || buf_[len_ - 3] != '*') {
    ++stats_.missing_checksum;
    return false;
  }
  const int hi = hex_value(buf_[len_ - 2]);
  const int lo = hex_value(buf_[len_ - 1]);
  if (hi < 0 || lo < 0) {
    ++stats_.missing_checksum;
    return false;
  }
  unsigned sum = 0;
  for (std::size_t i = 0; i + 3 < len_; ++i) sum ^= static_cast<unsigned char>(buf_[i]);
  if (sum != static_cast<unsigned>(hi * 16 + lo)) {
    ++stats_.bad_checksum;
    return false;
  }
  ++stats_.sentences;
  out->text = std::string_view(buf_, len_ - 3);
  out->stamp = start_;
  return true;
}

}  // namespace rtfuse::drivers
