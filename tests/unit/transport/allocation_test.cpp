// Steady-state allocation checks, with the counting operator new of
// tests/support (alloc_counter.cpp); it only counts while armed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Core>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "support/alloc_counter.hpp"
#include "transport/encode_buffer.hpp"
#include "transport/event_log.hpp"
#include "transport/sample_decoder.hpp"
#include "support/eigen_no_malloc.hpp"

namespace rtfuse::transport {
namespace allocation_test {

// Counts allocations made inside f, with Eigen's own check armed as well.
template <class F>
long allocations_in(F&& f) {
  rtfuse::test::EigenMallocForbidden eigen_no_malloc;
  long n = 0;
  {
    rtfuse::test::AllocScope scope;
    f();
    n = static_cast<long>(scope.count());
  }
  return n;
}

template <class Msg>
std::vector<std::uint8_t> bytes_of(const Msg& m) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

TEST(Allocation, CounterSeesAllocations) {
  // volatile: a new/delete pair the compiler can see through may be elided.
  EXPECT_GE(allocations_in([] {
              int* volatile p = new int(3);
              delete p;
            }),
            1);
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

}  // namespace allocation_test
}  // namespace rtfuse::transport
