#pragma once
// What the fusion tests feed the loop's real input path: a configuration
// from TOML text and encoded LCM messages.
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/time.hpp"
#include "rtfuse/odometry_t.hpp"
#include "runtime/config/config_loader.hpp"

namespace rtfuse::test {

// The configuration, or a default one with every error a test failure.
inline RuntimeConfig load_config_text(const std::string& text) {
  ConfigLoadResult r = load_config_string(text, "test.toml");
  if (!r.config) {
    for (const auto& e : r.errors) ADD_FAILURE() << e.to_string();
    return RuntimeConfig{};
  }
  return *r.config;
}

template <class Msg>
std::vector<std::uint8_t> encode(const Msg& m) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

// Wheel odometry in odom -> base_link: forward speed vx, a twist
// covariance of 1e-4 on the diagonal, no pose.
inline std::vector<std::uint8_t> wheel_odometry(TimeNs t, double vx) {
  rtfuse::odometry_t m{};
  m.header.utime = ns_to_utime(t);
  m.header.frame_id = "odom";
  m.child_frame_id = "base_link";
  m.pose.pose.orientation.w = 1.0;
  for (int i = 0; i < 6; ++i) m.twist.covariance[i * 7] = 1e-4;
  m.twist.twist.linear.x = vx;
  return encode(m);
}

}  // namespace rtfuse::test
