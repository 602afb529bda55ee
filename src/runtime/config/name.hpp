#pragma once
// The configuration's fixed-capacity names (channels, frames, device paths):
// one type, so any of them can be copied into another without a check.
#include "core/fixed_string.hpp"

namespace rtfuse {

using Name = FixedString<63>;

}  // namespace rtfuse
