#include "runtime/devices/hardware.hpp"

#include "runtime/devices/frame_consumer.hpp"
#include "runtime/devices/grid_consumer.hpp"
#include "runtime/devices/device_layout.hpp"
#include "runtime/fusion/navsat_status.hpp"
#include "runtime/fusion/standstill_status.hpp"

namespace rtfuse {
namespace {

std::string missing_buses(std::uint32_t missing) {
  std::string out;
  for (int k = 0; k < kBusKinds; ++k) {
    if ((missing & (1u << k)) == 0) continue;
    if (!out.empty()) out += ", ";
    out += to_string(static_cast<BusKind>(k));
  }
  return out;
}

}  // namespace

std::unique_ptr<Hardware> Hardware::create(const HalBuses& buses, FusionCore& core, std::string* error) {
  const RuntimeConfig& cfg = core.config();
  std::unique_ptr<Hardware> h(new Hardware());
  const DeviceLayout layout = device_layout(cfg);
  const int slots = layout.device_slots + navsat_slot_count(cfg) + standstill_slot_count(cfg);
  if (slots > kMaxDevices) {
    *error = "the configuration's devices, navsat transforms and gyro bias learners need " + std::to_string(slots) +
             " diagnostics slots, more than the " + std::to_string(kMaxDevices) + " a snapshot holds";
    return nullptr;
  }
  describe_devices(cfg, h->layout_, kMaxDevices);
  h->slot_count_ = layout.device_slots;
  for (int i = 0; i < device_type_count(); ++i) {
    const DeviceDescriptor& d = device_type(i);
    if (!d.enabled(cfg)) continue;
    const DeviceBuses& b = buses.device[i];
    const std::uint32_t missing = d.required_buses(cfg) & ~b.present();
    if (missing != 0) {
      *error = "[" + std::string(d.sections().front()) + "] is configured but the HAL has no " +
               missing_buses(missing);
      return nullptr;
    }
    DeviceContext ctx{core, layout.first_slot[i], nullptr};
    if (d.host() != nullptr) {
      const int host = find_device_type(d.host());
      ctx.host = host >= 0 ? h->devices_[host].get() : nullptr;
    }
    std::unique_ptr<Device> device = d.create(ctx, b, error);
    if (!device) return nullptr;
    if (ctx.host != nullptr && ctx.host->frame_source() != nullptr && device->frame_consumer() != nullptr &&
        !ctx.host->frame_source()->attach(*device->frame_consumer(), error)) {
      return nullptr;
    }
    if (ctx.host != nullptr && ctx.host->grid_source() != nullptr && device->grid_consumer() != nullptr &&
        !ctx.host->grid_source()->attach(*device->grid_consumer(), error)) {
      return nullptr;
    }
    const std::vector<std::string> channels = d.input_channels(cfg);
    for (std::size_t k = 0; k < channels.size(); ++k) {
      h->inputs_.push_back(Input{i, static_cast<int>(k), channels[k]});
    }
    switch (d.scheduling()) {
      case DeviceScheduling::kPolled: h->polled_[h->num_polled_++] = i; break;
      case DeviceScheduling::kThread: h->threaded_[h->num_threaded_++] = i; break;
      case DeviceScheduling::kHostThread: break;
      case DeviceScheduling::kWorker: h->workers_[h->num_workers_++] = i; break;
    }
    h->devices_[i] = std::move(device);
  }
  return h;
}

bool Hardware::start(TimeNs now, std::string* error) {
  for (const std::unique_ptr<Device>& d : devices_) {
    if (d && !d->start(now, error)) return false;
  }
  return true;
}

void Hardware::before_drain(TimeNs now) noexcept {
  for (int i = 0; i < num_polled_; ++i) devices_[polled_[i]]->poll(now);
}

void Hardware::fill_snapshot(Snapshot& s) noexcept {
  if (s.num_devices < slot_count_) s.num_devices = slot_count_;
  for (int i = 0; i < slot_count_; ++i) {
    s.devices[i].name = layout_[i].name;
    s.devices[i].hardware_id = layout_[i].hardware_id;
  }
  for (const std::unique_ptr<Device>& d : devices_) {
    if (d) d->fill_snapshot(s);
  }
}

void Hardware::deliver_input(int i, const std::uint8_t* data, int size, TimeNs now) noexcept {
  if (i < 0 || i >= input_count()) return;
  const Input& in = inputs_[static_cast<std::size_t>(i)];
  devices_[in.device]->on_input(in.index, data, size, now);
}

std::int64_t Hardware::input_taken(int i) const noexcept {
  if (i < 0 || i >= input_count()) return 0;
  const Input& in = inputs_[static_cast<std::size_t>(i)];
  return devices_[in.device]->inputs_taken(in.index);
}

int Hardware::find_input(std::string_view channel) const noexcept {
  for (std::size_t i = 0; i < inputs_.size(); ++i) {
    if (inputs_[i].channel == channel) return static_cast<int>(i);
  }
  return -1;
}

void Hardware::step_workers() noexcept {
  for (int i = 0; i < num_workers_; ++i) devices_[workers_[i]]->step(0);
}

void Hardware::finish_workers() noexcept {
  for (int i = 0; i < num_workers_; ++i) devices_[workers_[i]]->finish();
}

void Hardware::publish_due(TimeNs now, transport::MessageSink& sink) noexcept {
  for (const std::unique_ptr<Device>& d : devices_) {
    if (d) d->publish_due(now, sink);
  }
}

}  // namespace rtfuse
