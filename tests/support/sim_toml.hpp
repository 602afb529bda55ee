#pragma once
// config/sim.toml as text, for tests. Most tests are about the encoders, the
// IMU and the filter, not the camera: they take the robot without its
// [camera] table (nor the visual odometry on it: its [vo] table and its
// [[sensor]]), because the simulator renders every frame (about 7 ms
// natively, twenty times that under qemu) and a recording keeps 1 MB of
// each. The camera's own tests keep it.
#include <fstream>
#include <sstream>
#include <string>

namespace rtfuse::test {

inline const std::string kSimTomlPath = RTFUSE_SOURCE_DIR "/config/sim.toml";

// The camera's tests keep it; the mapper ([mapping], tens of milliseconds a
// keyframe) only where a test asks for it.
inline std::string sim_toml_text(bool with_camera, bool with_mapping = false) {
  std::ifstream in(kSimTomlPath);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  // From a table's header to the next table header.
  const auto erase_table = [&text](const char* table) {
    const std::size_t at = text.find(table);
    if (at == std::string::npos) return;
    const std::size_t next = text.find("\n[", at + 1);
    text.erase(at + 1, next == std::string::npos ? std::string::npos : next - at);
  };
  if (!with_mapping || !with_camera) erase_table("\n[mapping]\n");
  if (with_camera) return text;
  for (const char* table : {"\n[camera]\n", "\n[vo]\n"}) erase_table(table);
  // The [[sensor]] the odometry feeds: from its header to the next header.
  const std::size_t source = text.find("source = \"stereo_vo\"");
  if (source != std::string::npos) {
    const std::size_t at = text.rfind("\n[[sensor]]\n", source);
    const std::size_t next = text.find("\n[", source);
    text.erase(at + 1, next == std::string::npos ? std::string::npos : next - at);
  }
  return text;
}

}  // namespace rtfuse::test
