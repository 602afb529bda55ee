#pragma once
// Images of the vision layer: a view of 8-bit pixels someone else owns (a
// frame pool slot, a decoded PNG), and planes that own their pixels (grey,
// gradients, filter responses), allocated once when the workspace is sized
// and never again.
#include <cstddef>
#include <cstdint>
#include <memory>

namespace rtfuse::vision {

struct GreyView {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  int stride = 0;  // bytes from one row to the next

  const std::uint8_t* row(int v) const noexcept { return data + static_cast<std::ptrdiff_t>(v) * stride; }
  bool valid() const noexcept { return data != nullptr && width > 0 && height > 0 && stride >= width; }
};

// A width x height plane of T, rows padded to a multiple of 64 bytes.
template <class T>
class Plane {
 public:
  Plane() = default;
  Plane(int width, int height)
      : width_(width),
        height_(height),
        stride_(static_cast<int>(((static_cast<std::size_t>(width) * sizeof(T) + 63) / 64) * 64 / sizeof(T))),
        data_(new T[static_cast<std::size_t>(stride_) * static_cast<std::size_t>(height)]()) {}

  int width() const noexcept { return width_; }
  int height() const noexcept { return height_; }
  int stride() const noexcept { return stride_; }  // elements
  T* row(int v) noexcept { return data_.get() + static_cast<std::ptrdiff_t>(v) * stride_; }
  const T* row(int v) const noexcept { return data_.get() + static_cast<std::ptrdiff_t>(v) * stride_; }
  T at(int u, int v) const noexcept { return row(v)[u]; }

 private:
  int width_ = 0;
  int height_ = 0;
  int stride_ = 0;
  std::unique_ptr<T[]> data_;
};

inline GreyView view_of(const Plane<std::uint8_t>& p) noexcept {
  return GreyView{p.row(0), p.width(), p.height(), p.stride()};
}

}  // namespace rtfuse::vision
