// Steady-state allocation checks. Replacing the global operator new here
// replaces it for the whole test executable; it only counts while armed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Core>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "transport/encode_buffer.hpp"
#include "transport/event_log.hpp"
#include "transport/sample_decoder.hpp"

namespace {

std::atomic<bool> g_armed{false};
std::atomic<long> g_allocations{0};

void* counted_alloc(std::size_t size, std::size_t align) {
  if (g_armed.load(std::memory_order_relaxed))
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (size == 0) size = 1;
  void* p = nullptr;
  if (align <= alignof(std::max_align_t)) {
    p = std::malloc(size);
  } else if (posix_memalign(&p, align, size) != 0) {
    p = nullptr;
  }
  if (p == nullptr) throw std::bad_alloc();
  return p;
}

// Out of line so that GCC, seeing operator new paired with free() after
// inlining, does not raise -Wmismatched-new-delete at some optimisation levels.
[[gnu::noinline]] void counted_free(void* p) noexcept { std::free(p); }

// Counts allocations made inside f.
template <class F>
long allocations_in(F&& f) {
  g_allocations = 0;
#ifdef EIGEN_RUNTIME_NO_MALLOC
  Eigen::internal::set_is_malloc_allowed(false);
#endif
  g_armed = true;
  f();
  g_armed = false;
#ifdef EIGEN_RUNTIME_NO_MALLOC
  Eigen::internal::set_is_malloc_allowed(true);
#endif
  return g_allocations.load();
}

}  // namespace

void* operator new(std::size_t size) { return counted_alloc(size, 0); }
void* operator new[](std::size_t size) { return counted_alloc(size, 0); }
void* operator new(std::size_t size, std::align_val_t a) {
  return counted_alloc(size, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t size, std::align_val_t a) {
  return counted_alloc(size, static_cast<std::size_t>(a));
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted_alloc(size, 0);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t& t) noexcept {
  return operator new(size, t);
}
void operator delete(void* p, const std::nothrow_t&) noexcept { counted_free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { counted_free(p); }
void operator delete(void* p) noexcept { counted_free(p); }
void operator delete[](void* p) noexcept { counted_free(p); }
void operator delete(void* p, std::size_t) noexcept { counted_free(p); }
void operator delete[](void* p, std::size_t) noexcept { counted_free(p); }
void operator delete(void* p, std::align_val_t) noexcept { counted_free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { counted_free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { counted_free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { counted_free(p); }

namespace rtfuse::transport {
namespace {

template <class Msg>
std::vector<std::uint8_t> bytes_of(const Msg& m) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

TEST(Allocation, CounterSeesAllocations) {
  EXPECT_GE(allocations_in([] { delete new int(3); }), 1);
}

TEST(Allocation, DecoderDoesNotAllocateInSteadyState) {
  geometry::FrameTree frames;
  frames.intern("odom");
  frames.intern("base_link");
  const std::string long_frame(200, 'f');  // long, but within the reserved capacity
  frames.intern(std::string(60, 'g'));
  SampleDecoder decoder(frames);

  rtfuse::odometry_t odom{};
  odom.header.frame_id = "odom";
  odom.child_frame_id = "base_link";
  odom.pose.pose.orientation.w = 1.0;
  rtfuse::imu_t imu{};
  imu.header.frame_id = std::string(60, 'g');
  imu.orientation.w = 2.0;  // normalised on the way
  rtfuse::twist_with_covariance_stamped_t twist{};
  twist.header.frame_id = "base_link";
  rtfuse::pose_with_covariance_stamped_t pose{};
  pose.header.frame_id = long_frame;  // unknown frame: the error path must not allocate either
  pose.pose.pose.orientation.w = 1.0;

  std::vector<std::vector<std::uint8_t>> messages;
  for (int i = 0; i < 50; ++i) {
    odom.header.utime = i;
    odom.twist.twist.linear.x = i * 0.1;
    imu.angular_velocity.z = i * 0.01;
    twist.twist.covariance[0] = i;
    messages.push_back(bytes_of(odom));
    messages.push_back(bytes_of(imu));
    messages.push_back(bytes_of(twist));
    messages.push_back(bytes_of(pose));
  }
  const est::SensorKind kinds[] = {est::SensorKind::kOdometry, est::SensorKind::kImu,
                                   est::SensorKind::kTwist, est::SensorKind::kPose};
  const DecodeResult expected[] = {DecodeResult::kOk, DecodeResult::kOk, DecodeResult::kOk,
                                   DecodeResult::kUnknownFrame};
  est::SensorSample out;
  for (std::size_t k = 0; k < 4; ++k) {  // warm-up: first use of each type
    ASSERT_EQ(
        decoder.decode(kinds[k], messages[k].data(), static_cast<int>(messages[k].size()), &out),
        expected[k]);
  }
  int ok = 0;
  const long n = allocations_in([&] {
    for (std::size_t i = 0; i < messages.size(); ++i) {
      const auto& m = messages[i];
      const DecodeResult r =
          decoder.decode(kinds[i % 4], m.data(), static_cast<int>(m.size()), &out);
      ok += (r == expected[i % 4]) ? 1 : 0;
      // Wrong type and truncated input are error paths a bad sender can hit at rate.
      decoder.decode(kinds[(i + 1) % 4], m.data(), static_cast<int>(m.size()), &out);
      decoder.decode(kinds[i % 4], m.data(), static_cast<int>(m.size()) / 2, &out);
    }
  });
  EXPECT_EQ(n, 0);
  EXPECT_EQ(ok, static_cast<int>(messages.size()));
}

TEST(Allocation, LogReaderAndWriterDoNotAllocatePerEvent) {
  const std::string path =
      testing::TempDir() + "rtfuse_alloc_" + std::to_string(::getpid()) + ".lcmlog";
  std::string err;
  std::vector<std::uint8_t> big(100'000, 0xAB);
  {
    EventLogWriter w;
    ASSERT_TRUE(w.open(path, &err)) << err;
    ASSERT_TRUE(w.write(0, "BIG", big.data(), big.size(), &err));
    const long n = allocations_in([&] {
      for (int i = 1; i < 500; ++i) {
        EncodeBuffer<512> buf;
        rtfuse::header_t h{};
        h.utime = i;
        if (!buf.encode(h)) std::abort();
        if (!w.write(i, "SMALL", buf.data(), static_cast<std::size_t>(buf.size()), nullptr))
          std::abort();
      }
    });
    EXPECT_EQ(n, 0);
    ASSERT_TRUE(w.close(&err)) << err;
  }
  EventLogReader r;
  ASSERT_TRUE(r.open(path, &err)) << err;
  LogEvent ev;
  ASSERT_EQ(r.next(&ev, &err), ReadStatus::kEvent);  // the largest event sizes the buffer
  int events = 1;
  const long n = allocations_in([&] {
    while (r.next(&ev, nullptr) == ReadStatus::kEvent) ++events;
  });
  EXPECT_EQ(n, 0);
  EXPECT_EQ(events, 500);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace rtfuse::transport
