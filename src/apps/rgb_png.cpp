#include "apps/rgb_png.hpp"

#include <png.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csetjmp>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <vector>

namespace rtfuse::apps {
namespace {

// What the libpng callbacks report back: they cannot throw or return an
// error, only longjmp out of libpng.
struct PngContext {
  std::FILE* file = nullptr;
  int write_errno = 0;     // errno of a failed write (ENOSPC, EIO, ...)
  char message[256] = {};  // libpng's own error text
};

void on_error(png_structp png, png_const_charp message) {
  auto* ctx = static_cast<PngContext*>(png_get_error_ptr(png));
  std::snprintf(ctx->message, sizeof ctx->message, "%s", message != nullptr ? message : "unknown error");
  png_longjmp(png, 1);
}

// Warnings (e.g. an unusual but valid setting) do not fail the write.
void on_warning(png_structp, png_const_charp) {}

// Our own I/O callbacks rather than png_init_io: libpng's say "Write Error"
// and drop errno, and the caller must be told "No space left on device".
void on_write(png_structp png, png_bytep data, std::size_t size) {
  auto* ctx = static_cast<PngContext*>(png_get_io_ptr(png));
  errno = 0;
  if (std::fwrite(data, 1, size, ctx->file) != size) {
    ctx->write_errno = errno != 0 ? errno : EIO;
    png_error(png, "write failed");
  }
}

void on_flush(png_structp png) {
  auto* ctx = static_cast<PngContext*>(png_get_io_ptr(png));
  if (std::fflush(ctx->file) != 0) {
    ctx->write_errno = errno != 0 ? errno : EIO;
    png_error(png, "flush failed");
  }
}

// png_error longjmps back to the setjmp here, skipping every frame in
// between: this function and libpng's frames hold nothing with a destructor
// (the row buffer belongs to the caller, fill is noexcept and has returned
// before libpng runs), so nothing is leaked or skipped.
bool write_rows(png_structp png, png_infop info, int width, int height, RgbRowFill fill, const void* context,
                std::uint8_t* row) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < height; ++y) {
    fill(context, y, row);
    png_write_row(png, row);
  }
  png_write_end(png, nullptr);
  return true;
}

bool fail(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

}  // namespace

bool write_rgb_png(const std::string& path, int width, int height, RgbRowFill fill, const void* context,
                   std::string* error) {
  if (fill == nullptr) return fail(error, "PNG " + path + ": nothing to draw the rows with");
  if (width <= 0 || height <= 0 || width > PNG_USER_WIDTH_MAX || height > PNG_USER_HEIGHT_MAX)
    return fail(error, "PNG " + path + ": size " + std::to_string(width) + "x" + std::to_string(height) +
                           " is not within 1.." + std::to_string(PNG_USER_WIDTH_MAX) + " a side");

  PngContext ctx;
  ctx.file = std::fopen(path.c_str(), "wb");
  if (ctx.file == nullptr) return fail(error, "cannot open " + path + ": " + std::strerror(errno));

  std::vector<std::uint8_t> row(static_cast<std::size_t>(width) * 3u);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &ctx, on_error, on_warning);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  bool ok = false;
  if (png != nullptr && info != nullptr) {
    png_set_write_fn(png, &ctx, on_write, on_flush);
    ok = write_rows(png, info, width, height, fill, context, row.data());
  } else {
    std::snprintf(ctx.message, sizeof ctx.message, "libpng could not start (out of memory)");
  }
  png_destroy_write_struct(&png, &info);  // either may be null

  // fclose writes what stdio still buffers: its failure is a write failure.
  struct stat st {};
  const bool regular = fstat(fileno(ctx.file), &st) == 0 && S_ISREG(st.st_mode);
  if (std::fclose(ctx.file) != 0 && ok) {
    ok = false;
    ctx.write_errno = errno != 0 ? errno : EIO;
  }
  if (ok) return true;
  // A half-written PNG must not pass for a picture; never unlink a device.
  if (regular) ::unlink(path.c_str());
  if (ctx.write_errno != 0) return fail(error, "cannot write " + path + ": " + std::strerror(ctx.write_errno));
  return fail(error, "cannot write " + path + ": libpng: " + ctx.message);
}

}  // namespace rtfuse::apps
