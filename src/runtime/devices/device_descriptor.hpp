#pragma once
// Everything the runtime needs to know about one kind of device, in one
// place: its configuration sections and their checks, the [[sensor]]
// sources it feeds, the buses it needs and how the kernel provides them,
// whether the loop polls it or it runs on a thread of its own (or on another
// device's frames), its recording stream, its diagnostics slots, and the
// device object itself. The config loader, the Linux backend, the recording
// tap, the HAL replay, the device set and the simulated robot loop over the
// registered descriptors (device_registry.cpp) and never name a device.
//
// A descriptor is stateless; every call but create() is configuration or
// start-up work and may allocate.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "estimation/sensor_sample.hpp"
#include "runtime/config/config.hpp"
#include "runtime/devices/device.hpp"
#include "runtime/devices/device_buses.hpp"
#include "runtime/fusion/device_status.hpp"
#include "transport/recording_info.hpp"

namespace rtfuse {

class FusionCore;

namespace config {
class Section;
}

enum class DeviceScheduling : std::uint8_t {
  kPolled,      // the loop calls poll() inside its tick; its bus calls are the loop's stream
  kThread,      // step() on a thread of its own; its bus calls are the stream of its name
  kHostThread,  // a frame consumer of its host(), called on the host's thread with each pair
  // A consumer of its host()'s pairs and the loop's estimates that works on
  // a thread of its own at a lower priority (the mapper): live, step() on
  // that thread; a replay or a lockstep drive, step(0) after every tick. It
  // has no buses: what it does must follow from its inputs alone.
  kWorker,
};

// A [[sensor]] source a device feeds: `source = "<name>"` in the TOML.
struct DeviceSource {
  const char* name;        // "wheel_odometry"
  est::SensorKind kind;    // what its samples are
  const char* kind_name;   // the [[sensor]] type that fuses them: "twist"
  const char* section;     // the TOML section whose presence turns it on
};

// What a device's create() gets besides its buses.
struct DeviceContext {
  FusionCore& core;        // configuration, frame tree, the sensors' input rings
  int first_slot = 0;      // its first diagnostics slot in the snapshot
  Device* host = nullptr;  // a frame consumer's host(), made before it
};

class DeviceDescriptor {
 public:
  virtual ~DeviceDescriptor() = default;

  // Short and unique: the thread "rtfuse-<name>", a thread device's
  // recording stream, and the key of its simulated counterpart (src/sim).
  virtual const char* name() const noexcept = 0;
  virtual DeviceScheduling scheduling() const noexcept = 0;
  // A frame consumer's source: the device whose rectified pairs it takes
  // (kHostThread, kWorker).
  virtual const char* host() const noexcept { return nullptr; }

  // --- configuration (the loader) --------------------------------------------
  // Its top-level TOML sections ("can", "wheel_odometry").
  virtual std::vector<std::string_view> sections() const = 0;
  // Reads its sections present in the file into cfg.hardware, every problem
  // into root's diagnostics with file, line and key. Runs after [[sensor]]
  // and [[static_transform]] are read.
  virtual void read_config(const config::Section& root, RuntimeConfig& cfg) const = 0;
  virtual bool enabled(const RuntimeConfig& cfg) const noexcept = 0;
  // The [[sensor]] sources it feeds.
  virtual std::vector<DeviceSource> sources() const { return {}; }
  // Once, on the configuration the devices will be made from: read the
  // files it names (a factory calibration), so the driver and a recording
  // hold the same bytes. False with *error naming the file and errno text.
  virtual bool prepare(RuntimeConfig& cfg, std::string* error) const {
    (void)cfg;
    (void)error;
    return true;
  }
  // Those files, carried in a recording, and taken back from one (a replay
  // on a machine without them).
  virtual void recorded_files(const RuntimeConfig& cfg, std::vector<transport::RecordedFile>* out) const {
    (void)cfg;
    (void)out;
  }
  virtual void restore_file(const transport::RecordedFile& file, RuntimeConfig& cfg) const {
    (void)file;
    (void)cfg;
  }

  // LCM channels it takes messages from (Device::on_input gets the index).
  virtual std::vector<std::string> input_channels(const RuntimeConfig& cfg) const {
    (void)cfg;
    return {};
  }

  // --- buses -------------------------------------------------------------------
  // The kinds its driver cannot run without (bus_bit()s); others are optional.
  virtual std::uint32_t required_buses(const RuntimeConfig& cfg) const noexcept {
    (void)cfg;
    return 0;
  }
  // Whether a recording holds its clock's calls. The IMU's and the GNSS
  // receiver's waits decide what they read, so they are recorded; a
  // camera reads its clock only to back off while unplugged.
  virtual bool records_clock() const noexcept { return true; }
  // Its device path ("/dev/i2c-1", "can0"): its main bus's name in a
  // recording's device table.
  virtual std::string bus_path(const RuntimeConfig& cfg) const = 0;
  // The kernel's buses for it, kept alive by `keep`, with `clock` as its
  // clock; one line per bus for the start-up log into *description.
  // False with *error naming the device, errno text and the likely fix.
  virtual bool open_linux(const RuntimeConfig& cfg, BusKeeper& keep, hal::Clock& clock, DeviceBuses* out,
                          std::string* description, std::string* error) const {
    (void)cfg;
    (void)keep;
    (void)clock;
    (void)out;
    (void)description;
    (void)error;
    return true;
  }

  // --- diagnostics -------------------------------------------------------------
  virtual int slot_count(const RuntimeConfig& cfg) const noexcept = 0;
  // Names, hardware ids and counter keys (values 0, level stale) of its
  // slots out[0 .. slot_count).
  virtual void describe(const RuntimeConfig& cfg, DeviceStatus* out) const noexcept = 0;

  // --- the device --------------------------------------------------------------
  // On the buses a backend gave it (required ones checked present by the
  // caller). Null with *error naming the device and the cause.
  virtual std::unique_ptr<Device> create(const DeviceContext& ctx, const DeviceBuses& buses,
                                         std::string* error) const = 0;
};

// "/dev/i2c-1" -> "i2c-1": a path as a channel-safe name (no '/', no spaces).
std::string device_path_name(std::string_view path, const char* fallback);

}  // namespace rtfuse
