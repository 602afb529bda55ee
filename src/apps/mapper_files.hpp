#pragma once
// The mapper's files at exit ([mapping] output, --map-out of rtfused and
// rtfuse-sim): the map as it ended, the grid, and the keyframes' path over
// it (map_outputs.hpp). A tool's writer: allocates and does file I/O.
#include <string>

#include "runtime/devices/mapper/mapper_device.hpp"

namespace rtfuse::apps {

// False with the reason.
bool write_mapper_files(MapperDevice& mapper, const std::string& prefix, const std::string& title,
                        std::string* error);

}  // namespace rtfuse::apps
