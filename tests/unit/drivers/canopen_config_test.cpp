#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "drivers/canopen/canopen_encoders_config.hpp"

namespace canopen_config_test {

using rtfuse::drivers::CanopenEncodersConfig;
using rtfuse::drivers::effective_tpdo_cob_id;
using rtfuse::drivers::validate_config;

CanopenEncodersConfig two_nodes() {
  CanopenEncodersConfig c;
  c.node_count = 2;
  c.nodes[0].node_id = 1;
  c.nodes[1].node_id = 2;
  return c;
}

// The error must name the field so the user can find the TOML key.
void expect_error(const CanopenEncodersConfig& c, const std::string& field) {
  std::string error;
  EXPECT_FALSE(validate_config(c, &error));
  EXPECT_NE(error.find(field), std::string::npos) << error;
}

TEST(CanopenConfig, DefaultsAreCia406PositionInTpdo1) {
  const CanopenEncodersConfig c = two_nodes();
  std::string error;
  EXPECT_TRUE(validate_config(c, &error)) << error;
  EXPECT_EQ(effective_tpdo_cob_id(c.nodes[0]), 0x181U);
  EXPECT_EQ(effective_tpdo_cob_id(c.nodes[1]), 0x182U);
  EXPECT_EQ(c.nodes[0].tpdo.width_bits, 32);
  EXPECT_FALSE(c.nodes[0].tpdo.is_signed);
  EXPECT_EQ(c.sync_cob_id, 0x080U);
  EXPECT_EQ(c.heartbeat_timeout_ns, 500'000'000);
  EXPECT_EQ(c.tpdo_timeout_syncs, 5);
}

TEST(CanopenConfig, RejectsEachImpossibleValueNamingIt) {
  CanopenEncodersConfig c = two_nodes();
  c.node_count = 0;
  expect_error(c, "node_count = 0");
  c = two_nodes();
  c.node_count = 9;
  expect_error(c, "node_count = 9");
  c = two_nodes();
  c.nodes[1].node_id = 0;
  expect_error(c, "nodes[1].node_id = 0");
  c = two_nodes();
  c.nodes[1].node_id = 128;
  expect_error(c, "nodes[1].node_id = 128");
  c = two_nodes();
  c.nodes[0].tpdo.width_bits = 12;
  expect_error(c, "nodes[0].tpdo.width_bits = 12");
  c = two_nodes();
  c.nodes[0].tpdo.byte_offset = 6;
  expect_error(c, "nodes[0].tpdo: byte_offset 6");
  c = two_nodes();
  c.nodes[0].tpdo.cob_id = 0x800;
  expect_error(c, "nodes[0].tpdo.cob_id = 0x800");
  c = two_nodes();
  c.nodes[1].node_id = 1;
  expect_error(c, "both have node_id 1");
  c = two_nodes();
  c.nodes[1].tpdo.cob_id = 0x181;  // node 1's TPDO1
  expect_error(c, "both use COB-ID 0x181");
  c = two_nodes();
  c.nodes[0].tpdo.cob_id = 0x080;
  expect_error(c, "SYNC COB-ID");
  c = two_nodes();
  c.nodes[0].tpdo.cob_id = 0x701;
  expect_error(c, "own EMCY/heartbeat");
  c = two_nodes();
  c.sync_cob_id = 0;
  expect_error(c, "sync_cob_id = 0x0");
  c = two_nodes();
  c.tpdo_timeout_syncs = 0;
  expect_error(c, "tpdo_timeout_syncs = 0");
  c = two_nodes();
  c.heartbeat_timeout_ns = -1;
  expect_error(c, "heartbeat_timeout_ns = -1");
  c = two_nodes();
  c.max_counts_per_s = -5.0;
  expect_error(c, "max_counts_per_s = -5");
  c = two_nodes();
  c.nodes[1].max_counts_per_s = std::nan("");
  expect_error(c, "nodes[1].max_counts_per_s");
  c = two_nodes();
  c.stuck_min_counts = 0;
  expect_error(c, "stuck_min_counts = 0");
  c = two_nodes();
  c.max_frames_per_poll = 0;
  expect_error(c, "max_frames_per_poll = 0");
}

TEST(CanopenConfig, StuckMinCountsIsFreeWhenStuckDetectionIsOff) {
  CanopenEncodersConfig c = two_nodes();
  c.stuck_time_ns = 0;
  c.stuck_min_counts = 0;
  EXPECT_TRUE(validate_config(c, nullptr));
}

}  // namespace canopen_config_test
