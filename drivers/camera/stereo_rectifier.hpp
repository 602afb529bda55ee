#pragma once
// Per-frame stereo rectification of a side-by-side YUYV frame into two grey
// images, with tables built once at start-up.
//
// For every rectified pixel of each eye the table holds where to sample the
// raw eye (RawPositionMap, i.e. cv::initUndistortRectifyMap) in integer
// fixed point: the top-left source pixel and bilinear weights in 1/64 px
// (cv::remap uses 1/32). The per-frame work is integer only, so the output is
// the same bit for bit on every architecture; the tables come from IEEE
// double arithmetic with contraction off and rounded with floor(x * 64 + 0.5).
//
// Luma comes straight from YUYV (Y0 U Y1 V: Y at even byte offsets), so the
// frame is never converted first. Rectified pixels whose source lies outside
// the raw image (x outside [0, width - 1] or y outside [0, height - 1]) are 0.
//
// Table layout: one 8-byte entry per pixel (byte offset of the top-left
// source Y in the frame, four 7-bit weights), both eyes' rows interleaved,
// so a frame is one sequential pass over the table. The offsets bake in the
// frame's line pitch (set_bytes_per_line() re-targets them). x86-64 runs an
// SSE2 kernel (four pixels per step, pmaddwd), other targets the plain C++
// one; both compute the same integers, so the bytes are the same.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "drivers/camera/stereo_calibration.hpp"
#include "drivers/camera/stereo_rectification.hpp"

namespace rtfuse::drivers {

// A dequeued side-by-side frame: left eye in columns [0, width / 2), right in
// [width / 2, width).
struct YuyvFrameView {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;  // bytes readable at data
  int width = 0;         // whole frame, pixels (2 x eye)
  int height = 0;
  int bytes_per_line = 0;
};

// A caller-owned 8-bit grey image of the rectifier's eye size.
struct GreyImageView {
  std::uint8_t* data = nullptr;
  int stride = 0;  // bytes from one row to the next, >= width
};

class StereoRectifier {
 public:
  static constexpr int kFractionBits = 6;
  static constexpr int kOne = 1 << kFractionBits;

  // Builds both eyes' tables (allocates: start-up only) for frames whose
  // lines are `bytes_per_line` apart (0: tightly packed, 4 x eye width).
  // `rectification` is compute_stereo_rectification(calibration)'s; the eye
  // size is its width x height, which must be 2 x 2 to 8192 x 8192
  // (otherwise width() is 0 and every frame is refused).
  StereoRectifier(const StereoCalibration& calibration, const StereoRectification& rectification,
                  int bytes_per_line = 0);

  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  int bytes_per_line() const noexcept { return bytes_per_line_; }

  // Re-targets the tables to another line pitch, in place (no allocation, one
  // pass over the tables: call it when the device's negotiated format says
  // so, not per frame). False, changing nothing, if shorter than 4 x width().
  bool set_bytes_per_line(int bytes_per_line) noexcept;

  // Rectifies one frame into left and right (width() x height() each). False
  // without writing anything when the frame is not 2 * width() x height()
  // YUYV with bytes_per_line(), `size` cannot hold the frame, or an output is
  // missing or narrower than width(). No allocation, no lock, no system call.
  bool rectify(const YuyvFrameView& frame, GreyImageView left, GreyImageView right) const noexcept;
  // The same with the plain C++ kernel only (what targets without SSE2 run,
  // aarch64 among them); rectify() on x86-64 must give identical bytes,
  // which the tests check.
  bool rectify_portable(const YuyvFrameView& frame, GreyImageView left, GreyImageView right) const noexcept;

  // The table entry of one rectified pixel (eye 0 left, 1 right), for tests:
  // source column and row of the top-left neighbour in the raw eye, weights
  // of the right and lower neighbours in 1/64, and whether it is inside.
  struct Sample {
    int x = 0, y = 0, wx = 0, wy = 0;
    bool inside = false;
  };
  Sample sample(int eye, int u, int v) const noexcept;

 private:
  // One rectified pixel. Both eyes' rows are interleaved (left row v, right
  // row v, left row v + 1, ...) so the per-frame pass reads the table
  // strictly sequentially while both eyes sample the same source rows.
  struct Entry {
    // Byte offset of the top-left neighbour's Y from the frame's start.
    std::uint32_t offset;
    // Bilinear weights in 1/64 as four bytes: 64 - wx, 64 - wy, wx, wy
    // (bits 0, 8, 16, 24), so that masking gives the int16 weight pairs the
    // kernels multiply with. All zero for a source outside the raw image,
    // which makes the interpolation itself give 0 (no branch, no mask).
    std::uint32_t weights;
  };
  bool frame_fits(const YuyvFrameView& frame, GreyImageView left, GreyImageView right) const noexcept;
  static_assert(sizeof(Entry) == 8, "one 8-byte entry per pixel");

  int width_ = 0;
  int height_ = 0;
  int bytes_per_line_ = 0;
  std::vector<Entry> table_;  // (2 * height) rows of width entries
};

}  // namespace rtfuse::drivers
