// The simulated GNSS receiver: NAV-PVT bytes the real driver decodes into
// the truth plus the configured error, at the rate and latency configured,
// with the error statistics of a 1 m-class receiver, multipath jumps and
// outages.
#include "sim/sim_gnss.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "drivers/gnss/gnss_receiver.hpp"
#include "hal/mock/sim_clock.hpp"
#include "sim/truth_trajectory.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::sim {
namespace sim_gnss_test {

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kSec = 1'000 * kMs;
constexpr TimeNs kT0 = 50 * kSec;

// An hour up and down a 200 m straight, turning on the spot at each end.
DriveScenario long_drive() {
  DriveScenario sc;
  for (int i = 0; i < 10; ++i) {
    PathSegment a;
    a.type = SegmentType::kStraight;
    a.length_m = 200.0;
    a.speed_mps = 1.5;
    PathSegment b;
    b.type = SegmentType::kSpin;
    b.angle_rad = 3.14159265358979323846;
    b.yaw_rate_rad_s = 0.5;
    sc.path.push_back(a);
    sc.path.push_back(b);
  }
  sc.duration_s = 3600.0;
  sc.robot.wheel_count = 2;
  sc.robot.wheels[0] = SimWheel{1, true, 0.0};
  sc.robot.wheels[1] = SimWheel{2, false, 0.0};
  sc.gnss.enabled = true;
  sc.gnss.antenna_xyz_m = {0.3, 0.0, 0.8};
  sc.gnss.outage_count = 1;
  sc.gnss.outages[0] = GnssOutage{600.0, 60.0};
  return sc;
}

struct Rig {
  explicit Rig(const DriveScenario& s) : sc(s), truth(sc), gnss(sc, truth, clock, kT0), receiver(gnss, clock, {}) {}
  // Polls as the GNSS thread does; every fix on the way.
  std::vector<drivers::GnssFix> run(TimeNs until) {
    std::vector<drivers::GnssFix> fixes;
    drivers::GnssFix out[4];
    while (clock.now() < until) {
      const int n = receiver.poll(std::min<TimeNs>(50 * kMs, until - clock.now()), out, 4);
      fixes.insert(fixes.end(), out, out + n);
    }
    return fixes;
  }
  DriveScenario sc;
  TruthTrajectory truth;
  hal::mock::SimClock clock{kT0};
  SimGnss gnss;
  drivers::GnssReceiver receiver;
};

TEST(SimGnss, TheDriverDecodesTruthPlusTheErrorAtTheRateAndLatency) {
  Rig r(long_drive());
  const std::vector<drivers::GnssFix> fixes = r.run(kT0 + 10 * kSec);
  ASSERT_EQ(fixes.size(), 50u);  // 5 Hz; the epoch at 10 s arrives after it
  // The receiver's errors have state: a twin with the same seed, asked
  // epoch after epoch, has the same ones.
  Rig twin(long_drive());
  for (std::size_t k = 0; k < fixes.size(); ++k) {
    const drivers::GnssFix& f = fixes[k];
    const SimGnssEpoch& e = twin.gnss.epoch(static_cast<std::int64_t>(k));
    EXPECT_EQ(f.stamp, kT0 + static_cast<TimeNs>(k) * 200 * kMs + 100 * kMs) << k;
    EXPECT_EQ(f.status, drivers::GnssStatus::kFix);
    EXPECT_EQ(f.satellites, 14);
    const Eigen::Vector3d enu = r.gnss.plane().forward({f.latitude_deg, f.longitude_deg, f.altitude_m});
    for (int axis = 0; axis < 3; ++axis) {
      // 1e-7 degrees of latitude is 1.1 cm; the height is in millimetres.
      EXPECT_NEAR(enu[axis], e.truth_enu[axis] + e.error_enu[axis], 0.012) << k << " axis " << axis;
    }
    // The antenna: 0.3 m ahead of base_link and 0.8 m up.
    const TruthState s = r.truth.truth_at(0.2 * static_cast<double>(k));
    EXPECT_NEAR(e.truth_enu[0], s.x + 0.3 * std::cos(s.yaw), 1e-9);
    EXPECT_NEAR(e.truth_enu[2], 0.8, 1e-12);
    // The receiver's own accuracy estimate: bias and noise together.
    EXPECT_NEAR(f.covariance_enu[0], 0.7 * 0.7 + 0.25 * 0.25, 1e-3);
  }
}

TEST(SimGnss, AnHourHasTheErrorOfAOneMetreReceiverWithJumpsAndAnOutage) {
  Rig r(long_drive());
  double sum2[2] = {}, sum_bias_step2 = 0.0;
  int n = 0, jumps = 0, no_fix = 0, in_outage_with_fix = 0;
  bool was_jump = false;
  double previous_bias = 0.0;
  const std::int64_t epochs = 3600 * 5;
  for (std::int64_t k = 0; k < epochs; ++k) {
    const SimGnssEpoch e = r.gnss.epoch(k);
    const double t = 0.2 * static_cast<double>(k);
    if (!e.fix) {
      ++no_fix;
      continue;
    }
    if (t >= 600.0 && t < 660.0) ++in_outage_with_fix;
    if (e.multipath && !was_jump) ++jumps;
    was_jump = e.multipath;
    if (e.multipath) continue;
    sum2[0] += e.error_enu[0] * e.error_enu[0];
    sum2[1] += e.error_enu[1] * e.error_enu[1];
    sum_bias_step2 += (e.error_enu[0] - previous_bias) * (e.error_enu[0] - previous_bias);
    previous_bias = e.error_enu[0];
    ++n;
  }
  EXPECT_EQ(no_fix, 300);  // 60 s at 5 Hz
  EXPECT_EQ(in_outage_with_fix, 0);
  // sqrt(0.7^2 + 0.25^2) = 0.74 m per axis; over an hour with a 60 s
  // correlation time the sample spread is within about 20 %.
  for (int axis = 0; axis < 2; ++axis) {
    const double rms = std::sqrt(sum2[axis] / n);
    EXPECT_GT(rms, 0.55) << axis;
    EXPECT_LT(rms, 0.95) << axis;
  }
  // Epoch to epoch it moves by about the white noise (sqrt 2 x 0.25 m),
  // not by the bias: the bias wanders slowly.
  const double step = std::sqrt(sum_bias_step2 / n);
  EXPECT_GT(step, 0.28);
  EXPECT_LT(step, 0.45);
  // 20 an hour (Poisson: 5 sigma is about 22).
  EXPECT_GE(jumps, 5);
  EXPECT_LE(jumps, 45);
}

TEST(SimGnss, TheSameSeedGivesTheSameBytesAndReadsAllocateNothing) {
  Rig a(long_drive());
  Rig b(long_drive());
  a.run(kT0 + kSec);
  b.run(kT0 + kSec);
  std::vector<drivers::GnssFix> fa;
  fa.reserve(1000);
  {
    rtfuse::test::AllocScope scope;
    drivers::GnssFix out[4];
    while (a.clock.now() < kT0 + 20 * kSec) {
      const int n = a.receiver.poll(50 * kMs, out, 4);
      fa.insert(fa.end(), out, out + n);
    }
    EXPECT_EQ(scope.count(), 0u);
  }
  const std::vector<drivers::GnssFix> fb = b.run(kT0 + 20 * kSec);
  ASSERT_EQ(fa.size(), fb.size());
  for (std::size_t i = 0; i < fa.size(); ++i) {
    EXPECT_EQ(fa[i].latitude_deg, fb[i].latitude_deg);
    EXPECT_EQ(fa[i].longitude_deg, fb[i].longitude_deg);
  }
}

}  // namespace sim_gnss_test
}  // namespace rtfuse::sim
