// The queues of the real-time path carry fixed-size Eigen types; core has no
// Eigen, so the ring is exercised with them here, where Eigen is available.
#include <gtest/gtest.h>

#include <cstdint>

#include "core/spsc_ring.hpp"
#include "geometry/rigid_transform.hpp"
#include "support/eigen_no_malloc.hpp"

namespace rtfuse::test {
std::uint64_t allocation_count() noexcept;
}

namespace ring_payload_test {

struct alignas(32) Sample {
  std::int64_t stamp = 0;
  rtfuse::geometry::RigidTransform pose;
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();
  Eigen::Vector4d padded = Eigen::Vector4d::Zero();
};

TEST(GeometrySpscRingEigenPayload, PushPopWithoutAnyAllocation) {
  rtfuse::SpscRing<Sample> ring(5);
  Sample in;
  Sample out;
  rtfuse::test::EigenMallocForbidden eigen_no_malloc;
  const std::uint64_t before = rtfuse::test::allocation_count();
  bool ok = true;
  for (std::int64_t i = 0; i < 100; ++i) {
    in.stamp = i;
    in.pose.translation.x() = static_cast<double>(i);
    in.covariance(5, 5) = static_cast<double>(i);
    ok &= ring.try_push(in);
    ok &= ring.try_push(in);
    const Sample* front = ring.peek();
    ok &= front != nullptr && reinterpret_cast<std::uintptr_t>(front) % alignof(Sample) == 0;
    ok &= ring.try_pop(out);
    ok &= ring.try_pop(out);
    ok &= out.stamp == i && out.pose.translation.x() == static_cast<double>(i) &&
          out.covariance(5, 5) == static_cast<double>(i);
  }
  const std::uint64_t after = rtfuse::test::allocation_count();
  EXPECT_TRUE(ok);
  EXPECT_EQ(after, before);
}

}  // namespace ring_payload_test
