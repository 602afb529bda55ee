// Disparities of pixels without horizontal texture are taken back.
#include "vision/texture_filter.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "support/alloc_counter.hpp"

namespace texture_filter_test {

using namespace rtfuse::vision;

struct Images {
  std::vector<std::uint8_t> grey;
  std::vector<std::uint16_t> disparity;
  int w, h;
  Images(int width, int height, int downscale) : w(width), h(height) {
    grey.assign(static_cast<std::size_t>(w) * h, 100);
    disparity.assign(static_cast<std::size_t>(w / downscale) * (h / downscale), 5 * kDisparityScale);
  }
  GreyView view() const { return GreyView{grey.data(), w, h, w}; }
  DisparityImage out(int downscale) { return DisparityImage{disparity.data(), w / downscale, h / downscale, w / downscale}; }
};

TEST(TextureFilter, BlankRegionsLoseTheirDisparitiesTexturedOnesKeepThem) {
  Images im(64, 32, 1);
  // Columns 32 on: vertical stripes 2 px wide, 40 grey levels apart.
  for (int y = 0; y < im.h; ++y)
    for (int x = 32; x < im.w; ++x) im.grey[static_cast<std::size_t>(y) * im.w + x] = (x / 2) % 2 ? 140 : 100;
  TextureFilter filter(64, 32);
  const int taken = filter.apply(im.view(), 1, im.out(1));
  EXPECT_GT(taken, 0);
  EXPECT_EQ(im.disparity[16 * 64 + 10], kInvalidDisparity);  // blank
  EXPECT_EQ(im.disparity[16 * 64 + 50], 5 * kDisparityScale);  // striped
  int kept = 0;
  for (std::uint16_t d : im.disparity) kept += d != kInvalidDisparity;
  EXPECT_EQ(kept + taken, 64 * 32);
}

TEST(TextureFilter, HorizontalEdgesAloneAreNotTexture) {
  // Horizontal stripes: strong change, but none along the rows stereo
  // searches, so nothing can be matched.
  Images im(32, 32, 1);
  for (int y = 0; y < im.h; ++y)
    for (int x = 0; x < im.w; ++x) im.grey[static_cast<std::size_t>(y) * im.w + x] = (y / 2) % 2 ? 200 : 20;
  TextureFilter filter(32, 32);
  EXPECT_EQ(filter.apply(im.view(), 1, im.out(1)), 32 * 32);
}

TEST(TextureFilter, AHalvedDisparityLooksAtItsBlock) {
  Images im(64, 32, 2);
  for (int y = 0; y < im.h; ++y)
    for (int x = 32; x < im.w; ++x) im.grey[static_cast<std::size_t>(y) * im.w + x] = (x % 2) ? 180 : 60;
  TextureFilter filter(64, 32);
  filter.apply(im.view(), 2, im.out(2));
  EXPECT_EQ(im.disparity[8 * 32 + 4], kInvalidDisparity);        // input x 8: blank
  EXPECT_EQ(im.disparity[8 * 32 + 25], 5 * kDisparityScale);     // input x 50: textured
}

TEST(TextureFilter, SizesItCannotTakeAreRefusedAndNothingIsAllocated) {
  Images big(128, 32, 1);
  TextureFilter filter(64, 32);
  EXPECT_EQ(filter.apply(big.view(), 1, big.out(1)), -1);
  Images im(64, 32, 1);
  DisparityImage wrong = im.out(1);
  wrong.width = 65;
  wrong.stride = 65;
  EXPECT_EQ(filter.apply(im.view(), 1, wrong), -1);
  rtfuse::test::AllocScope scope;
  filter.apply(im.view(), 1, im.out(1));
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace texture_filter_test
