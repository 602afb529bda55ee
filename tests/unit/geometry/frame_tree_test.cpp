#include "geometry/frame_tree.hpp"

#include <gtest/gtest.h>

#include <string>

#include "geometry/angles.hpp"
#include "geometry/rotation.hpp"
#include "support/eigen_no_malloc.hpp"

namespace rtfuse::test {
std::uint64_t allocation_count() noexcept;
}

namespace frame_tree_test {

using rtfuse::geometry::FrameTree;
using rtfuse::geometry::kPi;
using rtfuse::geometry::quaternion_from_rpy;
using rtfuse::geometry::RigidTransform;

RigidTransform make(double x, double y, double z, double roll = 0, double pitch = 0, double yaw = 0) {
  RigidTransform t;
  t.translation = Eigen::Vector3d(x, y, z);
  t.rotation = quaternion_from_rpy(roll, pitch, yaw);
  return t;
}

// Compared through their action on points, so q and -q are equal.
void expect_same(const RigidTransform& a, const RigidTransform& b, double tol = 1e-12) {
  EXPECT_TRUE(a.translation.isApprox(b.translation, tol) || (a.translation - b.translation).norm() < tol)
      << a.translation.transpose() << " vs " << b.translation.transpose();
  EXPECT_TRUE(a.rotation_matrix().isApprox(b.rotation_matrix(), tol));
}

// map -> odom -> base_link -> {imu_link, laser}; world -> gps is a second tree.
//   map_T_odom:       (10, 0, 0)
//   odom_T_base:      (1, 2, 0), yaw +90 deg
//   base_T_imu:       (0.1, 0, 0.2), roll 180 deg (mounted upside down)
//   base_T_laser:     (0.2, 0, 0.3)
//   world_T_gps:      (0, 0, 1)
class GeometryFrameTree : public ::testing::Test {
 protected:
  void SetUp() override {
    // Children before parents on purpose: roots are recomputed on every add().
    ASSERT_TRUE(tree.add("base_link", "imu_link", make(0.1, 0, 0.2, kPi, 0, 0), &error)) << error;
    ASSERT_TRUE(tree.add("base_link", "laser", make(0.2, 0, 0.3), &error)) << error;
    ASSERT_TRUE(tree.add("odom", "base_link", make(1, 2, 0, 0, 0, kPi / 2), &error)) << error;
    ASSERT_TRUE(tree.add("map", "odom", make(10, 0, 0), &error)) << error;
    ASSERT_TRUE(tree.add("world", "gps", make(0, 0, 1), &error)) << error;
  }
  Eigen::Vector3d apply(std::string_view target, std::string_view source, const Eigen::Vector3d& p) {
    const auto t = tree.lookup(target, source);
    EXPECT_TRUE(t.has_value()) << target << " <- " << source;
    return t ? *t * p : Eigen::Vector3d::Constant(std::nan(""));
  }

  FrameTree tree;
  std::string error;
};

TEST_F(GeometryFrameTree, DirectEdgeIsTheGivenTransform) {
  const Eigen::Vector3d px(1, 0, 0), py(0, 1, 0);
  EXPECT_TRUE(apply("base_link", "imu_link", px).isApprox(Eigen::Vector3d(1.1, 0, 0.2), 1e-12));
  EXPECT_TRUE(apply("base_link", "imu_link", py).isApprox(Eigen::Vector3d(0.1, -1, 0.2), 1e-12));
  EXPECT_TRUE(apply("odom", "base_link", px).isApprox(Eigen::Vector3d(1, 3, 0), 1e-12));
  EXPECT_TRUE(apply("odom", "base_link", Eigen::Vector3d::Zero()).isApprox(Eigen::Vector3d(1, 2, 0), 1e-12));
}

TEST_F(GeometryFrameTree, ChainsComposeAsComputedByHand) {
  const Eigen::Vector3d p(1, 0, 0);  // one metre ahead of the IMU
  // imu -> base: (1.1, 0, 0.2); base -> odom: yaw 90 then + (1, 2, 0).
  EXPECT_TRUE(apply("odom", "imu_link", p).isApprox(Eigen::Vector3d(1.0, 3.1, 0.2), 1e-12));
  EXPECT_TRUE(apply("map", "imu_link", p).isApprox(Eigen::Vector3d(11.0, 3.1, 0.2), 1e-12));
  // Sibling to sibling through base_link: (1.1, 0, 0.2) - (0.2, 0, 0.3).
  EXPECT_TRUE(apply("laser", "imu_link", p).isApprox(Eigen::Vector3d(0.9, 0, -0.1), 1e-12));
  // Downwards: a point of odom seen from the imu (upside down).
  EXPECT_TRUE(apply("imu_link", "odom", Eigen::Vector3d(1.0, 3.1, 0.2)).isApprox(p, 1e-12));
  EXPECT_TRUE(apply("imu_link", "odom", Eigen::Vector3d(1, 2, 1)).isApprox(Eigen::Vector3d(-0.1, 0, -0.8), 1e-12));
  const auto odom_T_imu = tree.lookup("odom", "imu_link");
  ASSERT_TRUE(odom_T_imu);
  // imu z (down-facing after the roll) is odom -z; imu x is odom y.
  EXPECT_TRUE((odom_T_imu->rotation * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_TRUE((odom_T_imu->rotation * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
}

TEST_F(GeometryFrameTree, InverseAndCompositionConsistency) {
  const char* connected[] = {"map", "odom", "base_link", "imu_link", "laser"};
  for (const char* a : connected) {
    for (const char* b : connected) {
      SCOPED_TRACE(std::string(a) + " <- " + b);
      const auto a_T_b = tree.lookup(a, b);
      const auto b_T_a = tree.lookup(b, a);
      ASSERT_TRUE(a_T_b && b_T_a);
      EXPECT_TRUE((*a_T_b * *b_T_a).is_identity(1e-12));
      expect_same(*b_T_a, a_T_b->inverse());
      for (const char* c : connected) {
        const auto b_T_c = tree.lookup(b, c);
        const auto a_T_c = tree.lookup(a, c);
        ASSERT_TRUE(b_T_c && a_T_c);
        expect_same(*a_T_c, *a_T_b * *b_T_c);
      }
    }
  }
}

TEST_F(GeometryFrameTree, SelfLookupIsIdentity) {
  for (int i = 0; i < tree.size(); ++i) {
    const auto t = tree.lookup(i, i);
    ASSERT_TRUE(t);
    EXPECT_TRUE(t->is_identity(0.0));
  }
  const int lonely = tree.intern("lonely");
  ASSERT_GE(lonely, 0);
  ASSERT_TRUE(tree.lookup("lonely", "lonely"));
  EXPECT_FALSE(tree.lookup("lonely", "base_link"));
}

TEST_F(GeometryFrameTree, DisconnectedAndUnknownFrames) {
  EXPECT_FALSE(tree.lookup("base_link", "gps"));
  EXPECT_FALSE(tree.lookup("gps", "map"));
  EXPECT_TRUE(tree.lookup("world", "gps"));
  EXPECT_FALSE(tree.lookup("base_link", "nowhere"));
  EXPECT_FALSE(tree.lookup("nowhere", "nowhere"));
  EXPECT_FALSE(tree.lookup(-1, 0));
  EXPECT_FALSE(tree.lookup(0, tree.size()));
  // Joining the two trees connects them.
  ASSERT_TRUE(tree.add("map", "world", make(0, 0, 0, 0, 0, kPi), &error)) << error;
  EXPECT_TRUE(apply("imu_link", "gps", Eigen::Vector3d::Zero()).allFinite());
  EXPECT_TRUE(apply("map", "gps", Eigen::Vector3d::Zero()).isApprox(Eigen::Vector3d(0, 0, 1), 1e-12));
}

TEST_F(GeometryFrameTree, FindInternAndName) {
  EXPECT_EQ(tree.size(), 7);
  const int base = tree.find("base_link");
  ASSERT_GE(base, 0);
  EXPECT_EQ(tree.name(base), "base_link");
  EXPECT_EQ(tree.intern("base_link"), base);
  EXPECT_EQ(tree.size(), 7);
  EXPECT_EQ(tree.find("base"), -1);
  EXPECT_EQ(tree.find(""), -1);
  EXPECT_EQ(tree.intern(""), -1);
  EXPECT_EQ(tree.intern(std::string(64, 'x')), -1);
  EXPECT_EQ(tree.intern(std::string(63, 'x')), 7);
  EXPECT_EQ(tree.name(-1), "");
  EXPECT_EQ(tree.name(100), "");
}

TEST_F(GeometryFrameTree, FindAndLookupDoNotAllocate) {
  const int imu = tree.find("imu_link");
  const int map = tree.find("map");
  rtfuse::test::EigenMallocForbidden eigen_no_malloc;
  const std::uint64_t before = rtfuse::test::allocation_count();
  double sum = 0;
  int found = 0;
  for (int i = 0; i < 100; ++i) {
    found += tree.find("laser") >= 0;
    found += tree.find("not_there") >= 0;
    const auto t = tree.lookup(map, imu);
    const auto u = tree.lookup("laser", "odom");
    sum += t->translation.x() + u->translation.y();
  }
  const std::uint64_t after = rtfuse::test::allocation_count();
  EXPECT_EQ(after, before);
  EXPECT_EQ(found, 100);
  EXPECT_TRUE(std::isfinite(sum));
}

TEST_F(GeometryFrameTree, NonUnitQuaternionIsNormalised) {
  RigidTransform t = make(0, 0, 0, 0, 0, 0.5);
  t.rotation.coeffs() *= 2.0;
  ASSERT_TRUE(tree.add("laser", "laser_optical", t, &error)) << error;
  const auto laser_T_optical = tree.lookup("laser", "laser_optical");
  ASSERT_TRUE(laser_T_optical);
  EXPECT_NEAR(laser_T_optical->rotation.norm(), 1.0, 1e-15);
  expect_same(*laser_T_optical, make(0, 0, 0, 0, 0, 0.5));
}

// Error paths: each message names the edge and says exactly what is wrong,
// and a failed add() leaves the tree untouched.
class GeometryFrameTreeErrors : public ::testing::Test {
 protected:
  void expect_error(std::string_view parent, std::string_view child, const std::string& message,
                    const RigidTransform& t = RigidTransform::identity()) {
    const int size_before = tree.size();
    std::string error;
    EXPECT_FALSE(tree.add(parent, child, t, &error));
    EXPECT_EQ(error, message);
    EXPECT_EQ(tree.size(), size_before);
    EXPECT_FALSE(tree.add(parent, child, t, nullptr));  // no message wanted: still fails, no crash
  }
  FrameTree tree;
};

TEST_F(GeometryFrameTreeErrors, SecondParent) {
  std::string error;
  ASSERT_TRUE(tree.add("base_footprint", "imu_link", make(0, 0, 0.1), &error));
  expect_error("base_link", "imu_link",
               "static transform base_link -> imu_link: frame 'imu_link' already has parent 'base_footprint'");
  // The same edge twice is also a second parent.
  expect_error("base_footprint", "imu_link",
               "static transform base_footprint -> imu_link: frame 'imu_link' already has parent 'base_footprint'");
  const auto t = tree.lookup("base_footprint", "imu_link");
  ASSERT_TRUE(t);
  EXPECT_NEAR(t->translation.z(), 0.1, 1e-15);  // the original edge survived
}

TEST_F(GeometryFrameTreeErrors, Cycles) {
  std::string error;
  ASSERT_TRUE(tree.add("a", "b", make(1, 0, 0), &error));
  ASSERT_TRUE(tree.add("b", "c", make(1, 0, 0), &error));
  expect_error("c", "a", "static transform c -> a: frame 'c' already descends from 'a', the edge would close a cycle");
  expect_error("b", "a", "static transform b -> a: frame 'b' already descends from 'a', the edge would close a cycle");
  EXPECT_TRUE(tree.lookup("a", "c"));
}

TEST_F(GeometryFrameTreeErrors, SelfParent) {
  expect_error("base_link", "base_link", "static transform base_link -> base_link: frame 'base_link' cannot be its own parent");
}

TEST_F(GeometryFrameTreeErrors, EmptyNames) {
  expect_error("", "imu_link", "static transform '' -> imu_link: parent frame name is empty");
  expect_error("base_link", "", "static transform base_link -> '': child frame name is empty");
}

TEST_F(GeometryFrameTreeErrors, NamesLongerThan63) {
  const std::string n63(63, 'n');
  const std::string n64(64, 'n');
  std::string error;
  EXPECT_TRUE(tree.add("base_link", n63, RigidTransform::identity(), &error)) << error;
  expect_error("base_link", n64,
               "static transform base_link -> " + n64 + ": child frame name '" + n64 +
                   "' is 64 characters long, the limit is 63");
  expect_error(n64 + "x", "imu",
               "static transform " + n64 + "x -> imu: parent frame name '" + n64 +
                   "x' is 65 characters long, the limit is 63");
}

TEST_F(GeometryFrameTreeErrors, BadTransforms) {
  RigidTransform t = RigidTransform::identity();
  t.translation.y() = std::nan("");
  expect_error("a", "b", "static transform a -> b: transform has a non-finite value", t);
  t = RigidTransform::identity();
  t.rotation.coeffs().setZero();
  expect_error("a", "b", "static transform a -> b: rotation quaternion has zero norm", t);
}

TEST_F(GeometryFrameTreeErrors, Capacity) {
  std::string error;
  // A chain f0 -> f1 -> ... -> f47 fills all 48 slots.
  for (int i = 1; i < FrameTree::kMaxFrames; ++i) {
    ASSERT_TRUE(tree.add("f" + std::to_string(i - 1), "f" + std::to_string(i), make(1, 0, 0), &error)) << error;
  }
  ASSERT_EQ(tree.size(), FrameTree::kMaxFrames);
  expect_error("f47", "extra", "static transform f47 -> extra: frame tree is full (48 frames), cannot add 1 more");
  expect_error("x", "y", "static transform x -> y: frame tree is full (48 frames), cannot add 2 more");
  EXPECT_EQ(tree.intern("extra"), -1);
  // Depth 47: the chain still composes exactly.
  const auto t = tree.lookup("f0", "f47");
  ASSERT_TRUE(t);
  EXPECT_NEAR(t->translation.x(), 47.0, 1e-12);
}

TEST_F(GeometryFrameTreeErrors, FullTreeStillJoinsKnownFrames) {
  std::string error;
  for (int i = 0; i < FrameTree::kMaxFrames; ++i) ASSERT_GE(tree.intern("f" + std::to_string(i)), 0);
  ASSERT_TRUE(tree.add("f0", "f1", make(0, 1, 0), &error)) << error;
  ASSERT_TRUE(tree.lookup("f0", "f1"));
}

}  // namespace frame_tree_test
