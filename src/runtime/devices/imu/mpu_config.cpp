#include "runtime/devices/imu/mpu_config.hpp"

#include <string>
#include <string_view>

#include "runtime/config/toml_reader.hpp"

namespace rtfuse::config {
namespace {

void read_attitude(const Section& s, AttitudeSection& a) {
  s.reject_unknown({"algorithm", "beta", "zeta", "kp", "ki", "stillness_bias"});
  s.read("stillness_bias", a.stillness_bias);
  std::string alg;
  if (s.read("algorithm", alg)) {
    if (alg == "madgwick") {
      a.algorithm = AttitudeAlgorithmConfig::kMadgwick;
    } else if (alg == "mahony") {
      a.algorithm = AttitudeAlgorithmConfig::kMahony;
    } else {
      s.value_error("algorithm", "must be madgwick or mahony, got " + in_quotes(alg));
    }
  }
  const bool madgwick = a.algorithm == AttitudeAlgorithmConfig::kMadgwick;
  for (std::string_view k : {"beta", "zeta"}) {
    if (!madgwick && s.has(k)) s.key_error(k, "only used with algorithm = \"madgwick\"");
  }
  for (std::string_view k : {"kp", "ki"}) {
    if (madgwick && s.has(k)) s.key_error(k, "only used with algorithm = \"mahony\"");
  }
  read_number(s, "beta", a.beta, non_negative_finite, "must be >= 0 and finite");
  read_number(s, "zeta", a.zeta, non_negative_finite, "must be >= 0 and finite");
  read_number(s, "kp", a.kp, non_negative_finite, "must be >= 0 and finite");
  read_number(s, "ki", a.ki, non_negative_finite, "must be >= 0 and finite");
}

void read_mpu(const Section& s, MpuSection& m) {
  s.reject_unknown({"device", "address", "model", "sample_rate_divider", "dlpf", "gyro_range", "accel_range",
                    "data_ready_chip", "data_ready_line", "poll_rate", "frame", "frozen_reads", "gyro_noise",
                    "accel_noise", "attitude"});
  m.enabled = true;
  s.read_name("device", m.device);
  read_int(s, "address", m.address, 0x08, 0x77);
  std::string model;
  if (s.read("model", model)) {
    if (model == "auto") {
      m.model = MpuModelConfig::kAuto;
    } else if (model == "mpu6050") {
      m.model = MpuModelConfig::kMpu6050;
    } else if (model == "mpu6500") {
      m.model = MpuModelConfig::kMpu6500;
    } else if (model == "mpu9250") {
      m.model = MpuModelConfig::kMpu9250;
    } else {
      s.value_error("model", "must be one of auto, mpu6050, mpu6500, mpu9250, got " + in_quotes(model));
    }
  }
  read_int(s, "sample_rate_divider", m.sample_rate_divider, 0, 255);
  read_int(s, "dlpf", m.dlpf, 0, 6);
  std::int64_t v = 0;
  if (s.read("gyro_range", v)) {
    if (v != 250 && v != 500 && v != 1000 && v != 2000) {
      s.value_error("gyro_range", "must be 250, 500, 1000 or 2000 deg/s, got " + std::to_string(v));
    } else {
      m.gyro_range_dps = static_cast<int>(v);
    }
  }
  if (s.read("accel_range", v)) {
    if (v != 2 && v != 4 && v != 8 && v != 16) {
      s.value_error("accel_range", "must be 2, 4, 8 or 16 g, got " + std::to_string(v));
    } else {
      m.accel_range_g = static_cast<int>(v);
    }
  }
  const bool chip = s.read_name("data_ready_chip", m.data_ready_chip);
  read_int(s, "data_ready_line", m.data_ready_line, 0, 1023);
  if (chip != s.has("data_ready_line")) {
    s.key_error(chip ? "data_ready_chip" : "data_ready_line",
                "data_ready_chip and data_ready_line go together: give both, or neither to poll at poll_rate");
  }
  if (chip && s.has("poll_rate")) s.key_error("poll_rate", "only used without a data-ready line");
  read_number(s, "poll_rate", m.poll_rate_hz, [](double r) { return r > 0 && r <= 1000; },
              "must be > 0 and <= 1000 Hz");
  s.read_name("frame", m.frame);
  read_int(s, "frozen_reads", m.frozen_reads, 2, 100000);
  read_number(s, "gyro_noise", m.gyro_noise_rad_s, positive_finite, "must be > 0 rad/s and finite");
  read_number(s, "accel_noise", m.accel_noise_mps2, positive_finite, "must be > 0 m/s^2 and finite");
  read_attitude(Section(section_table(s, "attitude"), s.key("attitude"), s.diag()), m.attitude);
}

}  // namespace

void read_mpu_config(const Section& root, RuntimeConfig& cfg) {
  const toml::table* mpu = section_table(root, "mpu");
  if (mpu) read_mpu(Section(mpu, "mpu", root.diag()), cfg.hardware.mpu);
}

}  // namespace rtfuse::config
