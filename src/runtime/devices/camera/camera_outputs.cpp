#include "runtime/devices/camera/camera_outputs.hpp"

#include <cmath>

namespace rtfuse {

std::unique_ptr<CameraOutputs> CameraOutputs::create(FramePool& pool, const drivers::StereoRectification& r,
                                                     const CameraSection& config, std::string* error) {
  std::unique_ptr<CameraOutputs> o(new CameraOutputs(pool, config));
  transport::StereoCameraInfo model;
  model.width = pool.width();
  model.height = pool.height();
  model.fx = r.fx;
  model.fy = r.fy;
  model.cx = r.cx;
  model.cy = r.cy;
  model.baseline_m = r.baseline_m;
  model.left_frame_id = std::string(config.frame.view());
  // The right eye has no frame of its own in the tree: it is the left one
  // moved by the baseline, which its P already says.
  model.right_frame_id = std::string(config.frame.view());
  o->left_info_channel_ = std::string(config.info_channel.view()) + "/left";
  o->right_info_channel_ = std::string(config.info_channel.view()) + "/right";
  o->info_ = transport::CameraInfoEncoder::create(model, error);
  if (!o->info_) return nullptr;
  if (config.preview_rate_hz > 0.0) {
    o->preview_ = transport::PreviewEncoder::create(model.width, model.height, config.preview_downscale,
                                                    model.left_frame_id, error);
    if (!o->preview_) return nullptr;
    o->period_ = static_cast<TimeNs>(std::llround(1e9 / config.preview_rate_hz));
  }
  return o;
}

void CameraOutputs::publish_due(TimeNs now, transport::MessageSink& sink) noexcept {
  if (period_ == 0 || now < next_) return;
  FramePool& pool = pool_;
  FramePool::Handle h = pool.take_latest(last_frame_);
  if (!h.valid()) return;  // no new pair yet: look again at the next wake
  // The period counts from this preview: a stalled camera gives no burst.
  next_ = now + period_;
  last_frame_ = h.frame_id;
  const FramePool::Frame f = pool.frame(h);
  const transport::GreyImage left{f.left, f.width, f.height, f.stride};
  const transport::GreyImage right{f.right, f.width, f.height, f.stride};
  const transport::EncodedMessage preview = preview_->encode(left, right, f.stamp);
  if (preview.ok()) sink.publish(config_.preview_channel.c_str(), preview.data, preview.size, now);
  const TimeNs stamp = f.stamp;
  pool.release(h);
  const transport::EncodedMessage left_info = info_->encode(transport::StereoEye::kLeft, stamp);
  if (left_info.ok()) sink.publish(left_info_channel_.c_str(), left_info.data, left_info.size, now);
  const transport::EncodedMessage right_info = info_->encode(transport::StereoEye::kRight, stamp);
  if (right_info.ok()) sink.publish(right_info_channel_.c_str(), right_info.data, right_info.size, now);
  ++published_;
}

}  // namespace rtfuse
