// rtfuse-stereo: the dense disparity of the left view of one rectified
// stereo pair (vision/semi_global_matcher.hpp), written in KITTI's
// convention (16-bit PNG, disparity x 256, 0 = no estimate) at the input's
// size, and as its last stdout line one JSON object with the size, the
// range, the share of pixels with an estimate and the median time of
// --repeat runs on one thread. Colour PNGs are turned into luma as the
// camera path sees it (apps/grey_png.hpp, read_luma_png).
//
// Exit: 0 done, 1 a file could not be read or written, 2 usage or a pair
// or range the matcher cannot take.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "apps/command_line.hpp"
#include "apps/disparity_png.hpp"
#include "apps/grey_png.hpp"
#include "apps/json_text.hpp"
#include "vision/semi_global_matcher.hpp"

namespace {

using rtfuse::apps::json_string;

}  // namespace

int main(int argc, char** argv) {
  rtfuse::apps::CommandLine cli{"rtfuse-stereo: dense disparity of the left view of a rectified stereo pair (KITTI 16-bit PNG)"};
  std::string left_path, right_path, out_path;
  int disparities = 0, downscale = 1, repeat = 1;
  cli.option("left", &left_path, "left view, PNG (grey or colour), rectified").required();
  cli.option("right", &right_path, "right view, PNG, same size, rectified").required();
  cli.option("-d,--disparities", &disparities,
                 "disparities searched, 0..N-1, in input pixels: a multiple of 16 (of 32 with --downscale 2)")
      .required();
  cli.option("--downscale", &downscale, "1: match at full resolution, 2: at half (the live default)")
      .one_of({"1", "2"});
  cli.option("--repeat", &repeat, "run the matcher this many times; the JSON has the median time")
      .range(1, 100000);
  cli.option("-o,--out", &out_path, "disparity PNG to write: 16-bit, disparity x 256, 0 = no estimate");
  if (const auto exit = cli.parse(argc, argv)) return *exit;

  rtfuse::apps::GreyPng left, right;
  std::string error;
  if (!rtfuse::apps::read_luma_png(left_path, &left, &error) ||
      !rtfuse::apps::read_luma_png(right_path, &right, &error)) {
    std::fprintf(stderr, "rtfuse-stereo: %s (give a readable PNG image)\n", error.c_str());
    return 1;
  }
  if (left.width != right.width || left.height != right.height) {
    std::fprintf(stderr,
                 "rtfuse-stereo: %s is %d x %d but %s is %d x %d: the two views of a rectified pair have the same "
                 "size (rectify or crop them alike)\n",
                 left_path.c_str(), left.width, left.height, right_path.c_str(), right.width, right.height);
    return 2;
  }
  rtfuse::vision::DisparityParams params;
  params.disparities = disparities;
  params.downscale = downscale;
  rtfuse::vision::SemiGlobalMatcher matcher(left.width, left.height, params);
  if (!matcher.valid()) {
    const int widest = ((left.width / downscale - 1) / 16) * 16 * downscale;
    std::fprintf(stderr, "rtfuse-stereo: --disparities %d for %s (%d x %d, downscale %d): %s", disparities,
                 left_path.c_str(), left.width, left.height, downscale, matcher.error());
    if (widest >= 16 * downscale) {
      std::fprintf(stderr, " (this pair takes at most %d)\n", widest);
    } else {
      std::fprintf(stderr, " (this pair is too narrow for any range)\n");
    }
    return 2;
  }
  const int w = matcher.output_width(left.width), h = matcher.output_height(left.height);
  rtfuse::vision::Plane<std::uint16_t> disparity(w, h);
  const rtfuse::vision::GreyView lv{left.pixels.data(), left.width, left.height, left.width};
  const rtfuse::vision::GreyView rv{right.pixels.data(), right.width, right.height, right.width};
  std::vector<double> ms;
  for (int k = 0; k < repeat; ++k) {
    const auto start = std::chrono::steady_clock::now();
    const rtfuse::vision::DisparityStatus s = matcher.compute(lv, rv, rtfuse::vision::view_of(disparity));
    const std::chrono::duration<double, std::milli> took = std::chrono::steady_clock::now() - start;
    if (s != rtfuse::vision::DisparityStatus::kOk) {
      std::fprintf(stderr, "rtfuse-stereo: %s and %s: %s\n", left_path.c_str(), right_path.c_str(),
                   rtfuse::vision::to_string(s));
      return 2;
    }
    ms.push_back(took.count());
  }
  std::sort(ms.begin(), ms.end());
  if (!out_path.empty() && !rtfuse::apps::write_kitti_disparity_png(out_path, rtfuse::vision::view_of(disparity),
                                                                     downscale, left.width, left.height, &error)) {
    std::fprintf(stderr, "rtfuse-stereo: %s (choose a writable path for --out)\n", error.c_str());
    return 1;
  }
  std::printf("{\"left\": %s, \"right\": %s, \"width\": %d, \"height\": %d, \"matched_width\": %d, "
              "\"matched_height\": %d, \"disparities\": %d, \"downscale\": %d, \"valid_fraction\": %.4f, "
              "\"repeat\": %d, \"ms_median\": %.3f, \"ms_min\": %.3f, \"out\": %s}\n",
              json_string(left_path).c_str(), json_string(right_path).c_str(), left.width, left.height, w, h,
              disparities, downscale, static_cast<double>(matcher.valid_pixels()) / (static_cast<double>(w) * h),
              repeat, ms[ms.size() / 2], ms.front(), out_path.empty() ? "null" : json_string(out_path).c_str());
  return 0;
}
