#pragma once
// What the vivid guest tests share (v4l2_vivid_test.cpp: the V4L2 backend;
// stereo_camera_vivid_test.cpp: the stereo camera driver on top of it): the
// node found by its name in /sys, and a raw handle for what the stream does
// not do itself (vivid's input, DV timings and Disconnect button). Both
// sources build into one guest program, so one VM boot runs every case.
#include <dirent.h>
#include <fcntl.h>
#include <linux/v4l2-dv-timings.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

namespace rtfuse::kernel_test {

inline bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

inline std::string errno_text(int err) {
  return std::string(std::strerror(err)) + " (errno " + std::to_string(err) + ")";
}

// /dev/videoN of the node whose /sys/class/video4linux/*/name is `name`
// (vivid names them "vivid-000-vid-cap"); empty if there is none.
inline std::string find_node(const std::string& name) {
  DIR* dir = opendir("/sys/class/video4linux");
  if (dir == nullptr) return {};
  std::string found;
  while (dirent* e = readdir(dir)) {
    if (e->d_name[0] == '.') continue;
    std::ifstream in(std::string("/sys/class/video4linux/") + e->d_name + "/name");
    std::string line;
    if (std::getline(in, line) && line == name) {
      found = std::string("/dev/") + e->d_name;
      break;
    }
  }
  closedir(dir);
  return found;
}

// A raw file handle on a node, for what the stream does not do itself
// (choosing the input, pressing a control).
class RawNode {
 public:
  explicit RawNode(const std::string& path) : path_(path), fd_(::open(path.c_str(), O_RDWR | O_CLOEXEC)) {
    if (fd_ < 0) error_ = "open " + path + ": " + errno_text(errno);
  }
  ~RawNode() { close(); }
  RawNode(const RawNode&) = delete;
  RawNode& operator=(const RawNode&) = delete;
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  bool ok() const { return fd_ >= 0; }
  const std::string& error() const { return error_; }

  // Selects the first input whose name starts with `prefix` ("HDMI", "Webcam").
  bool select_input(const std::string& prefix) {
    for (std::uint32_t i = 0; i < 16; ++i) {
      v4l2_input in{};
      in.index = i;
      if (::ioctl(fd_, VIDIOC_ENUMINPUT, &in) < 0) break;
      if (std::string(reinterpret_cast<const char*>(in.name)).rfind(prefix, 0) != 0) continue;
      int index = static_cast<int>(i);
      if (::ioctl(fd_, VIDIOC_S_INPUT, &index) < 0) return fail("VIDIOC_S_INPUT " + prefix);
      return true;
    }
    error_ = path_ + " has no input named " + prefix + "*";
    return false;
  }

  // 1280x720p30 (CEA-861 VIC 34) on the HDMI input: a 30 fps source.
  bool set_hdmi_720p30() {
    v4l2_dv_timings t = V4L2_DV_BT_CEA_1280X720P30;
    if (::ioctl(fd_, VIDIOC_S_DV_TIMINGS, &t) < 0) return fail("VIDIOC_S_DV_TIMINGS 1280x720p30");
    return true;
  }

  // The id of the control named `name` (VIDIOC_QUERY_EXT_CTRL walk); 0 if none.
  std::uint32_t find_control(const std::string& name) {
    v4l2_query_ext_ctrl q{};
    q.id = V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND;
    while (::ioctl(fd_, VIDIOC_QUERY_EXT_CTRL, &q) == 0) {
      if (name == q.name) return q.id;
      q.id |= V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND;
    }
    error_ = path_ + " has no control named \"" + name + "\"";
    return 0;
  }

  bool press(std::uint32_t id) {
    v4l2_control c{};
    c.id = id;
    c.value = 1;
    if (::ioctl(fd_, VIDIOC_S_CTRL, &c) < 0) return fail("VIDIOC_S_CTRL (button)");
    return true;
  }

 private:
  bool fail(const std::string& what) {
    error_ = path_ + ": " + what + ": " + errno_text(errno);
    return false;
  }
  std::string path_;
  int fd_;
  std::string error_;
};

}  // namespace rtfuse::kernel_test
