#pragma once
// [navigation] from the TOML into cfg.hardware, every problem with its file,
// line and key. Configuration time only.
#include "runtime/config/config.hpp"

namespace rtfuse::config {

class Section;
void read_navigation_config(const Section& root, RuntimeConfig& cfg);

}  // namespace rtfuse::config
