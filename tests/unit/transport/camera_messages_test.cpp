// The camera's LCM messages, decoded back with the generated C++ types:
// every field of camera_info_t (ROS stereo convention) and of the image_t
// preview, the box filter's integers, and no allocation per encode.
#include "transport/camera_messages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "rtfuse/camera_info_t.hpp"
#include "rtfuse/image_t.hpp"
#include "support/alloc_counter.hpp"

namespace rtfuse::transport {
namespace camera_messages_test {

StereoCameraInfo zed_vga() {
  StereoCameraInfo m;
  m.width = 672;
  m.height = 376;
  m.fx = 350.25;
  m.fy = 350.25;
  m.cx = 331.5;
  m.cy = 190.75;
  m.baseline_m = 0.1199;
  m.left_frame_id = "zed_left_optical";
  m.right_frame_id = "zed_right_optical";
  return m;
}

template <class Msg>
Msg decode(const EncodedMessage& e) {
  Msg msg;
  EXPECT_TRUE(e.ok());
  EXPECT_EQ(msg.decode(e.data, 0, e.size), e.size) << "the whole buffer is one message";
  return msg;
}

void expect_pinhole(const rtfuse::camera_info_t& c, const StereoCameraInfo& m, double tx) {
  EXPECT_EQ(c.width, m.width);
  EXPECT_EQ(c.height, m.height);
  EXPECT_EQ(c.distortion_model, "plumb_bob");
  ASSERT_EQ(c.num_D, 5);
  ASSERT_EQ(c.D.size(), 5u);
  for (double d : c.D) EXPECT_EQ(d, 0.0);
  const double k[9] = {m.fx, 0, m.cx, 0, m.fy, m.cy, 0, 0, 1};
  const double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const double p[12] = {m.fx, 0, m.cx, tx, 0, m.fy, m.cy, 0, 0, 0, 1, 0};
  for (int i = 0; i < 9; ++i) EXPECT_EQ(c.K[i], k[i]) << "K[" << i << "]";
  for (int i = 0; i < 9; ++i) EXPECT_EQ(c.R[i], r[i]) << "R[" << i << "]";
  for (int i = 0; i < 12; ++i) EXPECT_EQ(c.P[i], p[i]) << "P[" << i << "]";
  EXPECT_EQ(c.binning_x, 0);
  EXPECT_EQ(c.binning_y, 0);
  EXPECT_EQ(c.roi_x_offset, 0);
  EXPECT_EQ(c.roi_y_offset, 0);
  EXPECT_EQ(c.roi_height, 0);
  EXPECT_EQ(c.roi_width, 0);
  EXPECT_EQ(c.roi_do_rectify, 0);
}

TEST(CameraInfoEncoder, LeftAndRightFollowTheRosStereoConvention) {
  const StereoCameraInfo m = zed_vga();
  std::string error;
  auto enc = CameraInfoEncoder::create(m, &error);
  ASSERT_NE(enc, nullptr) << error;

  const TimeNs stamp = 1'234'567'891'234;
  const auto left = decode<rtfuse::camera_info_t>(enc->encode(StereoEye::kLeft, stamp));
  EXPECT_EQ(left.header.utime, 1'234'567'891);
  EXPECT_EQ(left.header.seq, 0);
  EXPECT_EQ(left.header.frame_id, "zed_left_optical");
  expect_pinhole(left, m, 0.0);

  const auto right = decode<rtfuse::camera_info_t>(enc->encode(StereoEye::kRight, stamp));
  EXPECT_EQ(right.header.utime, 1'234'567'891);
  EXPECT_EQ(right.header.seq, 0) << "each eye counts its own messages";
  EXPECT_EQ(right.header.frame_id, "zed_right_optical");
  expect_pinhole(right, m, -m.fx * m.baseline_m);
  // image_geometry's StereoCameraInfo: baseline = -P_right[3] / fx.
  EXPECT_NEAR(-right.P[3] / right.P[0], 0.1199, 1e-15);
  EXPECT_LT(right.P[3], 0.0);

  // Later messages: only the stamp and sequence number change.
  const auto left2 = decode<rtfuse::camera_info_t>(enc->encode(StereoEye::kLeft, stamp + 33'333'333));
  EXPECT_EQ(left2.header.seq, 1);
  EXPECT_EQ(left2.header.utime, 1'234'601'224);
  expect_pinhole(left2, m, 0.0);
  EXPECT_EQ(enc->encode_failures(), 0);
}

TEST(CameraInfoEncoder, RefusesBadModelsNamingTheValue) {
  struct Case {
    void (*change)(StereoCameraInfo&);
    const char* names;
  };
  const Case cases[] = {
      {[](StereoCameraInfo& m) { m.width = 0; }, "width is 0"},
      {[](StereoCameraInfo& m) { m.height = -3; }, "height is -3"},
      {[](StereoCameraInfo& m) { m.fx = std::numeric_limits<double>::quiet_NaN(); }, "fx is nan"},
      {[](StereoCameraInfo& m) { m.fy = -1.0; }, "fy is -1"},
      {[](StereoCameraInfo& m) { m.cx = std::numeric_limits<double>::infinity(); }, "cx is inf"},
      {[](StereoCameraInfo& m) { m.baseline_m = 0.0; }, "baseline_m is 0"},
  };
  for (const Case& c : cases) {
    StereoCameraInfo m = zed_vga();
    c.change(m);
    std::string error;
    EXPECT_EQ(CameraInfoEncoder::create(m, &error), nullptr) << c.names;
    EXPECT_NE(error.find(c.names), std::string::npos) << error;
  }
}

TEST(CameraInfoEncoder, EncodesWithoutAllocating) {
  auto enc = CameraInfoEncoder::create(zed_vga(), nullptr);
  ASSERT_NE(enc, nullptr);
  int bytes = 0;
  std::size_t allocations = 0;
  {
    test::AllocScope scope;
    for (int i = 0; i < 100; ++i) {
      bytes += enc->encode(StereoEye::kLeft, TimeNs{i} * 33'000'000).size;
      bytes += enc->encode(StereoEye::kRight, TimeNs{i} * 33'000'000).size;
    }
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(bytes, 0);
}

// --- preview ----------------------------------------------------------------

// A grey image with rows `stride` bytes apart; the padding holds 0xEE so a
// filter reading past the width shows up in the values.
struct Image {
  int width, height, stride;
  std::vector<std::uint8_t> px;
  Image(int w, int h, int s) : width(w), height(h), stride(s), px(static_cast<std::size_t>(s) * h, 0xEE) {}
  std::uint8_t& at(int x, int y) { return px[static_cast<std::size_t>(y) * stride + x]; }
  GreyImage view() const { return GreyImage{px.data(), width, height, stride}; }
};

TEST(PreviewEncoder, HandComputedBlocks) {
  // 4x2 eyes, factor 2: two blocks per eye; means 15.5 -> 16 (half up), 35.5 -> 36, 0, 255.
  Image left(4, 2, 8), right(4, 2, 5);
  const std::uint8_t l[2][4] = {{10, 20, 30, 40}, {11, 21, 31, 41}};
  const std::uint8_t r[2][4] = {{0, 0, 255, 255}, {0, 1, 255, 255}};
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) {
      left.at(x, y) = l[y][x];
      right.at(x, y) = r[y][x];
    }
  std::string error;
  auto enc = PreviewEncoder::create(4, 2, 2, "zed_left_optical", &error);
  ASSERT_NE(enc, nullptr) << error;
  const auto img = decode<rtfuse::image_t>(enc->encode(left.view(), right.view(), 5'000));
  ASSERT_EQ(img.width, 4);
  ASSERT_EQ(img.height, 1);
  ASSERT_EQ(img.num_data, 4);
  const std::vector<std::uint8_t> want = {16, 36, 0, 255};  // right block 0: 1/4 = 0.25 -> 0
  EXPECT_EQ(img.data, want);
  EXPECT_EQ(img.header.utime, 5);
  EXPECT_EQ(img.header.frame_id, "zed_left_optical");
}

TEST(PreviewEncoder, VgaPairSideBySideMatchesTheBoxFilter) {
  const int w = 672, h = 376, factor = 2;
  Image left(w, h, 704), right(w, h, 704);  // FramePool rounds rows to 64 bytes
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      left.at(x, y) = static_cast<std::uint8_t>((x * 3 + y * 7) & 0xFF);
      right.at(x, y) = static_cast<std::uint8_t>((x * x + 5 * y) % 251);
    }
  std::string error;
  auto enc = PreviewEncoder::create(w, h, factor, "zed_left_optical", &error);
  ASSERT_NE(enc, nullptr) << error;
  EXPECT_EQ(enc->preview_width(), 672);
  EXPECT_EQ(enc->preview_height(), 188);

  const auto img = decode<rtfuse::image_t>(enc->encode(left.view(), right.view(), 2'000'000'000));
  EXPECT_EQ(img.header.utime, 2'000'000);
  EXPECT_EQ(img.header.seq, 0);
  EXPECT_EQ(img.header.frame_id, "zed_left_optical");
  EXPECT_EQ(img.width, 672);
  EXPECT_EQ(img.height, 188);
  EXPECT_EQ(img.encoding, "mono8");
  EXPECT_EQ(img.is_bigendian, 0);
  EXPECT_EQ(img.step, 672);
  ASSERT_EQ(img.num_data, 672 * 188);
  ASSERT_EQ(img.data.size(), 672u * 188u);

  int mismatches = 0;
  for (int oy = 0; oy < 188; ++oy)
    for (int ox = 0; ox < 672; ++ox) {
      Image& eye = ox < 336 ? left : right;
      const int ex = ox % 336;
      int sum = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) sum += eye.at(2 * ex + dx, 2 * oy + dy);
      const int want = (sum + 2) / 4;
      if (img.data[static_cast<std::size_t>(oy) * 672 + ox] != want && ++mismatches <= 5)
        ADD_FAILURE() << "preview (" << ox << ", " << oy << "): " << int(img.data[oy * 672 + ox]) << ", want " << want;
    }
  EXPECT_EQ(mismatches, 0);
  // One value by hand: left block (0, 0) = {0, 3, 7, 10} -> 20 / 4 = 5.
  EXPECT_EQ(img.data[0], 5);

  const auto next = decode<rtfuse::image_t>(enc->encode(left.view(), right.view(), 2'033'000'000));
  EXPECT_EQ(next.header.seq, 1);
  EXPECT_EQ(next.data, img.data);
}

TEST(PreviewEncoder, DropsColumnsAndRowsBeyondTheLastWholeBlock) {
  // 7x4 eyes, factor 3: one row of two blocks per eye; column 6 and row 3 unused.
  Image left(7, 4, 7), right(7, 4, 7);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 7; ++x) {
      left.at(x, y) = x < 3 ? 9 : (x < 6 ? 90 : 255);
      right.at(x, y) = y < 3 ? static_cast<std::uint8_t>(x < 3 ? 200 : 100) : 0;
    }
  auto enc = PreviewEncoder::create(7, 4, 3, "cam", nullptr);
  ASSERT_NE(enc, nullptr);
  const auto img = decode<rtfuse::image_t>(enc->encode(left.view(), right.view(), 0));
  EXPECT_EQ(img.width, 4);
  EXPECT_EQ(img.height, 1);
  EXPECT_EQ(img.step, 4);
  EXPECT_EQ(img.data, (std::vector<std::uint8_t>{9, 90, 200, 100}));
}

TEST(PreviewEncoder, RefusesBadSetupsAndMismatchedImages) {
  std::string error;
  EXPECT_EQ(PreviewEncoder::create(672, 376, 0, "cam", &error), nullptr);
  EXPECT_NE(error.find("factor 0"), std::string::npos) << error;
  EXPECT_EQ(PreviewEncoder::create(672, 376, PreviewEncoder::kMaxFactor + 1, "cam", &error), nullptr);
  EXPECT_EQ(PreviewEncoder::create(0, 376, 2, "cam", &error), nullptr);
  EXPECT_NE(error.find("0x376"), std::string::npos) << error;
  EXPECT_EQ(PreviewEncoder::create(3, 3, 4, "cam", &error), nullptr);
  EXPECT_NE(error.find("smaller than one 4x4 block"), std::string::npos) << error;

  auto enc = PreviewEncoder::create(8, 4, 2, "cam", &error);
  ASSERT_NE(enc, nullptr) << error;
  Image ok(8, 4, 8), small(6, 4, 8), narrow_stride(8, 4, 8);
  narrow_stride.stride = 7;
  EXPECT_FALSE(enc->encode(ok.view(), small.view(), 0).ok());
  EXPECT_FALSE(enc->encode(narrow_stride.view(), ok.view(), 0).ok());
  EXPECT_FALSE(enc->encode(GreyImage{}, ok.view(), 0).ok());
  EXPECT_EQ(enc->encode_failures(), 3);
  EXPECT_TRUE(enc->encode(ok.view(), ok.view(), 0).ok());
  EXPECT_EQ(enc->encode_failures(), 3);
}

TEST(PreviewEncoder, EncodesWithoutAllocating) {
  Image left(672, 376, 704), right(672, 376, 704);
  auto enc = PreviewEncoder::create(672, 376, 2, "zed_left_optical", nullptr);
  ASSERT_NE(enc, nullptr);
  int bytes = 0;
  std::size_t allocations = 0;
  {
    test::AllocScope scope;
    for (int i = 0; i < 20; ++i) bytes += enc->encode(left.view(), right.view(), TimeNs{i} * 100'000'000).size;
    allocations = scope.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(bytes, 20 * 672 * 188);
}

}  // namespace camera_messages_test
}  // namespace rtfuse::transport
