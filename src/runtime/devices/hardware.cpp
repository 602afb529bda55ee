#include "runtime/devices/hardware.hpp"

namespace rtfuse {

Hardware::Hardware(const RuntimeConfig& cfg) : slots_(device_slots(cfg)) {
  describe_devices(cfg, layout_, kMaxDevices);
}

std::unique_ptr<Hardware> Hardware::create(const HalBuses& buses, FusionCore& core, std::string* error) {
  const RuntimeConfig& cfg = core.config();
  std::unique_ptr<Hardware> h(new Hardware(cfg));
  const HardwareConfig& hw = cfg.hardware;
  if (hw.can.enabled) {
    if (buses.can == nullptr) {
      *error = "[can] is configured but the HAL has no CAN bus";
      return nullptr;
    }
    h->wheels_ = WheelEncoderDevice::create(*buses.can, core, h->slots_, error);
    if (!h->wheels_) return nullptr;
  }
  if (hw.mpu.enabled) {
    h->imu_ = ImuDevice::create(buses.imu, core, h->slots_.imu, error);
    if (!h->imu_) return nullptr;
    h->threaded_[h->num_threaded_++] = h->imu_.get();
  }
  if (hw.camera.enabled) {
    h->camera_ = CameraDevice::create(buses.camera, core, h->slots_.camera, h->slots_.vo, error);
    if (!h->camera_) return nullptr;
    h->threaded_[h->num_threaded_++] = h->camera_.get();
  }
  if (hw.gnss.enabled) {
    h->gnss_ = GnssDevice::create(buses.gnss, core, h->slots_.gnss, error);
    if (!h->gnss_) return nullptr;
    h->threaded_[h->num_threaded_++] = h->gnss_.get();
  }
  return h;
}

bool Hardware::start(TimeNs now, std::string* error) {
  if (wheels_ && !wheels_->start(now, error)) return false;
  if (imu_ && !imu_->start(error)) return false;
  return true;
}

void Hardware::before_drain(TimeNs now) noexcept {
  if (wheels_) wheels_->before_drain(now);
}

void Hardware::fill_snapshot(Snapshot& s) noexcept {
  s.num_devices = slots_.count;
  for (int i = 0; i < slots_.count; ++i) {
    s.devices[i].name = layout_[i].name;
    s.devices[i].hardware_id = layout_[i].hardware_id;
  }
  if (wheels_) wheels_->fill_snapshot(s);
  for (int i = 0; i < num_threaded_; ++i) threaded_[i]->fill_snapshot(s);
}

}  // namespace rtfuse
