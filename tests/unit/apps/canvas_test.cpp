// The figure canvas: lines land on the pixels they should and nowhere
// outside the clip, markers have their radius, and the PNG written is the
// canvas, or an error naming the path and the errno text.
#include "apps/canvas.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <string>

#include "unit/apps/png_readback.hpp"

namespace rtfuse::apps {
namespace canvas_test {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kBlue{20, 60, 200};

int count(const Canvas& c, Rgb colour) {
  int n = 0;
  for (int y = 0; y < c.height(); ++y)
    for (int x = 0; x < c.width(); ++x) n += c.at(x, y) == colour ? 1 : 0;
  return n;
}

TEST(Canvas, LinesCoverTheirPixelsAndThickness) {
  Canvas c(40, 30, kWhite);
  c.line({5, 10}, {25, 10}, kBlue);
  EXPECT_EQ(count(c, kBlue), 21);
  for (int x = 5; x <= 25; ++x) EXPECT_EQ(c.at(x, 10), kBlue) << x;

  Canvas thick(40, 30, kWhite);
  thick.line({5, 10}, {25, 10}, kBlue, 3);
  EXPECT_EQ(count(thick, kBlue), 3 * 23) << "a square pen: 3 rows, one pixel past each end";
  EXPECT_EQ(thick.at(15, 9), kBlue);
  EXPECT_EQ(thick.at(15, 11), kBlue);
  EXPECT_NE(thick.at(15, 12), kBlue);

  Canvas diagonal(40, 30, kWhite);
  diagonal.line({0, 0}, {20, 20}, kBlue);
  for (int i = 0; i <= 20; ++i) EXPECT_EQ(diagonal.at(i, i), kBlue) << i;
  EXPECT_EQ(count(diagonal, kBlue), 21);
}

// Clipping: the part inside the clip is drawn as it would be without it,
// nothing outside, and far-off or non-finite ends cost nothing.
TEST(Canvas, LinesAreClipped) {
  Canvas c(60, 40, kWhite);
  const Rect clip{10, 5, 30, 20};
  c.set_clip(clip);
  c.line({-1e15, 15}, {1e15, 15}, kBlue, 1);
  c.line({25, -1e300}, {25, 1e300}, kBlue, 1);
  int outside = 0;
  for (int y = 0; y < c.height(); ++y)
    for (int x = 0; x < c.width(); ++x)
      if (c.at(x, y) == kBlue && !clip.contains(x, y)) ++outside;
  EXPECT_EQ(outside, 0);
  EXPECT_EQ(count(c, kBlue), 30 + 20 - 1);

  Canvas none(20, 20, kWhite);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  none.line({nan, 3}, {10, 10}, kBlue);
  none.line({0, 0}, {inf, 10}, kBlue);
  none.polyline({{1, 1}, {nan, nan}, {5, 5}}, kBlue);
  none.marker({nan, 2}, Marker::kDisc, 3, kBlue);
  EXPECT_EQ(count(none, kBlue), 0);
}

TEST(Canvas, MarkersHaveTheirRadius) {
  Canvas c(41, 41, kWhite);
  c.marker({20, 20}, Marker::kDisc, 6, kBlue);
  EXPECT_EQ(c.at(20, 20), kBlue);
  EXPECT_EQ(c.at(26, 20), kBlue);
  EXPECT_EQ(c.at(20, 14), kBlue);
  EXPECT_NE(c.at(27, 20), kBlue);
  EXPECT_NE(c.at(25, 25), kBlue) << "a disc, not a square";

  Canvas ring(41, 41, kWhite);
  ring.marker({20, 20}, Marker::kCircle, 6, kBlue, 2);
  EXPECT_NE(ring.at(20, 20), kBlue) << "hollow";
  EXPECT_EQ(ring.at(26, 20), kBlue);
  EXPECT_EQ(ring.at(25, 20), kBlue);
  EXPECT_NE(ring.at(24, 20), kBlue);
}

TEST(Canvas, PngIsTheCanvas) {
  Canvas c(37, 23, Rgb{250, 240, 230});
  c.fill_rect({3, 4, 10, 5}, kBlue);
  c.line({0, 22}, {36, 0}, Rgb{1, 2, 3}, 2);
  c.text(12, 8, "Ok", Rgb{0, 0, 0}, 1);
  const std::string path = test_png::temp_png("rtfuse_canvas_", "canvas.png");
  std::string error;
  ASSERT_TRUE(write_png(c, path, &error)) << error;
  const test_png::RgbImage img = test_png::read_rgb_png(path);
  ASSERT_EQ(img.width, 37);
  ASSERT_EQ(img.height, 23);
  int wrong = 0;
  for (int y = 0; y < 23; ++y)
    for (int x = 0; x < 37; ++x) {
      const Rgb p = c.at(x, y);
      wrong += img.is(x, y, p.r, p.g, p.b) ? 0 : 1;
    }
  EXPECT_EQ(wrong, 0);
  ::unlink(path.c_str());
}

TEST(Canvas, UnwritablePathNamesThePathAndErrno) {
  const Canvas c(8, 8, kWhite);
  const std::string path = test_png::temp_png("rtfuse_canvas_", "no_such_dir") + "/figure.png";
  std::string error;
  EXPECT_FALSE(write_png(c, path, &error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("No such file or directory"), std::string::npos) << error;

  if (::access("/dev/full", W_OK) != 0) GTEST_SKIP() << "no writable /dev/full";
  EXPECT_FALSE(write_png(c, "/dev/full", &error));
  EXPECT_NE(error.find("/dev/full"), std::string::npos) << error;
  EXPECT_NE(error.find("No space left on device"), std::string::npos) << error;
  struct stat st {};
  EXPECT_EQ(::stat("/dev/full", &st), 0) << "a device is never unlinked";
}

}  // namespace canvas_test
}  // namespace rtfuse::apps
