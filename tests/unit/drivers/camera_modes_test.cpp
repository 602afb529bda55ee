// ZED camera modes: the published resolution / frame-rate table, lookup by
// name and rate, and the side-by-side frame geometry.
#include "drivers/camera/camera_modes.hpp"

#include <gtest/gtest.h>

#include <string>

namespace camera_modes_test {

using rtfuse::drivers::CameraMode;
using rtfuse::drivers::ZedResolution;

TEST(CameraModes, TableHoldsEveryPublishedMode) {
  const auto& modes = rtfuse::drivers::zed_modes();
  std::string listed;
  for (const CameraMode& m : modes) {
    listed += std::string(resolution_name(m.resolution)) + " " + std::to_string(m.eye_width) + "x" +
              std::to_string(m.eye_height) + "@" + std::to_string(m.fps) + "; ";
  }
  EXPECT_EQ(listed,
            "2K 2208x1242@15; FHD 1920x1080@15; FHD 1920x1080@30; HD 1280x720@15; HD 1280x720@30; HD 1280x720@60; "
            "VGA 672x376@15; VGA 672x376@30; VGA 672x376@60; VGA 672x376@100; ");
}

TEST(CameraModes, FindsModeByNameAndRate) {
  CameraMode m;
  std::string error;
  ASSERT_TRUE(find_camera_mode("HD", 60, &m, &error)) << error;
  EXPECT_EQ(m.resolution, ZedResolution::kHD);
  EXPECT_EQ(m.eye_width, 1280);
  EXPECT_EQ(m.eye_height, 720);
  EXPECT_EQ(m.fps, 60);
  ASSERT_TRUE(find_camera_mode("vga", 100, &m, &error)) << error;  // case does not matter
  EXPECT_EQ(m.resolution, ZedResolution::kVGA);
  ASSERT_TRUE(find_camera_mode("2K", 15, &m, &error)) << error;
  EXPECT_EQ(m.eye_width, 2208);
  EXPECT_EQ(m.eye_height, 1242);
}

TEST(CameraModes, UnknownRateListsTheValidChoices) {
  CameraMode m;
  std::string error;
  EXPECT_FALSE(find_camera_mode("HD", 100, &m, &error));
  EXPECT_EQ(error,
            "zed camera: HD has no 100 fps mode; valid modes (resolution@fps): 2K@15, FHD@15/30, HD@15/30/60, "
            "VGA@15/30/60/100");
  EXPECT_FALSE(find_camera_mode("2K", 30, &m, &error));
  EXPECT_NE(error.find("2K has no 30 fps mode"), std::string::npos) << error;
}

TEST(CameraModes, UnknownResolutionListsTheValidChoices) {
  CameraMode m;
  std::string error;
  EXPECT_FALSE(find_camera_mode("HD1080", 30, &m, &error));
  EXPECT_EQ(error,
            "zed camera: resolution \"HD1080\" is unknown; valid modes (resolution@fps): 2K@15, FHD@15/30, "
            "HD@15/30/60, VGA@15/30/60/100");
  EXPECT_FALSE(find_camera_mode("", 30, &m, &error));
  EXPECT_NE(error.find("resolution \"\" is unknown"), std::string::npos) << error;
}

TEST(CameraModes, ResolutionNamesRoundTrip) {
  for (ZedResolution r : {ZedResolution::k2K, ZedResolution::kFHD, ZedResolution::kHD, ZedResolution::kVGA}) {
    ZedResolution back = ZedResolution::k2K;
    ASSERT_TRUE(rtfuse::drivers::parse_resolution(resolution_name(r), &back));
    EXPECT_EQ(back, r);
  }
  ZedResolution r = ZedResolution::kHD;
  EXPECT_FALSE(rtfuse::drivers::parse_resolution("HD2", &r));
  EXPECT_FALSE(rtfuse::drivers::parse_resolution("H", &r));
  EXPECT_EQ(rtfuse::drivers::eye_size(ZedResolution::kFHD).width, 1920);
  EXPECT_EQ(rtfuse::drivers::eye_size(ZedResolution::kFHD).height, 1080);
}

TEST(CameraModes, SideBySideFrameIsTwoEyesWide) {
  CameraMode m;
  std::string error;
  ASSERT_TRUE(find_camera_mode("VGA", 30, &m, &error)) << error;
  EXPECT_EQ(rtfuse::drivers::side_by_side_width(m), 1344);
  EXPECT_EQ(rtfuse::drivers::side_by_side_height(m), 376);
  EXPECT_EQ(rtfuse::drivers::yuyv_min_bytes_per_line(m), 2688);
  EXPECT_EQ(rtfuse::drivers::yuyv_frame_bytes(m, 2688), 2688u * 376u);
  EXPECT_EQ(rtfuse::drivers::yuyv_frame_bytes(m, 2752), 2752u * 376u);  // padded lines
}

}  // namespace camera_modes_test
