// The occupancy map against OctoMap 1.9.7 itself (Debian's liboctomap-dev,
// test-only): the same clouds into an OcTree (insertPointCloud, lazy_eval
// and discretize off) and into the map, then every voxel OctoMap knows at
// the finest depth compared as float32 bits, the count of known voxels
// (so nothing extra is known here), the .bt files byte for byte, and the
// memory (at most half of OcTree::memoryUsage()). No tolerance: the ray
// arithmetic is OctoMap's, so a single differing voxel is a failure.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "apps/stereo_clouds.hpp"
#include "mapping/map_digest.hpp"
#include "mapping/octomap_binary.hpp"
#include "mapping/octomap_binary_reader.hpp"
#include "octomap_reference.hpp"

namespace octomap_equality_test {

using namespace rtfuse::mapping;

constexpr BrickCapacity kPool{200000, 400000};

const std::vector<MapPoint>& scan() {
  static const std::vector<MapPoint> points = rtfuse::test::read_octomap_scan(RTFUSE_SHARED_DATA);
  return points;
}

struct Maps {
  octomap::OcTree tree;
  OccupancyMap map;
  explicit Maps(double resolution) : tree(resolution), map(params(resolution), kPool) {}
  static OccupancyParams params(double resolution) {
    OccupancyParams p;
    p.resolution = resolution;
    return p;
  }
  void insert(const std::vector<MapPoint>& cloud, MapPoint origin, double max_range) {
    tree.insertPointCloud(rtfuse::test::to_octomap(cloud), octomap::point3d(origin.x, origin.y, origin.z), max_range,
                          false, false);
    map.insert_scan(cloud.data(), cloud.size(), origin, max_range);
  }
};

void expect_equal(Maps& m) {
  const rtfuse::test::Difference d = rtfuse::test::compare(m.tree, m.map);
  EXPECT_EQ(d.missing, 0u) << d.first;
  EXPECT_EQ(d.different, 0u) << d.first;
  EXPECT_EQ(m.map.known_voxels(), d.octomap_voxels);
  std::uint64_t occupied = 0;
  for (auto it = m.tree.begin_leafs(), end = m.tree.end_leafs(); it != end; ++it) {
    if (m.tree.isNodeOccupied(*it)) occupied += std::uint64_t{1} << (3 * (16 - it.getDepth()));
  }
  EXPECT_EQ(m.map.occupied_voxels(), occupied);

  const std::size_t octomap_bytes = m.tree.memoryUsage();
  EXPECT_LE(2 * m.map.store().bytes_used(), octomap_bytes)
      << "map " << m.map.store().bytes_used() << " bytes, OctoMap " << octomap_bytes;
  std::printf("voxels %llu (occupied %llu), OctoMap leaves %zu; memory %zu vs OctoMap %zu bytes (%.2f)\n",
              static_cast<unsigned long long>(d.octomap_voxels), static_cast<unsigned long long>(occupied),
              m.tree.getNumLeafNodes(), m.map.store().bytes_used(), octomap_bytes,
              static_cast<double>(m.map.store().bytes_used()) / static_cast<double>(octomap_bytes));

  // The file: OctoMap's writeBinary turns its tree to maximum likelihood
  // and prunes it, so it comes after the voxel comparison.
  OctomapBinaryWriter writer(kPool.bricks);
  std::vector<std::uint8_t> ours;
  const std::size_t nodes = writer.write(m.map, ours);
  std::ostringstream theirs;
  ASSERT_TRUE(m.tree.writeBinary(theirs));
  const std::string reference = theirs.str();
  EXPECT_EQ(nodes, m.tree.size());
  const std::string file(ours.begin(), ours.end());
  ASSERT_EQ(file.size(), reference.size());
  EXPECT_TRUE(file == reference) << ".bt bytes differ";

  // And OctoMap reads our file back into the tree it wrote.
  std::istringstream in(file);
  octomap::OcTree back(m.map.grid().resolution());
  ASSERT_TRUE(back.readBinary(in));
  EXPECT_EQ(back.size(), m.tree.size());
  EXPECT_EQ(back.getNumLeafNodes(), m.tree.getNumLeafNodes());
}

// OctoMap's test_scans: a 101 x 101 patch of a sphere around a sensor at
// (1, 0, -0.5), at 0.05 m, as its own spherical_scan.graph holds it.
TEST(OctomapEquality, SphericalScan) {
  octomap::ScanGraph graph;
  ASSERT_TRUE(graph.readBinary(std::string(RTFUSE_SHARED_DATA) + "/octomap/spherical_scan.graph"));
  ASSERT_EQ(graph.size(), 1u);
  octomap::ScanNode* node = *graph.begin();
  octomap::Pointcloud world(*node->scan);
  world.transform(node->pose);  // as insertPointCloud(scan, origin, pose) does, once for both maps
  std::vector<MapPoint> cloud;
  for (const auto& p : world) cloud.push_back({p.x(), p.y(), p.z()});
  const octomap::point3d o = node->pose.trans();
  Maps m(0.05);
  m.insert(cloud, {o.x(), o.y(), o.z()}, -1.0);
  expect_equal(m);
}

struct ScanCase {
  double resolution;
  double max_range;
};

class ScanDat : public ::testing::TestWithParam<ScanCase> {};

TEST_P(ScanDat, OneRealLaserScan) {
  Maps m(GetParam().resolution);
  m.insert(scan(), {0, 0, 0}, GetParam().max_range);
  expect_equal(m);
}

INSTANTIATE_TEST_SUITE_P(ResolutionAndRange, ScanDat,
                         ::testing::Values(ScanCase{0.1, -1.0}, ScanCase{0.1, 10.0}, ScanCase{0.05, -1.0},
                                           ScanCase{0.05, 10.0}),
                         [](const auto& info) {
                           return std::string(info.param.resolution == 0.1 ? "res10cm" : "res5cm") +
                                  (info.param.max_range < 0 ? "_unlimited" : "_range10m");
                         });

// Several scans from a moving sensor: voxels seen again are summed, clamp,
// turn from free to occupied and back, and OctoMap's file pruning gets
// something to collapse.
TEST(OctomapEquality, ScansFromAMovingSensor) {
  const std::vector<MapPoint>& points = scan();
  Maps m(0.1);
  for (int k = 0; k < 6; ++k) {
    const MapPoint origin{0.35f * k, 0.1f * k, 0.02f * k};
    std::vector<MapPoint> cloud;
    for (std::size_t i = static_cast<std::size_t>(k); i < points.size(); i += 2) {
      cloud.push_back({points[i].x + origin.x, points[i].y + origin.y, points[i].z + origin.z});
    }
    m.insert(cloud, origin, 8.0);
  }
  expect_equal(m);
  // Voxels are updated several times over; some reached the clamps.
  bool clamped = false;
  m.map.for_each_voxel([&](const VoxelKey&, float v) {
    clamped |= v == m.map.log_odds().clamp_min || v == m.map.log_odds().clamp_max;
  });
  EXPECT_TRUE(clamped);
}

// The project's own depth: dense disparity of the real KITTI 06 pairs
// (half resolution, 96 disparities) back-projected and placed with the
// ground truth poses, every third frame from 11 (frames 1-11 of the shared
// copy repeat one interpolated motion), 15 m range, 0.1 m voxels.
TEST(OctomapEquality, KittiStereoWithGroundTruthPoses) {
  rtfuse::apps::KittiSequence seq;
  std::string error;
  ASSERT_TRUE(rtfuse::apps::open_kitti_sequence(std::string(RTFUSE_SHARED_DATA) + "/kitti/kitti06_0000_0050", &seq,
                                                &error))
      << error;
  rtfuse::vision::DisparityParams params;
  params.disparities = 96;
  params.downscale = 2;
  std::vector<rtfuse::apps::StereoCloud> clouds;
  ASSERT_TRUE(rtfuse::apps::stereo_clouds(seq, seq.ground_truth, {11, 14, 17}, params, &clouds, &error)) << error;
  Maps m(0.1);
  for (const auto& cloud : clouds) {
    EXPECT_GT(cloud.points.size(), 40000u);  // of 113k pixels: sky and blank road dropped
    m.insert(cloud.points, cloud.origin, 15.0);
  }
  expect_equal(m);
}

// A .bt OctoMap wrote itself, of a real building (its example geb079.bt,
// 0.08 m), read by both: the same voxels, each at OctoMap's clamp of its
// side, and written back, the same file.
TEST(OctomapEquality, ReadsOctomapsOwnFile) {
  const std::string path = "/usr/share/doc/liboctomap-dev/examples/data/geb079.bt";
  std::ifstream in(path, std::ios::binary);
  if (!in) GTEST_SKIP() << path << " is not installed (a system without /usr/share/doc)";
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  octomap::OcTree tree(0.1);
  std::istringstream s(file);
  ASSERT_TRUE(tree.readBinary(s));
  OccupancyMap map(Maps::params(tree.getResolution()), kPool);
  std::string error;
  ASSERT_TRUE(read_octomap_binary(reinterpret_cast<const std::uint8_t*>(file.data()), file.size(), path, map,
                                  &error))
      << error;
  const rtfuse::test::Difference d = rtfuse::test::compare(tree, map);
  EXPECT_EQ(d.missing, 0u) << d.first;
  EXPECT_EQ(d.different, 0u) << d.first;
  EXPECT_EQ(map.known_voxels(), d.octomap_voxels);
  OctomapBinaryWriter writer(kPool.bricks);
  std::vector<std::uint8_t> again;
  writer.write(map, again);
  std::printf("geb079.bt: %llu voxels, %zu bytes; written back %zu bytes\n",
              static_cast<unsigned long long>(d.octomap_voxels), file.size(), again.size());
  EXPECT_TRUE(std::string(again.begin(), again.end()) == file);
}

}  // namespace octomap_equality_test
