#include "apps/kitti_sequence.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace rtfuse::apps {
namespace {

namespace fs = std::filesystem;

bool read_file(const std::string& path, std::string* text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  *text = ss.str();
  return static_cast<bool>(in) || in.eof();
}

// Up to `want` numbers from s; false on a token that is not a finite number.
bool numbers(const std::string& s, std::vector<double>* out, std::string* bad) {
  std::istringstream in(s);
  std::string tok;
  while (in >> tok) {
    char* end = nullptr;
    const double v = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0' || !std::isfinite(v)) {
      *bad = tok;
      return false;
    }
    out->push_back(v);
  }
  return true;
}

std::string where(const std::string& name, int line) { return name + ":" + std::to_string(line) + ": "; }

}  // namespace

bool parse_kitti_calibration(const std::string& text, const std::string& name, vision::StereoCameraModel* camera,
                             std::string* error) {
  std::istringstream in(text);
  std::string line;
  int lineno = 0, unlabelled = 0;
  std::vector<double> p[2];
  int p_line[2] = {0, 0};
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    std::string body = line;
    int which = -1;
    const std::size_t colon = line.find(':');
    if (colon != std::string::npos) {
      std::string label = line.substr(0, colon);
      label.erase(0, label.find_first_not_of(" \t"));
      label.erase(label.find_last_not_of(" \t") + 1);
      body = line.substr(colon + 1);
      if (label == "P0") which = 0;
      else if (label == "P1") which = 1;
      else continue;  // P2, P3, Tr: not needed
    } else {
      which = unlabelled < 2 ? unlabelled : -1;
      ++unlabelled;
      if (which < 0) continue;
    }
    std::vector<double> v;
    std::string bad;
    if (!numbers(body, &v, &bad)) {
      *error = where(name, lineno) + "'" + bad + "' is not a number (P" + std::to_string(which) +
               " is 12 numbers, the 3x4 projection matrix row by row)";
      return false;
    }
    if (v.size() != 12) {
      *error = where(name, lineno) + "P" + std::to_string(which) + " has " + std::to_string(v.size()) +
               " numbers, not 12 (the 3x4 projection matrix row by row)";
      return false;
    }
    p[which] = v;
    p_line[which] = lineno;
  }
  for (int k = 0; k < 2; ++k) {
    if (p[k].empty()) {
      *error = name + ": no P" + std::to_string(k) + " (" + (k == 0 ? "left" : "right") +
               " camera's projection matrix; a KITTI calib.txt starts with the P0 and P1 lines)";
      return false;
    }
  }
  const double f = p[0][0], fy = p[0][5], cu = p[0][2], cv = p[0][6];
  if (!(f > 0.0) || std::abs(fy - f) > 1e-6 * f || std::abs(p[1][0] - f) > 1e-6 * f ||
      std::abs(p[1][2] - cu) > 1e-6 * f || std::abs(p[1][6] - cv) > 1e-6 * f || p[0][3] != 0.0) {
    *error = where(name, p_line[1]) + "P0 and P1 do not describe a rectified pair (same fx = fy, cx, cy; P0 "
             "without translation): rectify the images first";
    return false;
  }
  const double baseline = -p[1][3] / f;
  if (!(baseline > 0.0)) {
    *error = where(name, p_line[1]) + "P1[0][3] = " + std::to_string(p[1][3]) +
             " gives a baseline of " + std::to_string(baseline) + " m: the right camera must be to the right";
    return false;
  }
  *camera = vision::StereoCameraModel{f, cu, cv, baseline};
  return true;
}

bool parse_kitti_poses(const std::string& text, const std::string& name, std::vector<Eigen::Matrix4d>* poses,
                       std::string* error) {
  std::istringstream in(text);
  std::string line;
  int lineno = 0;
  std::vector<Eigen::Matrix4d> out;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::vector<double> v;
    std::string bad;
    if (!numbers(line, &v, &bad)) {
      *error = where(name, lineno) + "'" + bad + "' is not a number";
      return false;
    }
    if (v.size() != 12) {
      *error = where(name, lineno) + std::to_string(v.size()) + " numbers, a pose is 12 (3x4, row by row)";
      return false;
    }
    Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) t(r, c) = v[static_cast<std::size_t>(4 * r + c)];
    out.push_back(t);
  }
  *poses = std::move(out);
  return true;
}

std::string kitti_pose_line(const Eigen::Matrix4d& t) {
  std::string s;
  char buf[32];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) {
      std::snprintf(buf, sizeof buf, "%s%.9e", (r || c) ? " " : "", t(r, c));
      s += buf;
    }
  return s;
}

bool open_kitti_sequence(const std::string& dir, KittiSequence* out, std::string* error) {
  KittiSequence seq;
  seq.dir = dir;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    *error = dir + ": not a folder (give a KITTI-style sequence: image_l/, image_r/, calib.txt)";
    return false;
  }
  std::string left_dir, right_dir;
  for (const auto& [l, r] : {std::pair{"image_l", "image_r"}, std::pair{"image_0", "image_1"}}) {
    if (fs::is_directory(fs::path(dir) / l, ec)) {
      left_dir = (fs::path(dir) / l).string();
      right_dir = (fs::path(dir) / r).string();
      break;
    }
  }
  if (left_dir.empty()) {
    *error = dir + ": no image_l/ (or image_0/) folder of left images";
    return false;
  }
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(left_dir, ec)) {
    if (e.is_regular_file() && e.path().extension() == ".png") names.push_back(e.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  if (names.empty()) {
    *error = left_dir + ": no .png images";
    return false;
  }
  for (const std::string& n : names) {
    seq.left.push_back((fs::path(left_dir) / n).string());
    const fs::path r = fs::path(right_dir) / n;
    seq.right.push_back(fs::exists(r, ec) ? r.string() : std::string());
  }
  const std::string calib = (fs::path(dir) / "calib.txt").string();
  std::string text;
  if (!read_file(calib, &text)) {
    *error = calib + ": cannot read (the P0 and P1 projection matrices of the rectified pair)";
    return false;
  }
  if (!parse_kitti_calibration(text, calib, &seq.camera, error)) return false;
  const std::string poses = (fs::path(dir) / "poses.txt").string();
  if (fs::exists(poses, ec)) {
    if (!read_file(poses, &text)) {
      *error = poses + ": cannot read";
      return false;
    }
    if (!parse_kitti_poses(text, poses, &seq.ground_truth, error)) return false;
    if (seq.ground_truth.size() != seq.left.size()) {
      *error = poses + ": " + std::to_string(seq.ground_truth.size()) + " poses for " +
               std::to_string(seq.left.size()) + " frames";
      return false;
    }
  }
  *out = std::move(seq);
  return true;
}

}  // namespace rtfuse::apps
