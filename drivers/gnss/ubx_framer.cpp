#include "drivers/gnss/ubx_framer.hpp"

namespace rtfuse::drivers {

namespace {
constexpr std::uint8_t kSync1 = 0xB5;
constexpr std::uint8_t kSync2 = 0x62;
}  // namespace

void UbxFramer::restart(std::uint8_t byte, TimeNs stamp) noexcept {
  // This byte may itself start the next frame.
  state_ = State::kSync1;
  if (byte == kSync1) {
    state_ = State::kSync2;
    start_ = stamp;
  } else {
    ++stats_.skipped_bytes;
  }
}

bool UbxFramer::push(std::uint8_t byte, TimeNs stamp, Frame* out) noexcept {
  const auto sum = [this](std::uint8_t b) {
    ck_a_ = static_cast<std::uint8_t>(ck_a_ + b);
    ck_b_ = static_cast<std::uint8_t>(ck_b_ + ck_a_);
  };
  switch (state_) {
    case State::kSync1:
      restart(byte, stamp);
      return false;
    case State::kSync2:
      if (byte == kSync2) {
        state_ = State::kClass;
        ck_a_ = ck_b_ = 0;
      } else {
        ++stats_.skipped_bytes;  // the lone 0xB5
        restart(byte, stamp);
      }
      return false;
    case State::kClass:
      class_ = byte;
      sum(byte);
      state_ = State::kId;
      return false;
    case State::kId:
      id_ = byte;
      sum(byte);
      state_ = State::kLength1;
      return false;
    case State::kLength1:
      length_ = byte;
      sum(byte);
      state_ = State::kLength2;
      return false;
    case State::kLength2:
      length_ |= static_cast<std::size_t>(byte) << 8;
      sum(byte);
      if (length_ > kMaxPayload) {
        ++stats_.oversize;
        state_ = State::kSync1;
        return false;
      }
      got_ = 0;
      state_ = length_ == 0 ? State::kCkA : State::kPayload;
      return false;
    case State::kPayload:
      payload_[got_++] = byte;
      sum(byte);
      if (got_ == length_) state_ = State::kCkA;
      return false;
    case State::kCkA:
      rx_ck_a_ = byte;
      state_ = State::kCkB;
      return false;
    case State::kCkB:
      state_ = State::kSync1;
      if (rx_ck_a_ != ck_a_ || byte != ck_b_) {
        ++stats_.bad_checksum;
        return false;
      }
      ++stats_.frames;
      out->msg_class = class_;
      out->msg_id = id_;
      out->payload = payload_;
      out->length = length_;
      out->stamp = start_;
      return true;
  }
  return false;
}

}  // namespace rtfuse::drivers
