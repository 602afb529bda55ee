// write_stereo_png, read back with libpng: size, format, each eye's pixels,
// the guide lines, the header band above them, and errors that name the path
// and the errno text.
#include "apps/stereo_png.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "unit/apps/png_readback.hpp"

namespace rtfuse::apps {
namespace stereo_png_test {

using test_png::read_rgb_png;
using test_png::RgbImage;

std::string temp_path(const char* name) { return test_png::temp_png("rtfuse_stereo_png_", name); }

struct Pair {
  static constexpr int kW = 64, kH = 40, kStride = 80;
  std::vector<std::uint8_t> left, right;
  Pair() : left(kStride * kH, 0xEE), right(kStride * kH, 0xEE) {
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        left[y * kStride + x] = static_cast<std::uint8_t>(x + 2 * y);
        right[y * kStride + x] = static_cast<std::uint8_t>(250 - x - y);
      }
  }
};

bool is_guide(const std::uint8_t* p) { return p[0] == kGuideRgb[0] && p[1] == kGuideRgb[1] && p[2] == kGuideRgb[2]; }

TEST(StereoPng, EyesSideBySideWithGuideLines) {
  const Pair pair;
  const std::string path = temp_path("guides.png");
  std::string error;
  ASSERT_TRUE(write_stereo_png(path, pair.left.data(), pair.right.data(), Pair::kW, Pair::kH, Pair::kStride, 10,
                               &error))
      << error;
  const RgbImage img = read_rgb_png(path);
  ASSERT_EQ(img.width, 2 * Pair::kW);
  ASSERT_EQ(img.height, Pair::kH);

  // A pixel of each eye, by hand: left (5, 3) = 5 + 6; right (5, 3) = 250 - 8.
  EXPECT_EQ(img.at(5, 3)[0], 11);
  EXPECT_EQ(img.at(5, 3)[1], 11);
  EXPECT_EQ(img.at(5, 3)[2], 11);
  EXPECT_EQ(img.at(Pair::kW + 5, 3)[0], 242);
  EXPECT_EQ(img.at(Pair::kW + 5, 3)[1], 242);
  EXPECT_EQ(img.at(Pair::kW + 5, 3)[2], 242);
  // A guide-line pixel in each half.
  EXPECT_TRUE(is_guide(img.at(5, 20)));
  EXPECT_TRUE(is_guide(img.at(Pair::kW + 40, 30)));

  // Everywhere: rows 10, 20, 30 green across both halves, grey elsewhere.
  int wrong = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = img.at(x, y);
      const bool guide = y > 0 && y % 10 == 0;
      const int ex = x % Pair::kW;
      const std::uint8_t grey = x < Pair::kW ? pair.left[y * Pair::kStride + ex] : pair.right[y * Pair::kStride + ex];
      const bool ok = guide ? is_guide(p) : (p[0] == grey && p[1] == grey && p[2] == grey);
      if (!ok && ++wrong <= 5) ADD_FAILURE() << "pixel (" << x << ", " << y << ")";
    }
  EXPECT_EQ(wrong, 0);
  ::unlink(path.c_str());
}

TEST(StereoPng, NoGuideLinesWhenTheSpacingIsZero) {
  const Pair pair;
  const std::string path = temp_path("plain.png");
  std::string error;
  ASSERT_TRUE(write_stereo_png(path, pair.left.data(), pair.right.data(), Pair::kW, Pair::kH, Pair::kStride, 0,
                               &error))
      << error;
  const RgbImage img = read_rgb_png(path);
  ASSERT_EQ(img.height, Pair::kH);
  EXPECT_EQ(img.at(5, 20)[0], 5 + 40);
  EXPECT_EQ(img.at(5, 20)[1], 5 + 40);
  ::unlink(path.c_str());
}

TEST(StereoPng, OpenErrorNamesThePathAndErrno) {
  const Pair pair;
  const std::string path = temp_path("no_such_dir") + "/pair.png";
  std::string error;
  EXPECT_FALSE(write_stereo_png(path, pair.left.data(), pair.right.data(), Pair::kW, Pair::kH, Pair::kStride, 10,
                                &error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("No such file or directory"), std::string::npos) << error;
}

TEST(StereoPng, WriteErrorNamesErrnoAndKeepsTheDevice) {
  if (::access("/dev/full", W_OK) != 0) GTEST_SKIP() << "no writable /dev/full";
  const Pair pair;
  std::string error;
  EXPECT_FALSE(write_stereo_png("/dev/full", pair.left.data(), pair.right.data(), Pair::kW, Pair::kH, Pair::kStride,
                                10, &error));
  EXPECT_NE(error.find("/dev/full"), std::string::npos) << error;
  EXPECT_NE(error.find("No space left on device"), std::string::npos) << error;
  struct stat st {};
  EXPECT_EQ(::stat("/dev/full", &st), 0) << "a device is never unlinked";
}

TEST(StereoPng, BadArgumentsLeaveAnExistingFileAlone) {
  const Pair pair;
  const std::string path = temp_path("keep.png");
  { std::ofstream(path) << "previous snapshot"; }
  std::string error;
  EXPECT_FALSE(write_stereo_png(path, pair.left.data(), pair.right.data(), Pair::kW, Pair::kH, Pair::kW - 1, 10,
                                &error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("stride 63"), std::string::npos) << error;
  EXPECT_FALSE(write_stereo_png(path, nullptr, pair.right.data(), Pair::kW, Pair::kH, Pair::kStride, 10, &error));
  EXPECT_FALSE(write_stereo_png(path, pair.left.data(), pair.right.data(), 0, Pair::kH, Pair::kStride, 10, &error));
  std::string content;
  std::getline(std::ifstream(path), content);
  EXPECT_EQ(content, "previous snapshot");
  ::unlink(path.c_str());
}

// With a header the pair keeps every pixel and guide line, moved down by
// exactly the rows stereo_png_header_rows says; above it the band carries
// dark text and the green guide swatch on light paper.
TEST(StereoPng, HeaderBandAboveTheUnchangedPair) {
  const Pair pair;
  const std::string plain_path = temp_path("no_header.png"), path = temp_path("header.png");
  std::string error;
  ASSERT_TRUE(write_stereo_png(plain_path, pair.left.data(), pair.right.data(), Pair::kW, Pair::kH, Pair::kStride, 10,
                               &error))
      << error;
  const StereoPngHeader header{"camera /dev/video7 of robot.toml", "frame counter 12, t = 1.500 s into the test",
                               350.5, 320.25, 180.75, 0.12};
  ASSERT_TRUE(write_stereo_png(path, pair.left.data(), pair.right.data(), Pair::kW, Pair::kH, Pair::kStride, 10,
                               &header, &error))
      << error;
  const RgbImage plain = read_rgb_png(plain_path), img = read_rgb_png(path);
  const int top = stereo_png_header_rows(Pair::kW);
  ASSERT_GT(top, 0);
  ASSERT_EQ(img.width, 2 * Pair::kW);
  ASSERT_EQ(img.height, top + Pair::kH);
  ASSERT_EQ(plain.height, Pair::kH);
  int moved = 0;
  for (int y = 0; y < Pair::kH; ++y)
    for (int x = 0; x < img.width; ++x)
      for (int c = 0; c < 3; ++c) moved += plain.at(x, y)[c] != img.at(x, top + y)[c] ? 1 : 0;
  EXPECT_EQ(moved, 0) << "the pair below the band is the picture without a header";
  EXPECT_TRUE(is_guide(img.at(3, top + 10)));
  EXPECT_FALSE(is_guide(img.at(3, 10)));

  int ink = 0, paper = 0;
  for (int y = 0; y < top; ++y)
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = img.at(x, y);
      ink += p[0] < 64 && p[1] < 64 && p[2] < 64 ? 1 : 0;
      paper += p[0] > 200 && p[1] > 200 && p[2] > 200 ? 1 : 0;
    }
  EXPECT_GT(ink, 100) << "text in the band";
  EXPECT_GT(paper, img.width * top / 2) << "light paper under it";
  EXPECT_GT(img.count(kGuideRgb[0], kGuideRgb[1], kGuideRgb[2], 0, 0, img.width, top), 0)
      << "the guide lines' legend swatch";
  ::unlink(plain_path.c_str());
  ::unlink(path.c_str());
}

// A pair as wide as a VGA camera's gets the header in twice the font's size:
// the band is taller than on a small pair, and its text fits the width.
TEST(StereoPng, HeaderRowsGrowWithTheTextScale) {
  EXPECT_GT(stereo_png_header_rows(672), stereo_png_header_rows(64));
  EXPECT_EQ(stereo_png_header_rows(672), stereo_png_header_rows(1920));
}

TEST(StereoPng, HeaderedWriteErrorNamesThePathAndErrno) {
  const Pair pair;
  const StereoPngHeader header{"here", "now", 1.0, 2.0, 3.0, 0.1};
  const std::string path = temp_path("no_such_dir") + "/pair.png";
  std::string error;
  EXPECT_FALSE(write_stereo_png(path, pair.left.data(), pair.right.data(), Pair::kW, Pair::kH, Pair::kStride, 10,
                                &header, &error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("No such file or directory"), std::string::npos) << error;
}

}  // namespace stereo_png_test
}  // namespace rtfuse::apps
