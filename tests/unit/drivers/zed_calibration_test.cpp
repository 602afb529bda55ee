// The ZED factory calibration reader: a realistic SN<serial>.conf for every
// resolution, the ZED -> OpenCV convention, and every way a file can be
// wrong, each with its message (file, line, key). A deterministic mutation
// loop stands in for the fuzzer until it exists: no input may crash it.
#include "drivers/camera/zed_calibration.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

#include "unit/drivers/zed_test_calibrations.hpp"

namespace zed_calibration_test {

using rtfuse::drivers::ZedCalibration;
using rtfuse::drivers::ZedResolution;

constexpr const char* kName = "SN21531.conf";

// 1-based line of the first line containing `needle`.
int line_of(const std::string& text, const std::string& needle) {
  const std::size_t at = text.find(needle);
  EXPECT_NE(at, std::string::npos) << needle;
  int line = 1;
  for (std::size_t i = 0; i < at; ++i) line += text[i] == '\n';
  return line;
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// The text between `[section]` and the next blank line, removed.
std::string without_section(const std::string& text, const std::string& section) {
  const std::size_t at = text.find("[" + section + "]");
  EXPECT_NE(at, std::string::npos) << section;
  const std::size_t end = text.find("\n\n", at);
  return text.substr(0, at) + text.substr(end + 2);
}

std::string parse_error(const std::string& text, ZedResolution r = ZedResolution::kHD, const char* name = kName,
                        std::int64_t serial = 0) {
  ZedCalibration c;
  std::string error;
  EXPECT_FALSE(rtfuse::drivers::parse_zed_calibration(text, name, r, serial, &c, &error));
  return error;
}

TEST(ZedCalibration, ReadsRealisticFileForEveryResolution) {
  const std::string text = rtfuse::test::realistic_zed_file();
  ZedCalibration c;
  std::string error;
  ASSERT_TRUE(parse_zed_calibration(text, kName, ZedResolution::kHD, 0, &c, &error)) << error;
  const rtfuse::drivers::StereoCalibration expected = rtfuse::test::zed_like_hd();
  EXPECT_EQ(c.serial, 21531);
  EXPECT_EQ(c.resolution, ZedResolution::kHD);
  EXPECT_EQ(c.stereo.width, 1280);
  EXPECT_EQ(c.stereo.height, 720);
  EXPECT_EQ(c.stereo.left.fx, expected.left.fx);
  EXPECT_EQ(c.stereo.left.cy, expected.left.cy);
  EXPECT_EQ(c.stereo.left.k3, expected.left.k3);
  EXPECT_EQ(c.stereo.right.cx, expected.right.cx);
  EXPECT_EQ(c.stereo.right.p2, expected.right.p2);
  // Convention: rotation = (RX, CV, RZ) as it stands; T = -(Baseline, TY, TZ) in metres.
  EXPECT_EQ(c.stereo.rotation, expected.rotation);
  EXPECT_NEAR(c.stereo.translation.x(), -0.119997, 1e-15);
  EXPECT_NEAR(c.stereo.translation.y(), -0.00157105e-3, 1e-18);
  EXPECT_NEAR(c.stereo.translation.z(), -0.00237081e-3, 1e-18);

  struct {
    ZedResolution r;
    int width, height;
    double left_fx, right_cy;
  } cases[] = {{ZedResolution::k2K, 2208, 1242, 1398.68, 573.25},
               {ZedResolution::kFHD, 1920, 1080, 1398.68, 508.49},
               {ZedResolution::kVGA, 672, 376, 349.67, 179.872}};
  for (const auto& k : cases) {
    ASSERT_TRUE(parse_zed_calibration(text, kName, k.r, 0, &c, &error)) << error;
    EXPECT_EQ(c.stereo.width, k.width);
    EXPECT_EQ(c.stereo.height, k.height);
    EXPECT_EQ(c.stereo.left.fx, k.left_fx);
    EXPECT_EQ(c.stereo.right.cy, k.right_cy);
  }
}

TEST(ZedCalibration, SerialComesFromTheFileNameInAnyFolder) {
  ZedCalibration c;
  std::string error;
  ASSERT_TRUE(parse_zed_calibration(rtfuse::test::realistic_zed_file(), "/usr/local/zed/settings/SN10027514.conf",
                                    ZedResolution::kVGA, 10027514, &c, &error))
      << error;
  EXPECT_EQ(c.serial, 10027514);
  // Without a configured serial any name will do.
  ASSERT_TRUE(parse_zed_calibration(rtfuse::test::realistic_zed_file(), "calib/zed_left.ini", ZedResolution::kVGA, 0,
                                    &c, &error))
      << error;
  EXPECT_EQ(c.serial, 0);
}

TEST(ZedCalibration, PerResolutionTranslationWinsAndLayoutVariantsAreRead) {
  // CRLF line ends, a byte-order mark, spaces around '=', comments, lower-
  // case section and key names, a leading '+', TY_HD / TZ_HD next to TY / TZ.
  std::string text = "\xEF\xBB\xBF# ZED calibration\r\n; exported by hand\r\n";
  text += "[left_cam_hd]\r\n fx = 700\r\nfy=+701\r\ncx=640\r\ncy=360\r\nk1=-0.17\r\nk2=0.03\r\np1=0\r\np2=0\r\nk3=0\r\n";
  text += "k4 = 12\r\nS1=whatever\r\n";
  text += "[RIGHT_CAM_HD]\r\nfx=700\r\nfy=700\r\ncx=641\r\ncy=350\r\nk1=-0.17\r\nk2=0.03\r\np1=0\r\np2=0\r\nk3=0\r\n\r\n";
  text += "[STEREO]\r\nbaseline=63.0\r\nTY=1\r\nTZ=2\r\nTY_HD=0.5\r\nTZ_HD=-0.25\r\ncv_hd=0.01\r\nRX_HD=0.02\r\nRZ_HD=0.03\r\n";
  text += "[IMU]\r\nacc = 1 2 3\r\n";
  ZedCalibration c;
  std::string error;
  ASSERT_TRUE(parse_zed_calibration(text, kName, ZedResolution::kHD, 0, &c, &error)) << error;
  EXPECT_EQ(c.stereo.left.fx, 700.0);
  EXPECT_EQ(c.stereo.left.fy, 701.0);
  EXPECT_EQ(c.stereo.rotation, Eigen::Vector3d(0.02, 0.01, 0.03));
  EXPECT_EQ(c.stereo.translation, Eigen::Vector3d(-63.0, -0.5, 0.25) * 1e-3);
}

TEST(ZedCalibration, MissingSectionIsNamed) {
  const std::string text = without_section(rtfuse::test::realistic_zed_file(), "RIGHT_CAM_HD");
  EXPECT_EQ(parse_error(text),
            "zed calibration: SN21531.conf: missing section [RIGHT_CAM_HD]; the file is incomplete, download it "
            "again from https://calib.stereolabs.com/?SN=<serial>");
  const std::string no_stereo = without_section(rtfuse::test::realistic_zed_file(), "STEREO");
  EXPECT_EQ(parse_error(no_stereo),
            "zed calibration: SN21531.conf: missing section [STEREO] (Baseline, TY, TZ, CV_HD, RX_HD, RZ_HD)");
}

TEST(ZedCalibration, MissingKeyNamesSectionLineAndKey) {
  const std::string full = rtfuse::test::realistic_zed_file();
  const std::string hd = full.substr(full.find("[LEFT_CAM_HD]"));
  const std::string text = full.substr(0, full.find("[LEFT_CAM_HD]")) + replaced(hd, "k3=-0.000911\n", "");
  EXPECT_EQ(parse_error(text), "zed calibration: SN21531.conf:" + std::to_string(line_of(text, "[LEFT_CAM_HD]")) +
                                   ": [LEFT_CAM_HD] has no key 'k3' (each eye needs fx fy cx cy k1 k2 p1 p2 k3)");

  const std::string no_cv = replaced(full, "CV_HD=0.0125461\n", "");
  EXPECT_EQ(parse_error(no_cv), "zed calibration: SN21531.conf:" + std::to_string(line_of(no_cv, "[STEREO]")) +
                                    ": [STEREO] has no key 'CV_HD' (rotation of the right eye, radians)");
  const std::string no_tz = replaced(full, "TZ=0.00237081\n", "");
  EXPECT_EQ(parse_error(no_tz), "zed calibration: SN21531.conf:" + std::to_string(line_of(no_tz, "[STEREO]")) +
                                    ": [STEREO] has no key 'TZ' (nor 'TZ_HD'; millimetres)");
  const std::string no_baseline = replaced(full, "Baseline=119.997\n", "");
  EXPECT_NE(parse_error(no_baseline).find("[STEREO] has no key 'Baseline' (millimetres)"), std::string::npos);
}

TEST(ZedCalibration, MalformedNumbersNameLineKeyAndValue) {
  const std::string full = rtfuse::test::realistic_zed_file();
  const int line = line_of(full, "fx=699.34");
  const std::string prefix = "zed calibration: SN21531.conf:" + std::to_string(line) + ": [LEFT_CAM_HD] fx = ";
  EXPECT_EQ(parse_error(replaced(full, "fx=699.34", "fx=699.34abc")),
            prefix + "'699.34abc': malformed number (trailing characters after the number)");
  EXPECT_EQ(parse_error(replaced(full, "fx=699.34", "fx=699,34")),
            prefix + "'699,34': malformed number (trailing characters after the number)");
  EXPECT_EQ(parse_error(replaced(full, "fx=699.34", "fx=")), prefix + "'': malformed number (empty value)");
  EXPECT_EQ(parse_error(replaced(full, "fx=699.34", "fx=nan")),
            prefix + "'nan': malformed number (NaN and infinity are not calibration values)");
  EXPECT_EQ(parse_error(replaced(full, "fx=699.34", "fx=-inf")),
            prefix + "'-inf': malformed number (NaN and infinity are not calibration values)");
  EXPECT_EQ(parse_error(replaced(full, "fx=699.34", "fx=1e999")),
            prefix + "'1e999': malformed number (out of the range of a double)");
  EXPECT_EQ(parse_error(replaced(full, "fx=699.34", "fx=+-1")), prefix + "'+-1': malformed number (not a number)");
  EXPECT_EQ(parse_error(replaced(full, "fx=699.34", "fx=abc")), prefix + "'abc': malformed number (not a number)");
  EXPECT_EQ(parse_error(replaced(full, "fx=699.34", "fx=0x2bb")),
            prefix + "'0x2bb': malformed number (trailing characters after the number)");
  // A malformed value in another resolution still means a damaged file.
  const std::string vga = replaced(full, "RZ_VGA=-0.00163963", "RZ_VGA=-0.0016 3963");
  EXPECT_EQ(parse_error(vga), "zed calibration: SN21531.conf:" + std::to_string(line_of(vga, "RZ_VGA")) +
                                  ": [STEREO] RZ_VGA = '-0.0016 3963': malformed number (trailing characters after "
                                  "the number)");
}

TEST(ZedCalibration, DuplicateKeyNamesBothLines) {
  const std::string full = rtfuse::test::realistic_zed_file();
  const std::string text = replaced(full, "cy=342.745\n", "cy=342.745\nCY=343\n");
  const int first = line_of(text, "cy=342.745");
  EXPECT_EQ(parse_error(text), "zed calibration: SN21531.conf:" + std::to_string(first + 1) +
                                   ": [RIGHT_CAM_HD] cy: duplicate key (first set on line " + std::to_string(first) +
                                   "); keep one of the two");
  const std::string twice = replaced(full, "TY=0.00157105\n", "TY=0.00157105\nTY=0.0016\n");
  EXPECT_NE(parse_error(twice).find("[STEREO] TY: duplicate key"), std::string::npos);
}

TEST(ZedCalibration, NonPositiveFocalLengthIsRejected) {
  const std::string full = rtfuse::test::realistic_zed_file();
  const std::string zero = replaced(full, "fy=699.34", "fy=0");
  EXPECT_EQ(parse_error(zero), "zed calibration: SN21531.conf:" + std::to_string(line_of(zero, "fy=0")) +
                                   ": [LEFT_CAM_HD] fy = 0: focal length must be > 0 pixels");
  const std::string negative = replaced(full, "fx=700.784", "fx=-700.784");
  EXPECT_EQ(parse_error(negative), "zed calibration: SN21531.conf:" + std::to_string(line_of(negative, "fx=-700")) +
                                       ": [RIGHT_CAM_HD] fx = -700.784: focal length must be > 0 pixels");
  const std::string baseline = replaced(full, "Baseline=119.997", "Baseline=-119.997");
  EXPECT_NE(parse_error(baseline).find("[STEREO] Baseline = -119.997: must be > 0 mm"), std::string::npos);
}

TEST(ZedCalibration, LinesThatAreNeitherKeyValueNorSection) {
  const std::string full = rtfuse::test::realistic_zed_file();
  struct {
    const char* line;
    const char* shown;
  } cases[] = {{"this is not ini", "this is not ini"},
               {"[LEFT_CAM_HD", "[LEFT_CAM_HD"},
               {"[]", "[]"},
               {"[LEFT CAM]", "[LEFT CAM]"},
               {"= 5", "= 5"},
               {"f x = 5", "f x = 5"}};
  for (const auto& k : cases) {
    const std::string text = replaced(full, "[MISC]\n", std::string("[MISC]\n") + k.line + "\n");
    EXPECT_EQ(parse_error(text), "zed calibration: SN21531.conf:" + std::to_string(line_of(text, "[MISC]") + 1) +
                                     ": '" + k.shown + "' is neither `key = value` nor a `[SECTION]` header");
  }
  EXPECT_EQ(parse_error("fx=1\n" + full), "zed calibration: SN21531.conf:1: key 'fx' comes before any [SECTION] header");
  // Control bytes are shown as '?', never printed raw.
  const std::string binary = replaced(full, "[MISC]\n", "[MISC]\n\x01\x02garbage\n");
  EXPECT_NE(parse_error(binary).find("'??garbage' is neither"), std::string::npos);
}

TEST(ZedCalibration, SerialMustMatchTheConfiguredCamera) {
  const std::string full = rtfuse::test::realistic_zed_file();
  EXPECT_EQ(parse_error(full, ZedResolution::kHD, "/etc/rtfuse/SN21531.conf", 12345),
            "zed calibration: /etc/rtfuse/SN21531.conf: calibration of camera SN21531, but the configured camera is "
            "SN12345: use SN12345.conf (https://calib.stereolabs.com/?SN=12345) or fix the configured serial");
  EXPECT_EQ(parse_error(full, ZedResolution::kHD, "zed.conf", 12345),
            "zed calibration: zed.conf: the file name is not SN<serial>.conf, so the configured serial 12345 cannot "
            "be checked; use the factory file's name (SN12345.conf)");
  EXPECT_NE(parse_error(full, ZedResolution::kHD, "SN12a45.conf", 12345).find("not SN<serial>.conf"),
            std::string::npos);
  ZedCalibration c;
  std::string error;
  EXPECT_TRUE(parse_zed_calibration(full, "SN21531.conf", ZedResolution::kHD, 21531, &c, &error)) << error;
}

TEST(ZedCalibration, MissingResolutionListsWhatTheFileHas) {
  std::string text = rtfuse::test::realistic_zed_file();
  for (const char* s : {"LEFT_CAM_2K", "RIGHT_CAM_2K", "LEFT_CAM_FHD", "RIGHT_CAM_FHD"}) text = without_section(text, s);
  EXPECT_EQ(parse_error(text, ZedResolution::kFHD),
            "zed calibration: SN21531.conf: no calibration for resolution FHD ([LEFT_CAM_FHD], [RIGHT_CAM_FHD]); the "
            "file has: HD, VGA. Run the camera at one of those or download the file again");
  EXPECT_NE(parse_error("[MISC]\nSensor_ID=0\n", ZedResolution::kVGA).find("the file has: none"), std::string::npos);
  EXPECT_NE(parse_error("", ZedResolution::kVGA).find("the file has: none"), std::string::npos);
}

TEST(ZedCalibration, OversizedInputIsRejectedNotTruncated) {
  const std::string full = rtfuse::test::realistic_zed_file();
  const std::string long_line = replaced(full, "[MISC]\n", "[MISC]\nnote=" + std::string(300, 'x') + "\n");
  EXPECT_EQ(parse_error(long_line), "zed calibration: SN21531.conf:" + std::to_string(line_of(long_line, "note=")) +
                                        ": line is 305 characters long (at most 256): this is not a ZED calibration "
                                        "file");
  const std::string huge(rtfuse::drivers::kMaxZedCalibrationBytes + 1, '\n');
  EXPECT_EQ(parse_error(huge), "zed calibration: SN21531.conf: 262145 bytes (at most 262144): this is not a ZED "
                               "calibration file");
  std::string nul = full;
  nul.insert(nul.find("[MISC]"), std::string("a=1\0", 4));
  EXPECT_NE(parse_error(nul).find("NUL byte"), std::string::npos);
}

TEST(ZedCalibration, LoadsFromFileAndReportsMissingFile) {
  char dir_template[] = "/tmp/rtfuse_zed_XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  const std::string path = std::string(dir_template) + "/SN21531.conf";
  {
    std::ofstream out(path, std::ios::binary);
    out << rtfuse::test::realistic_zed_file();
  }
  ZedCalibration c;
  std::string error;
  EXPECT_TRUE(load_zed_calibration(path, ZedResolution::kVGA, 21531, &c, &error)) << error;
  EXPECT_EQ(c.stereo.width, 672);
  EXPECT_EQ(c.stereo.left.fx, 349.67);
  EXPECT_FALSE(load_zed_calibration(path, ZedResolution::kVGA, 4242, &c, &error));
  EXPECT_NE(error.find(path + ": calibration of camera SN21531, but the configured camera is SN4242"),
            std::string::npos)
      << error;
  std::remove(path.c_str());
  ::rmdir(dir_template);
  EXPECT_FALSE(load_zed_calibration(path, ZedResolution::kVGA, 0, &c, &error));
  EXPECT_EQ(error, "zed calibration: " + path +
                       ": cannot open: No such file or directory (download it from "
                       "https://calib.stereolabs.com/?SN=<serial>)");
}

// Stand-in for the fuzz harness: thousands of deterministic mutations of a
// real file (byte flips, truncations, inserted junk). Each must either parse
// or fail with a message; none may crash or hang.
TEST(ZedCalibration, SurvivesMutatedInput) {
  const std::string full = rtfuse::test::realistic_zed_file();
  std::uint32_t state = 2463534242u;
  auto next = [&state] {
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    return state;
  };
  int parsed = 0;
  for (int i = 0; i < 5000; ++i) {
    std::string text = full;
    const int edits = 1 + static_cast<int>(next() % 4);
    for (int k = 0; k < edits && !text.empty(); ++k) {
      const std::size_t at = next() % text.size();
      switch (next() % 4) {
        case 0: text[at] = static_cast<char>(next() & 0xFF); break;
        case 1: text.erase(at, 1 + next() % 8); break;
        case 2: text.insert(at, std::string(1 + next() % 4, static_cast<char>(next() & 0xFF))); break;
        case 3: text.resize(at); break;
      }
    }
    ZedCalibration c;
    std::string error;
    const bool ok = parse_zed_calibration(text, kName, ZedResolution::kHD, 21531, &c, &error);
    if (ok) {
      ++parsed;
      EXPECT_GT(c.stereo.left.fx, 0.0);
    } else {
      EXPECT_EQ(error.rfind("zed calibration: SN21531.conf", 0), 0u) << error;
    }
  }
  EXPECT_GT(parsed, 0);  // edits in skipped sections or values still parse
}

}  // namespace zed_calibration_test
