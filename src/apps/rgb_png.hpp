#pragma once
// Writing an 8-bit RGB PNG row by row (libpng), for every picture the tools
// draw: the stereo snapshot, the figures. Rows come from a callback, so a
// writer that makes them on the fly (the snapshot's pair) needs no copy of
// the whole picture. A tool's writer (allocates, does file I/O); never on
// the real-time path.
#include <cstdint>
#include <string>

namespace rtfuse::apps {

// Fills row y (0 = top) of the picture: 3 * width bytes, R G B per pixel.
// noexcept because it runs inside libpng's setjmp context, which an
// exception must not cross.
using RgbRowFill = void (*)(const void* context, int y, std::uint8_t* row) noexcept;

// Writes `path` as a width x height 8-bit RGB PNG whose rows `fill` makes.
// False and *error naming the path and the cause (the errno text for I/O,
// libpng's message otherwise) on failure; a partial regular file is removed
// (a device such as /dev/full is never unlinked). Sizes are checked before
// the file is opened, so a bad size never truncates an existing file.
bool write_rgb_png(const std::string& path, int width, int height, RgbRowFill fill, const void* context,
                   std::string* error);

}  // namespace rtfuse::apps
