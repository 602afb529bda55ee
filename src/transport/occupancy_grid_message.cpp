#include "transport/occupancy_grid_message.hpp"

#include <cmath>
#include <cstring>

#include "rtfuse/occupancy_grid_t.hpp"
#include "transport/encode_buffer.hpp"

namespace rtfuse::transport {

struct OccupancyGridEncoder::Impl {
  rtfuse::occupancy_grid_t msg{};
  std::unique_ptr<std::uint8_t[]> bytes;
  int capacity = 0;
  int max_cells = 0;
  std::uint32_t seq = 0;
  std::int64_t failures = 0;
};

OccupancyGridEncoder::OccupancyGridEncoder(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OccupancyGridEncoder::~OccupancyGridEncoder() = default;

std::unique_ptr<OccupancyGridEncoder> OccupancyGridEncoder::create(int max_cells, const std::string& frame_id,
                                                                   TimeNs map_start, std::string* error) {
  // An LCM message over UDP is at most 4 GB in principle, but a grid past
  // 64 M cells is no longer a robot's local map.
  if (max_cells <= 0 || max_cells > (1 << 26)) {
    if (error != nullptr) {
      *error = "occupancy grid: " + std::to_string(max_cells) + " cells; a grid holds 1 to " +
               std::to_string(1 << 26);
    }
    return nullptr;
  }
  auto impl = std::make_unique<Impl>();
  impl->max_cells = max_cells;
  impl->msg.header.frame_id = frame_id;
  impl->msg.map_load_utime = ns_to_utime(map_start);
  impl->msg.origin.orientation.w = 1.0;
  impl->msg.data.assign(static_cast<std::size_t>(max_cells), -1);
  impl->msg.num_cells = max_cells;
  // Sized for the largest grid; encoding once also runs lcm-gen's lazily
  // computed type hash off the publishing path.
  impl->capacity = impl->msg.getEncodedSize();
  impl->bytes.reset(new std::uint8_t[static_cast<std::size_t>(impl->capacity)]());
  impl->msg.encode(impl->bytes.get(), 0, impl->capacity);
  return std::unique_ptr<OccupancyGridEncoder>(new OccupancyGridEncoder(std::move(impl)));
}

EncodedMessage OccupancyGridEncoder::encode(const OccupancyGridLayout& layout, const std::int8_t* cells,
                                            TimeNs stamp) noexcept {
  Impl& m = *impl_;
  const long long n = static_cast<long long>(layout.width) * layout.height;
  bool ok = layout.width >= 0 && layout.height >= 0 && n <= m.max_cells && (cells != nullptr || n == 0) &&
            std::isfinite(layout.resolution) && layout.resolution > 0.0 && std::isfinite(layout.origin_x) &&
            std::isfinite(layout.origin_y);
  for (long long i = 0; ok && i < n; ++i) ok = cells[i] >= -1 && cells[i] <= 100;
  if (!ok) {
    ++m.failures;
    return EncodedMessage{};
  }
  m.msg.header.utime = ns_to_utime(stamp);
  m.msg.header.seq = static_cast<std::int32_t>(m.seq++);
  m.msg.resolution = static_cast<float>(layout.resolution);
  m.msg.width = layout.width;
  m.msg.height = layout.height;
  m.msg.origin.position.x = layout.origin_x;
  m.msg.origin.position.y = layout.origin_y;
  m.msg.origin.position.z = 0.0;
  m.msg.num_cells = static_cast<std::int32_t>(n);
  if (n > 0) std::memcpy(m.msg.data.data(), cells, static_cast<std::size_t>(n));
  const int size = encode_into(m.msg, m.bytes.get(), m.capacity);
  if (size <= 0) {
    ++m.failures;
    return EncodedMessage{};
  }
  return EncodedMessage{m.bytes.get(), size};
}

std::int64_t OccupancyGridEncoder::encode_failures() const noexcept { return impl_->failures; }

}  // namespace rtfuse::transport
