#include "sim/simulated_robot.hpp"

#include <limits>

#include "sim/ground_truth.hpp"
#include "transport/encode_buffer.hpp"

namespace rtfuse::sim {

std::unique_ptr<SimulatedRobot> SimulatedRobot::create(const RuntimeConfig& cfg, const std::string& scenario_path,
                                                       hal::Clock& clock, TimeNs t0, std::string* error,
                                                       const std::string_view* scenario_text) {
  std::unique_ptr<SimulatedRobot> r(new SimulatedRobot());
  const std::string path = scenario_path.empty() ? cfg.hardware.scenario : scenario_path;
  if (path.empty()) {
    *error = "no drive scenario: set [hardware] scenario or give --scenario";
    return nullptr;
  }
  const bool loaded = scenario_text != nullptr
                          ? load_drive_scenario_string(*scenario_text, path, &r->scenario_, error)
                          : load_drive_scenario(path, &r->scenario_, error);
  if (!loaded) return nullptr;
  const RobotBody& body = r->scenario_.robot;
  const HardwareConfig& hw = cfg.hardware;
  // The config must address the simulated devices, or the drivers would
  // talk to nobody and the run would say nothing useful.
  if (hw.can.enabled) {
    for (int i = 0; i < hw.can.num_nodes; ++i) {
      const int id = hw.can.nodes[static_cast<std::size_t>(i)].node_id;
      const CanNodeSection& n = hw.can.nodes[static_cast<std::size_t>(i)];
      bool found = false;
      for (int w = 0; w < body.wheel_count; ++w) {
        const SimWheel& wheel = body.wheels[static_cast<std::size_t>(w)];
        if (wheel.node_id != id) continue;
        found = true;
        // A counter of another width or signedness unwraps at the wrong
        // place: jumps and wrong counts, with no error to say why.
        if (n.position_bits != body.encoder_bits || n.position_signed != body.encoder_signed) {
          *error = cfg.source + ": can.node[" + std::to_string(i) + "] reads a " + std::to_string(n.position_bits) +
                   "-bit " + (n.position_signed ? "signed" : "unsigned") + " position but the simulated encoder in " +
                   path + " counts " + std::to_string(body.encoder_bits) + "-bit " +
                   (body.encoder_signed ? "signed" : "unsigned");
          return nullptr;
        }
        const bool inverted = wheel.left ? body.invert_left : body.invert_right;
        if ((n.sign < 0) != inverted) {
          *error = cfg.source + ": can.node[" + std::to_string(i) + "].sign = " + std::to_string(n.sign) +
                   " but the simulated encoder in " + path + (inverted ? " counts down" : " counts up") +
                   " driving forward";
          return nullptr;
        }
      }
      if (!found) {
        *error = cfg.source + ": can.node[" + std::to_string(i) + "].node_id = " + std::to_string(id) +
                 " is not an encoder of the simulated robot in " + path;
        return nullptr;
      }
    }
  }
  if (hw.mpu.enabled && hw.mpu.address != r->scenario_.imu.address) {
    *error = cfg.source + ": mpu.address = " + std::to_string(hw.mpu.address) +
             " but the simulated IMU in " + path + " answers at " + std::to_string(r->scenario_.imu.address);
    return nullptr;
  }
  r->truth_ = std::make_unique<TruthTrajectory>(r->scenario_);
  if (!r->truth_->valid()) {
    *error = path + ": the path cannot be driven within the motion limits";
    return nullptr;
  }
  r->clock_ = &clock;
  r->t0_ = t0;
  r->encoders_ = std::make_unique<SimEncoders>(r->scenario_, *r->truth_, clock, t0);
  r->imu_ = std::make_unique<SimImu>(r->scenario_, *r->truth_, clock, t0);
  if (hw.gnss.enabled) {
    if (!r->scenario_.gnss.enabled) {
      *error = cfg.source + ": [gnss] is configured but the scenario " + path +
               " has no [gnss] receiver on the simulated robot";
      return nullptr;
    }
    if (hw.gnss.protocol != GnssProtocolConfig::kUbx) {
      *error = cfg.source + ": gnss.protocol: the simulated receiver speaks ubx (u-blox NAV-PVT)";
      return nullptr;
    }
    r->gnss_ = std::make_unique<SimGnss>(r->scenario_, *r->truth_, clock, t0);
  }
  if (hw.camera.enabled) {
    r->camera_ = SimCamera::create(cfg, *r->truth_, clock, t0, r->scenario_.seed, error);
    if (!r->camera_) return nullptr;
  }
  return r;
}

HalBuses SimulatedRobot::buses() {
  HalBuses b;
  b.can = encoders_.get();
  b.imu.i2c = imu_.get();
  b.imu.data_ready = imu_.get();
  b.imu.clock = clock_;
  if (gnss_) {
    b.gnss.serial = gnss_.get();
    b.gnss.clock = clock_;
  }
  if (camera_) {
    b.camera.video = &camera_->stream();
    b.camera.clock = clock_;
  }
  return b;
}

double SimulatedRobot::duration_s() const { return truth_->duration_s(); }

TruthState SimulatedRobot::truth_at(TimeNs t) const noexcept { return truth_->truth_at(ns_to_sec(t - t0_)); }

GroundTruthEncoder::GroundTruthEncoder() {
  fill_ground_truth(TruthState{}, 0, 0, &msg_);
  buf_.assign(static_cast<std::size_t>(msg_.getEncodedSize() + 64), 0);
  msg_.encode(buf_.data(), 0, static_cast<int>(buf_.size()));
}

const std::uint8_t* GroundTruthEncoder::encode(const TruthState& truth, TimeNs stamp, int* size) noexcept {
  fill_ground_truth(truth, stamp, seq_++, &msg_);
  *size = transport::encode_into(msg_, buf_.data(), static_cast<int>(buf_.size()));
  return buf_.data();
}

TimeNs SimulatedRobot::next_event_time(std::string_view name) const noexcept {
  if (name == "imu" && imu_) return imu_->next_edge_time();
  if (name == "camera" && camera_) return camera_->next_frame_time();
  if (name == "gnss" && gnss_) return gnss_->next_arrival();
  return std::numeric_limits<TimeNs>::max();
}

}  // namespace rtfuse::sim
