// rtfuse-vo: the stereo visual odometry alone on a folder of rectified pairs
// in the KITTI odometry layout (image_l/ + image_r/ or image_0/ + image_1/,
// calib.txt with P0 and P1, optional poses.txt as ground truth). Writes the
// left camera's poses in KITTI format (12 numbers a line, frame 0 the
// identity, one line per frame), draws the trajectory against the ground
// truth, and prints as its last line one JSON object with the timing and,
// with ground truth, the errors. A frame the VO cannot solve (missing or
// unreadable image, too few matches, no consensus) still gets a pose: the
// last motion held; it is counted.
//
// Exit: 0 done, 1 a file could not be read or written, 2 usage or a
// malformed sequence.
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/LU>

#include "apps/command_line.hpp"
#include "apps/grey_png.hpp"
#include "apps/kitti_sequence.hpp"
#include "apps/trajectory_metrics.hpp"
#include "apps/trajectory_plot.hpp"
#include "vision/stereo_odometry.hpp"

namespace {

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5));
  return v[i];
}

// The folder's own name ("kitti06_0000_0050" of ".../kitti06_0000_0050/"):
// the plot's title.
std::string sequence_name(const std::string& dir) {
  const std::filesystem::path p(dir);
  const std::string name = p.filename().string();
  return name.empty() ? p.parent_path().filename().string() : name;
}

void print_errors(const rtfuse::apps::TrajectoryErrors& e) {
  std::printf(", \"path_length_m\": %.3f, \"final_error_m\": %.4f, \"final_error_pct\": %.3f, \"ate_rmse_m\": %.4f, "
              "\"final_rotation_error_deg\": %.4f, \"rpe_translation_m\": %.4f, \"rpe_rotation_deg\": %.4f",
              e.path_length_m, e.final_error_m, e.final_error_pct, e.ate_rmse_m, e.final_rotation_error_deg,
              e.rpe_translation_m, e.rpe_rotation_deg);
}

}  // namespace

int main(int argc, char** argv) {
  rtfuse::apps::CommandLine cli{"rtfuse-vo: stereo visual odometry on a KITTI-layout folder of rectified pairs"};
  std::string dir, out_path, plot_path;
  int max_frames = 0;
  int eval_from = 0;
  cli.option("--kitti", &dir, "sequence folder: image_l/ image_r/ (or image_0/ image_1/), calib.txt, [poses.txt]")
      .required();
  cli.option("-o,--out", &out_path, "poses to write, KITTI format");
  cli.option("--plot", &plot_path,
                 "PNG: top view against the ground truth in metres, legend, key figures, the error over frames");
  cli.option("-n,--frames", &max_frames, "at most this many frames (0: all)");
  cli.option("--eval-from", &eval_from,
                 "also judge the frames from this one on against the ground truth, both re-anchored there "
                 "(\"from_frame\" in the JSON): a stretch whose ground truth is measured")
      .non_negative();
  if (const auto exit = cli.parse(argc, argv)) return *exit;
  rtfuse::apps::KittiSequence seq;
  std::string error;
  if (!rtfuse::apps::open_kitti_sequence(dir, &seq, &error)) {
    std::fprintf(stderr, "rtfuse-vo: %s\n", error.c_str());
    return 2;
  }
  std::size_t frames = seq.left.size();
  if (max_frames > 0) frames = std::min(frames, static_cast<std::size_t>(max_frames));
  if (eval_from > 0 && seq.ground_truth.empty()) {
    std::fprintf(stderr, "rtfuse-vo: --eval-from needs the ground truth %s/poses.txt\n", dir.c_str());
    return 2;
  }
  if (eval_from > 0 && static_cast<std::size_t>(eval_from) + 1 >= std::min(frames, seq.ground_truth.size())) {
    std::fprintf(stderr, "rtfuse-vo: --eval-from %d: a stretch needs two frames, and %zu frames have ground truth\n",
                 eval_from, std::min(frames, seq.ground_truth.size()));
    return 2;
  }
  rtfuse::apps::GreyPng first;
  if (!rtfuse::apps::read_grey_png(seq.left[0], &first, &error)) {
    std::fprintf(stderr, "rtfuse-vo: %s\n", error.c_str());
    return 1;
  }
  const int width = first.width, height = first.height;
  rtfuse::vision::StereoOdometry vo(width, height, seq.camera, rtfuse::vision::StereoOdometryParams{});

  std::vector<Eigen::Matrix4d> poses;
  Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
  Eigen::Matrix4d last_step = Eigen::Matrix4d::Identity();  // camera k -> camera k-1
  std::vector<double> ms;
  std::int64_t failed = 0, unreadable = 0, inliers = 0, solved = 0, features = 0, matches = 0, processed = 0;
  rtfuse::apps::GreyPng left, right;
  for (std::size_t k = 0; k < frames; ++k) {
    bool have = true;
    if (seq.right[k].empty()) {
      std::fprintf(stderr, "rtfuse-vo: frame %zu: no right image for %s\n", k, seq.left[k].c_str());
      have = false;
    } else if (!rtfuse::apps::read_grey_png(seq.left[k], &left, &error) ||
               !rtfuse::apps::read_grey_png(seq.right[k], &right, &error)) {
      std::fprintf(stderr, "rtfuse-vo: frame %zu: %s\n", k, error.c_str());
      have = false;
    } else if (left.width != width || left.height != height || right.width != width || right.height != height) {
      std::fprintf(stderr, "rtfuse-vo: frame %zu: %d x %d and %d x %d, the sequence is %d x %d\n", k, left.width,
                   left.height, right.width, right.height, width, height);
      have = false;
    }
    if (!have) {
      ++unreadable;
      vo.reset();  // the next pair matches against nothing older than itself
    } else {
      const rtfuse::vision::GreyView lv{left.pixels.data(), width, height, width};
      const rtfuse::vision::GreyView rv{right.pixels.data(), width, height, width};
      const auto t0 = std::chrono::steady_clock::now();
      const rtfuse::vision::StereoOdometryResult r = vo.process(lv, rv, k);
      const auto t1 = std::chrono::steady_clock::now();
      ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      ++processed;
      features += r.features_left;
      matches += r.matches;
      if (r.status == rtfuse::vision::VoStatus::kMotion) {
        last_step = rtfuse::vision::egomotion_transform(r.motion.params).inverse();
        inliers += r.motion.inliers;
        ++solved;
      } else if (r.status != rtfuse::vision::VoStatus::kFirstFrame) {
        ++failed;
        std::fprintf(stderr, "rtfuse-vo: frame %zu: %s (%d matches, %d after the spread): the last motion held\n", k,
                     rtfuse::vision::to_string(r.status), r.matches, r.bucketed);
      }
      if (r.status == rtfuse::vision::VoStatus::kFirstFrame && k > 0) {
        // After a gap: the last motion held for the frame that restarted.
      }
    }
    if (k > 0) pose = pose * last_step;
    poses.push_back(pose);
  }
  if (!out_path.empty()) {
    std::FILE* f = std::fopen(out_path.c_str(), "w");
    if (f == nullptr) {
      std::perror(("rtfuse-vo: " + out_path).c_str());
      return 1;
    }
    for (const Eigen::Matrix4d& p : poses) std::fprintf(f, "%s\n", rtfuse::apps::kitti_pose_line(p).c_str());
    if (std::fclose(f) != 0) {
      std::perror(("rtfuse-vo: " + out_path).c_str());
      return 1;
    }
  }
  // The figures the JSON line and the plot both show, computed once.
  rtfuse::apps::TrajectoryPlotFigures figures;
  figures.title = sequence_name(dir);
  figures.frames = static_cast<int>(frames);
  figures.solved = solved;
  figures.failed = failed;
  figures.unreadable = unreadable;
  figures.ms_per_frame_median = percentile(ms, 0.5);
  figures.ms_per_frame_p99 = percentile(ms, 0.99);
  if (!seq.ground_truth.empty()) {
    figures.errors = rtfuse::apps::compare_trajectories(poses, seq.ground_truth);
    if (eval_from > 0) {
      const auto first = static_cast<std::size_t>(eval_from);
      figures.eval_from = eval_from;
      figures.stretch_errors = rtfuse::apps::compare_trajectories(rtfuse::apps::reanchored(poses, first),
                                                                  rtfuse::apps::reanchored(seq.ground_truth, first));
    }
  }
  if (!plot_path.empty() &&
      !rtfuse::apps::write_trajectory_plot(plot_path, poses, seq.ground_truth, figures, &error)) {
    std::fprintf(stderr, "rtfuse-vo: %s\n", error.c_str());
    return 1;
  }
  std::printf("{\"frames\": %zu, \"solved\": %" PRId64 ", \"failed\": %" PRId64 ", \"unreadable\": %" PRId64
              ", \"features_mean\": %.1f, \"matches_mean\": %.1f, \"inliers_mean\": %.1f, \"ms_per_frame_median\": %.3f, "
              "\"ms_per_frame_p99\": %.3f",
              frames, solved, failed, unreadable, processed > 0 ? static_cast<double>(features) / processed : 0.0,
              processed > 0 ? static_cast<double>(matches) / processed : 0.0,
              solved > 0 ? static_cast<double>(inliers) / solved : 0.0,
              figures.ms_per_frame_median, figures.ms_per_frame_p99);
  if (figures.errors) {
    print_errors(*figures.errors);
    if (figures.stretch_errors) {
      std::printf(", \"from_frame\": {\"first\": %d", eval_from);
      print_errors(*figures.stretch_errors);
      std::printf("}");
    }
  }
  std::printf("}\n");
  return 0;
}
