#include <gtest/gtest.h>

#include <cstdint>

#include "drivers/canopen/position_unwrap.hpp"

namespace canopen_unwrap_test {

using rtfuse::drivers::position_from_raw;
using rtfuse::drivers::read_le;
using rtfuse::drivers::wrapped_delta;

TEST(CanopenUnwrap, ReadsLittleEndianAtAnyOffset) {
  rtfuse::hal::CanFrame f;
  f.dlc = 8;
  const std::uint8_t bytes[8] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88};
  for (int i = 0; i < 8; ++i) f.data[i] = bytes[i];
  EXPECT_EQ(read_le(f, 0, 4), 0x44332211U);
  EXPECT_EQ(read_le(f, 4, 4), 0x88776655U);
  EXPECT_EQ(read_le(f, 5, 3), 0x887766U);
  EXPECT_EQ(read_le(f, 7, 1), 0x88U);
  EXPECT_EQ(read_le(f, 2, 2), 0x4433U);
}

TEST(CanopenUnwrap, SignedValuesAreTwosComplementAtEachWidth) {
  EXPECT_EQ(position_from_raw(0x80, 8, true), -128);
  EXPECT_EQ(position_from_raw(0x80, 8, false), 128);
  EXPECT_EQ(position_from_raw(0x7F, 8, true), 127);
  EXPECT_EQ(position_from_raw(0xFFFF, 16, true), -1);
  EXPECT_EQ(position_from_raw(0x800000, 24, true), -8388608);
  EXPECT_EQ(position_from_raw(0xFFFFFF, 24, false), 16777215);
  EXPECT_EQ(position_from_raw(0x80000000U, 32, true), -2147483648LL);
  EXPECT_EQ(position_from_raw(0xFFFFFFFFU, 32, false), 4294967295LL);
}

TEST(CanopenUnwrap, DeltaTakesTheShortestWayAcrossTheWrap) {
  EXPECT_EQ(wrapped_delta(5, 250, 8), 11);     // 250 -> 255 -> 0 -> 5
  EXPECT_EQ(wrapped_delta(250, 5, 8), -11);
  EXPECT_EQ(wrapped_delta(127, 0, 8), 127);    // just under half the range
  EXPECT_EQ(wrapped_delta(128, 0, 8), -128);   // half the range is ambiguous: taken as backwards
  EXPECT_EQ(wrapped_delta(0x0010, 0xFFF0, 16), 0x20);
  EXPECT_EQ(wrapped_delta(0x000100, 0xFFFF00, 24), 0x200);
  EXPECT_EQ(wrapped_delta(0x00000010U, 0xFFFFFFF0U, 32), 0x20);
  EXPECT_EQ(wrapped_delta(0xFFFFFFF0U, 0x00000010U, 32), -0x20);
  EXPECT_EQ(wrapped_delta(0x7FFFFFFFU, 0, 32), 0x7FFFFFFF);
  // Bits above the width (a wider read) do not leak in.
  EXPECT_EQ(wrapped_delta(0x1005, 0x20FA, 8), 11);
}

}  // namespace canopen_unwrap_test
