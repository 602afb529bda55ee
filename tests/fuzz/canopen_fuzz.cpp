// The CANopen encoder master on a bus where anything can arrive: TPDOs,
// heartbeats and EMCYs of configured and unknown nodes with any length and
// payload, extended and remote frames, error frames, bus-state changes,
// stamps out of order, polls at any interval. The input draws the master's
// configuration, then a script of those events.
// Property: the master keeps its own books straight: a valid reading is
// healthy, a sample set counts its valid readings right, and the frame
// counters add up to what the bus delivered.
#include <fuzzer/FuzzedDataProvider.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "drivers/canopen/canopen_encoders.hpp"
#include "drivers/canopen/cia301.hpp"
#include "fuzz_check.hpp"
#include "hal/mock/mock_can_bus.hpp"

using namespace rtfuse::drivers;
using rtfuse::TimeNs;
using rtfuse::hal::CanBusState;
using rtfuse::hal::CanFrame;
using rtfuse::hal::mock::MockCanBus;

namespace {

CanopenEncodersConfig draw_config(FuzzedDataProvider& in) {
  CanopenEncodersConfig c;
  c.node_count = in.ConsumeIntegralInRange(1, 3);
  for (int i = 0; i < c.node_count; ++i) {
    EncoderNodeConfig& n = c.nodes[static_cast<std::size_t>(i)];
    n.node_id = in.ConsumeIntegralInRange<std::uint8_t>(1, 127);
    const std::uint8_t widths[] = {8, 16, 24, 32};
    n.tpdo.width_bits = widths[in.ConsumeIntegralInRange(0, 3)];
    n.tpdo.byte_offset = in.ConsumeIntegralInRange<std::uint8_t>(0, 8 - n.tpdo.width_bits / 8);
    n.tpdo.is_signed = in.ConsumeBool();
    if (in.ConsumeBool()) n.tpdo.cob_id = in.ConsumeIntegralInRange<std::uint32_t>(0, 0x7FF);
  }
  const double rates[] = {0.0, 1000.0, 1e6};
  c.max_counts_per_s = rates[in.ConsumeIntegralInRange(0, 2)];
  c.heartbeat_timeout_ns = in.ConsumeBool() ? 0 : 100'000'000;
  c.tpdo_timeout_syncs = in.ConsumeIntegralInRange(1, 8);
  c.stuck_time_ns = in.ConsumeBool() ? 0 : 50'000'000;
  c.stuck_min_counts = in.ConsumeIntegralInRange<std::int64_t>(0, 1000);
  c.max_frames_per_poll = in.ConsumeIntegralInRange(1, 32);
  return c;
}

// Mostly the ids the master listens to, so the script reaches its logic.
std::uint32_t draw_id(FuzzedDataProvider& in, const CanopenEncodersConfig& c) {
  const EncoderNodeConfig& n = c.nodes[in.ConsumeIntegralInRange(0, c.node_count - 1)];
  switch (in.ConsumeIntegralInRange(0, 4)) {
    case 0: return effective_tpdo_cob_id(n);
    case 1: return cia301::kHeartbeatBase + n.node_id;
    case 2: return cia301::kEmcyBase + n.node_id;
    case 3: return c.sync_cob_id;
    default: return in.ConsumeIntegral<std::uint32_t>();
  }
}

void check_books(const CanopenEncoders& enc) {
  const EncoderSampleSet& set = enc.last_set();
  FUZZ_CHECK(set.node_count == 0 || set.node_count == enc.node_count(), "a set has every node");
  int valid = 0;
  for (int i = 0; i < set.node_count; ++i) {
    const EncoderReading& r = set.readings[i];
    if (r.valid) ++valid;
    FUZZ_CHECK(r.valid == (r.health == EncoderHealth::kOk), "valid exactly when healthy");
  }
  FUZZ_CHECK(valid == set.valid_count, "valid_count counts the valid readings");
  for (int i = 0; i < enc.node_count(); ++i) {
    const EncoderReading& r = enc.reading(i);
    FUZZ_CHECK(r.valid == (r.health == EncoderHealth::kOk), "valid exactly when healthy");
    FUZZ_CHECK(to_string(r.health) != nullptr, "every health has a name");
  }
  const CanopenBusStats& b = enc.bus_stats();
  FUZZ_CHECK(b.malformed_frames + b.unexpected_cob_ids + b.rtr_frames + b.error_frames <= b.frames_received,
             "no frame is counted twice");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  const CanopenEncodersConfig config = draw_config(in);
  MockCanBus bus;
  std::string error;
  std::unique_ptr<CanopenEncoders> enc = CanopenEncoders::create(bus, config, &error);
  if (!enc) {
    FUZZ_CHECK(!error.empty(), "a refused configuration says why");
    return 0;
  }
  TimeNs now = 1'000'000'000;
  bus.set_time(now);
  enc->start(now);
  std::int64_t delivered = 0;
  for (int step = 0; step < 4096 && in.remaining_bytes() > 0; ++step) {
    switch (in.ConsumeIntegralInRange(0, 4)) {
      case 0:
      case 1: {
        CanFrame f;
        f.id = draw_id(in, config);
        f.extended = in.ConsumeProbability<float>() < 0.05f;
        f.rtr = in.ConsumeProbability<float>() < 0.05f;
        f.id &= f.extended ? 0x1FFFFFFFu : 0x7FFu;
        f.dlc = in.ConsumeIntegralInRange<std::uint8_t>(0, 8);
        for (int b = 0; b < f.dlc; ++b) f.data[b] = in.ConsumeIntegral<std::uint8_t>();
        // A stamp a little before or after now: frames queued late, clocks jittering.
        const TimeNs stamp = now + in.ConsumeIntegralInRange<TimeNs>(-10'000'000, 10'000'000);
        if (bus.inject_at(f, stamp)) ++delivered;
        break;
      }
      case 2: {
        CanFrame f;
        f.error = true;
        f.id = in.ConsumeBool() ? (in.ConsumeBool() ? cia301::kCanErrBusOff : cia301::kCanErrRestarted)
                                : in.ConsumeIntegral<std::uint32_t>() & 0x1FFFFFFFu;
        f.dlc = 8;
        for (auto& b : f.data) b = in.ConsumeIntegral<std::uint8_t>();
        if (bus.inject(f)) ++delivered;
        break;
      }
      case 3:
        bus.set_state(static_cast<CanBusState>(in.ConsumeIntegralInRange(0, 4)));
        break;
      default: {
        now += in.ConsumeIntegralInRange<TimeNs>(0, 20'000'000);
        bus.set_time(now);
        enc->poll(now);
        EncoderSampleSet set;
        while (enc->take_sample_set(&set)) {
          FUZZ_CHECK(set.node_count == enc->node_count(), "a set has every node");
        }
        check_books(*enc);
        break;
      }
    }
  }
  enc->poll(now + 5'000'000);
  check_books(*enc);
  FUZZ_CHECK(enc->bus_stats().frames_received <= delivered, "no more frames than the bus delivered");
  return 0;
}
