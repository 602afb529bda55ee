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

inline std::string sim_toml_text(bool with_camera) {
  std::ifstream in(kSimTomlPath);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  if (with_camera) return text;
  // From a table's header to the next table header.
  for (const char* table : {"\n[camera]\n", "\n[vo]\n"}) {
    const std::size_t at = text.find(table);
    if (at == std::string::npos) continue;
    const std::size_t next = text.find("\n[", at + 1);
    text.erase(at + 1, next == std::string::npos ? std::string::npos : next - at);
  }
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
