#include "transport/camera_messages.hpp"

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <string>
#include <utility>

#include "rtfuse/camera_info_t.hpp"
#include "rtfuse/image_t.hpp"
#include "transport/encode_buffer.hpp"

namespace rtfuse::transport {
namespace {

// A message and the buffer it is encoded into. The strings and arrays of
// `msg` are final when finalize() runs, so the encoded size never changes
// afterwards and the buffer is exactly that size.
template <class Msg>
struct Encoded {
  Msg msg{};
  std::unique_ptr<std::uint8_t[]> bytes;
  int capacity = 0;
  std::uint32_t seq = 0;  // unsigned: wraps instead of overflowing

  // Encoding once here also runs lcm-gen's lazily computed static type
  // hashes (a function-local static) off the publishing path.
  void finalize() {
    capacity = msg.getEncodedSize();
    bytes.reset(new std::uint8_t[static_cast<std::size_t>(capacity)]());
    msg.encode(bytes.get(), 0, capacity);
  }

  EncodedMessage encode(TimeNs stamp, std::int64_t* failures) noexcept {
    msg.header.utime = ns_to_utime(stamp);
    msg.header.seq = static_cast<std::int32_t>(seq++);
    const int n = encode_into(msg, bytes.get(), capacity);
    if (n <= 0) {
      ++*failures;
      return EncodedMessage{};
    }
    return EncodedMessage{bytes.get(), n};
  }
};

bool fail(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
  return false;
}

bool check_model(const StereoCameraInfo& m, std::string* error) {
  const auto bad = [&](const char* what, double v, const char* want) {
    char text[64];
    std::snprintf(text, sizeof text, "%.9g", v);
    return fail(error, std::string("camera model: ") + what + " is " + text + ", must be " + want);
  };
  if (m.width <= 0) return bad("width", m.width, "> 0");
  if (m.height <= 0) return bad("height", m.height, "> 0");
  if (!std::isfinite(m.fx) || m.fx <= 0.0) return bad("fx", m.fx, "finite and > 0");
  if (!std::isfinite(m.fy) || m.fy <= 0.0) return bad("fy", m.fy, "finite and > 0");
  if (!std::isfinite(m.cx)) return bad("cx", m.cx, "finite");
  if (!std::isfinite(m.cy)) return bad("cy", m.cy, "finite");
  if (!std::isfinite(m.baseline_m) || m.baseline_m <= 0.0) return bad("baseline_m", m.baseline_m, "finite and > 0");
  return true;
}

void fill_camera_info(const StereoCameraInfo& m, const std::string& frame_id, double tx,
                      rtfuse::camera_info_t* info) {
  info->header.frame_id = frame_id;
  info->width = m.width;
  info->height = m.height;
  // Rectified images have no distortion; ROS tools still expect a model name
  // and its five coefficients.
  info->distortion_model = "plumb_bob";
  info->num_D = 5;
  info->D.assign(5, 0.0);
  const double k[9] = {m.fx, 0.0, m.cx, 0.0, m.fy, m.cy, 0.0, 0.0, 1.0};
  const double r[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  const double p[12] = {m.fx, 0.0, m.cx, tx, 0.0, m.fy, m.cy, 0.0, 0.0, 0.0, 1.0, 0.0};
  for (int i = 0; i < 9; ++i) info->K[i] = k[i];
  for (int i = 0; i < 9; ++i) info->R[i] = r[i];
  for (int i = 0; i < 12; ++i) info->P[i] = p[i];
  // 0: no binning, no ROI (the whole image), as ROS drivers leave them.
  info->binning_x = 0;
  info->binning_y = 0;
  info->roi_x_offset = 0;
  info->roi_y_offset = 0;
  info->roi_height = 0;
  info->roi_width = 0;
  info->roi_do_rectify = 0;
}

// One eye shrunk into `out` (out_w x out_h, rows out_step apart): each output
// pixel is the mean of its factor x factor block rounded half up. Sums stay
// below 255 * kMaxFactor^2, far inside 32 bits.
void shrink(const GreyImage& in, int factor, int out_w, int out_h, std::uint8_t* out, int out_step) noexcept {
  const std::uint32_t n = static_cast<std::uint32_t>(factor * factor);
  const std::uint32_t half = n / 2u;
  const std::ptrdiff_t stride = in.stride;
  for (int oy = 0; oy < out_h; ++oy) {
    const std::uint8_t* band = in.pixels + static_cast<std::ptrdiff_t>(oy) * factor * stride;
    std::uint8_t* dst = out + static_cast<std::ptrdiff_t>(oy) * out_step;
    for (int ox = 0; ox < out_w; ++ox) {
      const std::uint8_t* block = band + static_cast<std::ptrdiff_t>(ox) * factor;
      std::uint32_t sum = 0;
      for (int dy = 0; dy < factor; ++dy) {
        const std::uint8_t* row = block + dy * stride;
        for (int dx = 0; dx < factor; ++dx) sum += row[dx];
      }
      dst[ox] = static_cast<std::uint8_t>((sum + half) / n);
    }
  }
}

bool fits(const GreyImage& g, int width, int height) noexcept {
  return g.pixels != nullptr && g.width == width && g.height == height && g.stride >= g.width;
}

}  // namespace

// --- CameraInfoEncoder ------------------------------------------------------

struct CameraInfoEncoder::Impl {
  Encoded<rtfuse::camera_info_t> left, right;
  std::int64_t failures = 0;
};

CameraInfoEncoder::CameraInfoEncoder(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
CameraInfoEncoder::~CameraInfoEncoder() = default;

std::unique_ptr<CameraInfoEncoder> CameraInfoEncoder::create(const StereoCameraInfo& model, std::string* error) {
  if (!check_model(model, error)) return nullptr;
  auto impl = std::make_unique<Impl>();
  fill_camera_info(model, model.left_frame_id, 0.0, &impl->left.msg);
  // ROS: the right eye projects points of the LEFT rectified frame, so its
  // P carries the baseline: Tx = -fx * B.
  fill_camera_info(model, model.right_frame_id, -model.fx * model.baseline_m, &impl->right.msg);
  impl->left.finalize();
  impl->right.finalize();
  return std::unique_ptr<CameraInfoEncoder>(new CameraInfoEncoder(std::move(impl)));
}

EncodedMessage CameraInfoEncoder::encode(StereoEye eye, TimeNs stamp) noexcept {
  auto& out = eye == StereoEye::kLeft ? impl_->left : impl_->right;
  return out.encode(stamp, &impl_->failures);
}

std::int64_t CameraInfoEncoder::encode_failures() const noexcept { return impl_->failures; }

// --- PreviewEncoder ---------------------------------------------------------

struct PreviewEncoder::Impl {
  int width = 0, height = 0;  // full-size eye
  int factor = 1;
  int eye_width = 0;  // preview of one eye
  Encoded<rtfuse::image_t> image;
  std::int64_t failures = 0;
};

PreviewEncoder::PreviewEncoder(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
PreviewEncoder::~PreviewEncoder() = default;

std::unique_ptr<PreviewEncoder> PreviewEncoder::create(int width, int height, int factor, const std::string& frame_id,
                                                       std::string* error) {
  if (width <= 0 || height <= 0) {
    fail(error, "preview: eye size " + std::to_string(width) + "x" + std::to_string(height) + " must be positive");
    return nullptr;
  }
  if (factor < 1 || factor > kMaxFactor) {
    fail(error, "preview: downscale factor " + std::to_string(factor) + " must be 1.." + std::to_string(kMaxFactor));
    return nullptr;
  }
  if (width < factor || height < factor) {
    fail(error, "preview: eye size " + std::to_string(width) + "x" + std::to_string(height) +
                    " is smaller than one " + std::to_string(factor) + "x" + std::to_string(factor) + " block");
    return nullptr;
  }
  // 2 * (width / factor) * (height / factor) bytes must fit LCM's int sizes.
  if (static_cast<std::int64_t>(width / factor) * 2 * (height / factor) > 0x7FFFFFFF - 4096) {
    fail(error, "preview: " + std::to_string(width) + "x" + std::to_string(height) + " is too large for one message");
    return nullptr;
  }
  auto impl = std::make_unique<Impl>();
  impl->width = width;
  impl->height = height;
  impl->factor = factor;
  impl->eye_width = width / factor;
  auto& msg = impl->image.msg;
  msg.header.frame_id = frame_id;
  msg.width = 2 * impl->eye_width;
  msg.height = height / factor;
  msg.encoding = "mono8";
  msg.is_bigendian = 0;
  msg.step = msg.width;  // one byte per pixel, rows packed
  msg.num_data = msg.step * msg.height;
  // The pixels are written into the message's own vector, sized here once;
  // encode() copies them into the buffer (a memcpy of the preview, cheap at
  // a preview's rate, and it keeps lcm-gen's encoder the only writer of the
  // wire format).
  msg.data.assign(static_cast<std::size_t>(msg.num_data), 0);
  impl->image.finalize();
  return std::unique_ptr<PreviewEncoder>(new PreviewEncoder(std::move(impl)));
}

EncodedMessage PreviewEncoder::encode(const GreyImage& left, const GreyImage& right, TimeNs stamp) noexcept {
  Impl& m = *impl_;
  if (!fits(left, m.width, m.height) || !fits(right, m.width, m.height)) {
    ++m.failures;
    return EncodedMessage{};
  }
  auto& msg = m.image.msg;
  std::uint8_t* out = msg.data.data();
  shrink(left, m.factor, m.eye_width, msg.height, out, msg.step);
  shrink(right, m.factor, m.eye_width, msg.height, out + m.eye_width, msg.step);
  return m.image.encode(stamp, &m.failures);
}

int PreviewEncoder::preview_width() const noexcept { return impl_->image.msg.width; }
int PreviewEncoder::preview_height() const noexcept { return impl_->image.msg.height; }
std::int64_t PreviewEncoder::encode_failures() const noexcept { return impl_->failures; }

}  // namespace rtfuse::transport
