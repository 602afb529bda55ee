#include "sim/sim_camera.hpp"
#include "sim/sim_device.hpp"
#include "sim/sim_encoders.hpp"
#include "sim/sim_gnss.hpp"
#include "sim/sim_imu.hpp"

namespace rtfuse::sim {
namespace {

// One line per registered device the simulated robot carries.
const SimCounterpart kCounterparts[] = {
    {"wheel_encoders", &make_sim_encoders},
    {"imu", &make_sim_imu},
    {"camera", &make_sim_camera},
    {"gnss", &make_sim_gnss},
};

}  // namespace

const SimCounterpart* find_sim_counterpart(std::string_view device) noexcept {
  for (const SimCounterpart& c : kCounterparts) {
    if (device == c.device) return &c;
  }
  return nullptr;
}

}  // namespace rtfuse::sim
