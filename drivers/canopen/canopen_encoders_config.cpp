#include "drivers/canopen/canopen_encoders_config.hpp"

#include <cmath>
#include <cstdio>

#include "drivers/config_error.hpp"

namespace rtfuse::drivers {

namespace {

constexpr const char* kWho = "canopen encoders";

// The ids a node answers on besides its TPDO: each must belong to one object.
struct NodeIds {
  std::uint32_t tpdo, emcy, heartbeat;
};

NodeIds ids_of(const EncoderNodeConfig& n) {
  return {effective_tpdo_cob_id(n), cia301::kEmcyBase + n.node_id, cia301::kHeartbeatBase + n.node_id};
}

}  // namespace

std::uint32_t effective_tpdo_cob_id(const EncoderNodeConfig& node) noexcept {
  return node.tpdo.cob_id != 0 ? node.tpdo.cob_id : cia301::kTpdo1Base + node.node_id;
}

bool validate_config(const CanopenEncodersConfig& c, std::string* error) {
  if (c.node_count < 1 || c.node_count > kMaxEncoderNodes) {
    return config_fail(error, kWho, "node_count = %d: configure 1..%d encoder nodes", c.node_count, kMaxEncoderNodes);
  }
  if (c.sync_cob_id == 0 || c.sync_cob_id > cia301::kMaxStandardId) {
    return config_fail(error, kWho, "sync_cob_id = 0x%X: must be an 11-bit COB-ID 0x001..0x7FF (CiA 301 default 0x080)",
                static_cast<unsigned>(c.sync_cob_id));
  }
  for (int i = 0; i < c.node_count; ++i) {
    const EncoderNodeConfig& n = c.nodes[static_cast<std::size_t>(i)];
    if (n.node_id < 1 || n.node_id > 127) {
      return config_fail(error, kWho, "nodes[%d].node_id = %d: a CANopen node-id is 1..127 (the encoder's LSS/DIP setting)", i,
                  n.node_id);
    }
    const int w = n.tpdo.width_bits;
    if (w != 8 && w != 16 && w != 24 && w != 32) {
      return config_fail(error, kWho, "nodes[%d].tpdo.width_bits = %d: the position value must be 8, 16, 24 or 32 bits wide", i, w);
    }
    if (n.tpdo.byte_offset + w / 8 > 8) {
      return config_fail(error, kWho,
                  "nodes[%d].tpdo: byte_offset %d + %d bytes runs past the 8-byte PDO; check the TPDO mapping "
                  "(objects 0x1A00..)",
                  i, n.tpdo.byte_offset, w / 8);
    }
    const std::uint32_t tpdo = effective_tpdo_cob_id(n);
    if (tpdo > cia301::kMaxStandardId || tpdo == cia301::kNmtCobId) {
      return config_fail(error, kWho, "nodes[%d].tpdo.cob_id = 0x%X: must be an 11-bit COB-ID 0x001..0x7FF (0 = 0x180 + node_id)",
                  i, static_cast<unsigned>(tpdo));
    }
    if (!std::isfinite(n.max_counts_per_s) || n.max_counts_per_s < 0.0) {
      return config_fail(error, kWho, "nodes[%d].max_counts_per_s = %g: must be >= 0 (0 = the global limit)", i,
                  n.max_counts_per_s);
    }
  }
  // Every object id of every node must be unique on the bus and differ from SYNC.
  for (int i = 0; i < c.node_count; ++i) {
    const NodeIds a = ids_of(c.nodes[static_cast<std::size_t>(i)]);
    const std::uint32_t mine[3] = {a.tpdo, a.emcy, a.heartbeat};
    for (std::uint32_t id : mine) {
      if (id == c.sync_cob_id) {
        return config_fail(error, kWho, "nodes[%d] (node-id %d) uses COB-ID 0x%X, which is the SYNC COB-ID; change sync_cob_id or "
                    "the node's TPDO cob_id", i, c.nodes[static_cast<std::size_t>(i)].node_id,
                    static_cast<unsigned>(id));
      }
    }
    if (a.tpdo == a.emcy || a.tpdo == a.heartbeat) {
      return config_fail(error, kWho, "nodes[%d].tpdo.cob_id = 0x%X collides with the node's own EMCY/heartbeat COB-ID", i,
                  static_cast<unsigned>(a.tpdo));
    }
    for (int j = i + 1; j < c.node_count; ++j) {
      const EncoderNodeConfig& nj = c.nodes[static_cast<std::size_t>(j)];
      if (nj.node_id == c.nodes[static_cast<std::size_t>(i)].node_id) {
        return config_fail(error, kWho, "nodes[%d] and nodes[%d] both have node_id %d: every node needs its own id", i, j,
                    nj.node_id);
      }
      const NodeIds b = ids_of(nj);
      const std::uint32_t theirs[3] = {b.tpdo, b.emcy, b.heartbeat};
      for (std::uint32_t x : mine) {
        for (std::uint32_t y : theirs) {
          if (x == y) {
            return config_fail(error, kWho, "nodes[%d] and nodes[%d] both use COB-ID 0x%X: give each TPDO its own cob_id", i, j,
                        static_cast<unsigned>(x));
          }
        }
      }
    }
  }
  if (c.heartbeat_timeout_ns < 0) {
    return config_fail(error, kWho, "heartbeat_timeout_ns = %lld: must be >= 0 (0 disables heartbeat supervision)",
                static_cast<long long>(c.heartbeat_timeout_ns));
  }
  if (c.tpdo_timeout_syncs < 1) {
    return config_fail(error, kWho, "tpdo_timeout_syncs = %d: must be >= 1 SYNC", c.tpdo_timeout_syncs);
  }
  if (!std::isfinite(c.max_counts_per_s) || c.max_counts_per_s < 0.0) {
    return config_fail(error, kWho, "max_counts_per_s = %g: must be >= 0 (0 disables jump detection)", c.max_counts_per_s);
  }
  if (c.stuck_time_ns < 0) {
    return config_fail(error, kWho, "stuck_time_ns = %lld: must be >= 0 (0 disables stuck detection)",
                static_cast<long long>(c.stuck_time_ns));
  }
  if (c.stuck_time_ns > 0 && c.stuck_min_counts < 1) {
    return config_fail(error, kWho, "stuck_min_counts = %lld: must be >= 1 when stuck detection is on",
                static_cast<long long>(c.stuck_min_counts));
  }
  if (c.nmt_restart_interval_ns < 0) {
    return config_fail(error, kWho, "nmt_restart_interval_ns = %lld: must be >= 0", static_cast<long long>(c.nmt_restart_interval_ns));
  }
  if (c.max_frames_per_poll < 1 || c.max_frames_per_poll > 4096) {
    return config_fail(error, kWho, "max_frames_per_poll = %d: must be 1..4096 (several frames per node per SYNC)",
                c.max_frames_per_poll);
  }
  return true;
}

}  // namespace rtfuse::drivers
