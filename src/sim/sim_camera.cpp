#include "sim/sim_camera.hpp"

#include <cmath>

#include "drivers/camera/camera_modes.hpp"
#include "geometry/frame_tree.hpp"
#include "runtime/devices/camera/camera_calibration.hpp"

namespace rtfuse::sim {

std::unique_ptr<SimCamera> SimCamera::create(const RuntimeConfig& cfg, TruthSource& truth, hal::Clock& clock,
                                             TimeNs t0, std::uint64_t seed, const std::vector<ObstacleBox>& obstacles,
                                             std::string* error) {
  const CameraSection& c = cfg.hardware.camera;
  drivers::CameraMode mode;
  if (!drivers::find_camera_mode(c.resolution.view(), c.fps, &mode, error)) return nullptr;
  drivers::ZedCalibration calibration;
  // The simulated camera is the one the calibration describes.
  if (!load_camera_calibration(c, 0, &calibration, error)) return nullptr;
  geometry::FrameTree frames;
  frames.intern(cfg.base_link_frame.view());
  for (int i = 0; i < cfg.num_static_transforms; ++i) {
    const StaticTransformConfig& t = cfg.static_transforms[static_cast<std::size_t>(i)];
    std::string why;
    if (!frames.add(t.parent.view(), t.child.view(), t.parent_T_child, &why)) {
      *error = cfg.source + ": static_transform[" + std::to_string(i) + "]: " + why;
      return nullptr;
    }
  }
  const auto mount = frames.lookup(cfg.base_link_frame.view(), c.frame.view());
  if (!mount) {
    *error = "camera.frame '" + std::string(c.frame.view()) + "' is not connected to '" +
             std::string(cfg.base_link_frame.view()) + "': add a [[static_transform]] with parent = '" +
             std::string(cfg.base_link_frame.view()) + "' and child = '" + std::string(c.frame.view()) +
             "' (the left eye's optical frame: x right, y down, z forward)";
    return nullptr;
  }
  std::unique_ptr<SimCamera> s(new SimCamera());
  s->truth_ = &truth;
  s->t0_ = t0;
  s->period_ = static_cast<TimeNs>(std::llround(1e9 / c.fps));
  // The first exposure ends one period after the start, as a camera that
  // was switched on with the robot.
  s->next_ = t0 + s->period_;
  s->base_T_camera_ = *mount;
  CameraWorldConfig world;
  world.seed = seed;
  world.obstacles = obstacles;
  s->world_ = std::make_unique<CameraWorld>(world);
  StereoRendererOptions options;
  options.noise_seed = seed;
  s->renderer_ = std::make_unique<StereoRenderer>(calibration.stereo, *s->world_, options);
  if (!s->renderer_->valid()) {
    *error = c.calibration_file + ": the simulated camera cannot render this calibration: " + s->renderer_->error();
    return nullptr;
  }
  s->format_ = hal::mock::yuyv_format(drivers::side_by_side_width(mode), drivers::side_by_side_height(mode), c.fps,
                                      c.buffers);
  s->stream_ = std::make_unique<hal::mock::MockVideoStream>(clock, *s, s->format_);
  return s;
}

std::uint32_t SimCamera::fill(TimeNs stamp, std::uint32_t sequence, std::uint8_t* data,
                              std::uint32_t capacity) noexcept {
  next_ = stamp + period_;
  // A frame lost for want of a free buffer is not drawn.
  if (data == nullptr || capacity < format_.image_size) return 0;
  const TruthState t = truth_->truth_at(ns_to_sec(stamp - t0_));
  geometry::RigidTransform world_T_base;
  world_T_base.translation = Eigen::Vector3d(t.x, t.y, 0.0);
  world_T_base.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(t.yaw, Eigen::Vector3d::UnitZ()));
  renderer_->render(world_T_base * base_T_camera_, stamp, sequence, data, format_.bytes_per_line);
  return format_.image_size;
}

void SimCamera::stall_until(TimeNs until) noexcept {
  // The frames due before `until` are never exposed: the next one is the
  // first of the camera's own cadence after the stall.
  if (until > next_) next_ += (until - next_ + period_ - 1) / period_ * period_;
}

void SimCamera::provide(DeviceBuses& out, hal::Clock& clock) noexcept {
  out.video = stream_.get();
  out.clock = &clock;
}

std::unique_ptr<SimDevice> make_sim_camera(const SimDeviceContext& ctx, std::string* error) {
  return SimCamera::create(ctx.cfg, ctx.truth, ctx.clock, ctx.t0, ctx.scenario.seed, ctx.scenario.obstacles, error);
}

}  // namespace rtfuse::sim
