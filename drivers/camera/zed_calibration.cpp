#include "drivers/camera/zed_calibration.hpp"

#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <system_error>

namespace rtfuse::drivers {

namespace {

constexpr int kResolutionCount = 4;
constexpr std::array<ZedResolution, kResolutionCount> kResolutions{ZedResolution::k2K, ZedResolution::kFHD,
                                                                  ZedResolution::kHD, ZedResolution::kVGA};

// The per-eye keys, in CameraIntrinsics order.
constexpr int kEyeKeyCount = 9;
constexpr std::array<const char*, kEyeKeyCount> kEyeKeys{"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"};

// [STEREO] keys: resolution-free ones, then one set per resolution.
enum StereoKey { kBaseline, kTy, kTz, kStereoKeyCount };
enum PerResolutionKey { kTyRes, kTzRes, kCvRes, kRxRes, kRzRes, kPerResolutionKeyCount };
constexpr std::array<const char*, kStereoKeyCount> kStereoKeys{"Baseline", "TY", "TZ"};
constexpr std::array<const char*, kPerResolutionKeyCount> kPerResolutionKeys{"TY", "TZ", "CV", "RX", "RZ"};

struct Field {
  double value = 0.0;
  int line = 0;  // 0: not in the file
};

struct Section {
  int line = 0;  // of its first header; 0: not in the file
};

struct EyeSection {
  Section section;
  std::array<Field, kEyeKeyCount> keys{};
};

struct ParsedFile {
  std::array<std::array<EyeSection, 2>, kResolutionCount> eyes{};  // [resolution][0 left, 1 right]
  Section stereo;
  std::array<Field, kStereoKeyCount> stereo_keys{};
  std::array<std::array<Field, kPerResolutionKeyCount>, kResolutionCount> per_resolution{};
};

// Which section the parser is in.
struct Where {
  enum Kind { kNone, kUnknown, kEye, kStereo } kind = kNone;
  int resolution = 0;
  int eye = 0;  // 0 left, 1 right
  char name[64] = {};  // for messages
};

const char* eye_prefix(int eye) { return eye == 0 ? "LEFT_CAM_" : "RIGHT_CAM_"; }

char upper(char c) { return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c; }

bool iequal(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (upper(a[i]) != upper(b[i])) return false;
  }
  return true;
}

// a == prefix + suffix, case-insensitively.
bool iequal_joined(std::string_view a, std::string_view prefix, std::string_view suffix) {
  return a.size() == prefix.size() + suffix.size() && iequal(a.substr(0, prefix.size()), prefix) &&
         iequal(a.substr(prefix.size()), suffix);
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool is_key_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
         c == '.';
}

// Text from the file, safe to print: at most 40 bytes, non-printable bytes
// as '?'.
struct Excerpt {
  char text[48];
  explicit Excerpt(std::string_view s) {
    std::size_t n = 0;
    for (; n < s.size() && n < 40; ++n) {
      const unsigned char c = static_cast<unsigned char>(s[n]);
      text[n] = (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
    }
    if (s.size() > 40) {
      text[n++] = '.';
      text[n++] = '.';
      text[n++] = '.';
    }
    text[n] = '\0';
  }
};

class Reporter {
 public:
  Reporter(std::string_view name, std::string* error) : name_(name), error_(error) {}

  // "zed calibration: <file>[:<line>]: <message>"
  bool fail(int line, const char* fmt, ...) __attribute__((format(printf, 3, 4))) {
    if (error_ == nullptr) return false;
    char where[320];
    const int name_len = static_cast<int>(name_.size() > 200 ? 200 : name_.size());
    if (line > 0) {
      std::snprintf(where, sizeof where, "%.*s:%d", name_len, name_.data(), line);
    } else {
      std::snprintf(where, sizeof where, "%.*s", name_len, name_.data());
    }
    char message[640];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(message, sizeof message, fmt, args);
    va_end(args);
    *error_ = std::string("zed calibration: ") + where + ": " + message;
    return false;
  }

 private:
  std::string_view name_;
  std::string* error_;
};

// A decimal number and nothing else (no NaN, no infinity, no trailing text).
// std::from_chars ignores the locale, unlike strtod (a German locale would
// read "699.34" as 699).
bool parse_number(std::string_view value, double* out, const char** why) {
  if (value.empty()) {
    *why = "empty value";
    return false;
  }
  // from_chars takes no leading '+'; a hand-edited file may have one.
  std::string_view digits = value;
  if (digits.front() == '+') {
    digits.remove_prefix(1);
    if (digits.empty() || digits.front() == '+' || digits.front() == '-') {
      *why = "not a number";
      return false;
    }
  }
  double v = 0.0;
  const char* end = digits.data() + digits.size();
  const std::from_chars_result r = std::from_chars(digits.data(), end, v, std::chars_format::general);
  if (r.ec == std::errc::result_out_of_range) {
    *why = "out of the range of a double";
    return false;
  }
  if (r.ec != std::errc() || r.ptr == digits.data()) {
    *why = "not a number";
    return false;
  }
  if (r.ptr != end) {
    *why = "trailing characters after the number";
    return false;
  }
  if (!std::isfinite(v)) {
    *why = "NaN and infinity are not calibration values";
    return false;
  }
  *out = v;
  return true;
}

// SN<digits>.conf as the last path component -> serial; 0 otherwise.
std::int64_t serial_from_name(std::string_view name) {
  const std::size_t slash = name.find_last_of('/');
  std::string_view base = slash == std::string_view::npos ? name : name.substr(slash + 1);
  constexpr std::string_view kSuffix = ".conf";
  if (base.size() < 2 + kSuffix.size() + 1 || base.substr(0, 2) != "SN" ||
      base.substr(base.size() - kSuffix.size()) != kSuffix) {
    return 0;
  }
  const std::string_view digits = base.substr(2, base.size() - 2 - kSuffix.size());
  if (digits.size() > 18) return 0;
  std::int64_t serial = 0;
  for (char c : digits) {
    if (c < '0' || c > '9') return 0;
    serial = serial * 10 + (c - '0');
  }
  return serial;
}

// The [section] header: which section it is. Empty names are the caller's.
Where classify_section(std::string_view name) {
  Where w;
  const std::size_t n = name.size() < sizeof w.name - 1 ? name.size() : sizeof w.name - 1;
  std::memcpy(w.name, name.data(), n);
  w.name[n] = '\0';
  if (iequal(name, "STEREO")) {
    w.kind = Where::kStereo;
    return w;
  }
  for (int r = 0; r < kResolutionCount; ++r) {
    for (int e = 0; e < 2; ++e) {
      if (iequal_joined(name, eye_prefix(e), resolution_name(kResolutions[static_cast<std::size_t>(r)]))) {
        w.kind = Where::kEye;
        w.resolution = r;
        w.eye = e;
        return w;
      }
    }
  }
  w.kind = Where::kUnknown;
  return w;
}

// The field a key of the current section fills, or nullptr for keys the
// calibration does not use. *key_name gets the key's canonical spelling.
Field* field_for(ParsedFile* f, const Where& w, std::string_view key, const char** key_name) {
  if (w.kind == Where::kEye) {
    for (int i = 0; i < kEyeKeyCount; ++i) {
      if (iequal(key, kEyeKeys[static_cast<std::size_t>(i)])) {
        *key_name = kEyeKeys[static_cast<std::size_t>(i)];
        return &f->eyes[static_cast<std::size_t>(w.resolution)][static_cast<std::size_t>(w.eye)]
                    .keys[static_cast<std::size_t>(i)];
      }
    }
    return nullptr;
  }
  if (w.kind != Where::kStereo) return nullptr;
  for (int i = 0; i < kStereoKeyCount; ++i) {
    if (iequal(key, kStereoKeys[static_cast<std::size_t>(i)])) {
      *key_name = kStereoKeys[static_cast<std::size_t>(i)];
      return &f->stereo_keys[static_cast<std::size_t>(i)];
    }
  }
  for (int r = 0; r < kResolutionCount; ++r) {
    for (int i = 0; i < kPerResolutionKeyCount; ++i) {
      const std::string_view prefix = kPerResolutionKeys[static_cast<std::size_t>(i)];
      const std::string_view res = resolution_name(kResolutions[static_cast<std::size_t>(r)]);
      if (key.size() == prefix.size() + 1 + res.size() && iequal(key.substr(0, prefix.size()), prefix) &&
          key[prefix.size()] == '_' && iequal(key.substr(prefix.size() + 1), res)) {
        *key_name = nullptr;  // the caller prints the key as written
        return &f->per_resolution[static_cast<std::size_t>(r)][static_cast<std::size_t>(i)];
      }
    }
  }
  return nullptr;
}

bool parse_lines(std::string_view text, Reporter& report, ParsedFile* f) {
  // A UTF-8 byte-order mark, as Windows editors write it.
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  Where where;
  int line_no = 0;
  while (!text.empty()) {
    ++line_no;
    const std::size_t nl = text.find('\n');
    std::string_view raw = nl == std::string_view::npos ? text : text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    if (raw.size() > kMaxZedCalibrationLine) {
      return report.fail(line_no, "line is %zu characters long (at most %zu): this is not a ZED calibration file",
                         raw.size(), kMaxZedCalibrationLine);
    }
    if (raw.find('\0') != std::string_view::npos) {
      return report.fail(line_no, "line holds a NUL byte: this is not a ZED calibration file (binary or corrupted)");
    }
    const std::string_view line = trim(raw);
    if (line.empty() || line.front() == '#' || line.front() == ';') continue;

    if (line.front() == '[') {
      const std::string_view name = trim(line.substr(1, line.size() >= 2 ? line.size() - 2 : 0));
      bool ok = line.back() == ']' && line.size() >= 2 && !name.empty();
      for (char c : name) ok = ok && is_key_char(c);
      if (!ok) {
        return report.fail(line_no, "'%s' is neither `key = value` nor a `[SECTION]` header", Excerpt(line).text);
      }
      where = classify_section(name);
      Section* s = nullptr;
      if (where.kind == Where::kEye) {
        s = &f->eyes[static_cast<std::size_t>(where.resolution)][static_cast<std::size_t>(where.eye)].section;
      } else if (where.kind == Where::kStereo) {
        s = &f->stereo;
      }
      if (s != nullptr && s->line == 0) s->line = line_no;
      continue;
    }

    const std::size_t eq = line.find('=');
    const std::string_view key = eq == std::string_view::npos ? std::string_view{} : trim(line.substr(0, eq));
    bool key_ok = !key.empty();
    for (char c : key) key_ok = key_ok && is_key_char(c);
    if (!key_ok) {
      return report.fail(line_no, "'%s' is neither `key = value` nor a `[SECTION]` header", Excerpt(line).text);
    }
    const std::string_view value = trim(line.substr(eq + 1));
    if (where.kind == Where::kNone) {
      return report.fail(line_no, "key '%s' comes before any [SECTION] header", Excerpt(key).text);
    }
    const char* canonical = nullptr;
    Field* field = field_for(f, where, key, &canonical);
    if (field == nullptr) continue;  // a key this reader does not need
    const Excerpt key_text(key);
    const char* key_name = canonical != nullptr ? canonical : key_text.text;
    if (field->line != 0) {
      return report.fail(line_no, "[%s] %s: duplicate key (first set on line %d); keep one of the two", where.name,
                         key_name, field->line);
    }
    const char* why = "";
    if (!parse_number(value, &field->value, &why)) {
      return report.fail(line_no, "[%s] %s = '%s': malformed number (%s)", where.name, key_name, Excerpt(value).text,
                         why);
    }
    field->line = line_no;
  }
  return true;
}

bool eye_intrinsics(const ParsedFile& f, int r, int eye, Reporter& report, CameraIntrinsics* k) {
  const EyeSection& s = f.eyes[static_cast<std::size_t>(r)][static_cast<std::size_t>(eye)];
  const char* res = resolution_name(kResolutions[static_cast<std::size_t>(r)]);
  if (s.section.line == 0) {
    return report.fail(0, "missing section [%s%s]; the file is incomplete, download it again from "
                          "https://calib.stereolabs.com/?SN=<serial>",
                       eye_prefix(eye), res);
  }
  double v[kEyeKeyCount];
  for (int i = 0; i < kEyeKeyCount; ++i) {
    const Field& field = s.keys[static_cast<std::size_t>(i)];
    if (field.line == 0) {
      return report.fail(s.section.line, "[%s%s] has no key '%s' (each eye needs fx fy cx cy k1 k2 p1 p2 k3)",
                         eye_prefix(eye), res, kEyeKeys[static_cast<std::size_t>(i)]);
    }
    v[i] = field.value;
  }
  for (int i = 0; i < 2; ++i) {
    if (!(v[i] > 0.0)) {
      return report.fail(s.keys[static_cast<std::size_t>(i)].line, "[%s%s] %s = %g: focal length must be > 0 pixels",
                         eye_prefix(eye), res, kEyeKeys[static_cast<std::size_t>(i)], v[i]);
    }
  }
  *k = CameraIntrinsics{v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]};
  return true;
}

// Baseline / TY / TZ: the per-resolution key when present, else the plain one.
bool stereo_value(const ParsedFile& f, int r, StereoKey plain, int per_res, Reporter& report, double* out) {
  if (per_res >= 0) {
    const Field& specific = f.per_resolution[static_cast<std::size_t>(r)][static_cast<std::size_t>(per_res)];
    if (specific.line != 0) {
      *out = specific.value;
      return true;
    }
  }
  const Field& general = f.stereo_keys[static_cast<std::size_t>(plain)];
  if (general.line != 0) {
    *out = general.value;
    return true;
  }
  const char* key = kStereoKeys[static_cast<std::size_t>(plain)];
  if (per_res < 0) return report.fail(f.stereo.line, "[STEREO] has no key '%s' (millimetres)", key);
  return report.fail(f.stereo.line, "[STEREO] has no key '%s' (nor '%s_%s'; millimetres)", key, key,
                     resolution_name(kResolutions[static_cast<std::size_t>(r)]));
}

bool rotation_value(const ParsedFile& f, int r, int key, Reporter& report, double* out) {
  const Field& field = f.per_resolution[static_cast<std::size_t>(r)][static_cast<std::size_t>(key)];
  if (field.line == 0) {
    return report.fail(f.stereo.line, "[STEREO] has no key '%s_%s' (rotation of the right eye, radians)",
                       kPerResolutionKeys[static_cast<std::size_t>(key)],
                       resolution_name(kResolutions[static_cast<std::size_t>(r)]));
  }
  *out = field.value;
  return true;
}

}  // namespace

bool parse_zed_calibration(std::string_view text, std::string_view name, ZedResolution resolution,
                           std::int64_t expected_serial, ZedCalibration* calibration, std::string* error) {
  Reporter report(name, error);
  const std::int64_t serial = serial_from_name(name);
  if (expected_serial != 0) {
    if (serial == 0) {
      return report.fail(0, "the file name is not SN<serial>.conf, so the configured serial %lld cannot be checked; "
                            "use the factory file's name (SN%lld.conf)",
                         static_cast<long long>(expected_serial), static_cast<long long>(expected_serial));
    }
    if (serial != expected_serial) {
      return report.fail(0, "calibration of camera SN%lld, but the configured camera is SN%lld: use SN%lld.conf "
                            "(https://calib.stereolabs.com/?SN=%lld) or fix the configured serial",
                         static_cast<long long>(serial), static_cast<long long>(expected_serial),
                         static_cast<long long>(expected_serial), static_cast<long long>(expected_serial));
    }
  }
  if (text.size() > kMaxZedCalibrationBytes) {
    return report.fail(0, "%zu bytes (at most %zu): this is not a ZED calibration file", text.size(),
                       kMaxZedCalibrationBytes);
  }

  ParsedFile f;
  if (!parse_lines(text, report, &f)) return false;

  int r = 0;
  while (r < kResolutionCount && kResolutions[static_cast<std::size_t>(r)] != resolution) ++r;
  if (r == kResolutionCount) return report.fail(0, "resolution %d is not a ZED resolution", static_cast<int>(resolution));
  const char* res = resolution_name(resolution);
  const auto& eyes = f.eyes[static_cast<std::size_t>(r)];
  if (eyes[0].section.line == 0 && eyes[1].section.line == 0) {
    std::string have;
    for (int i = 0; i < kResolutionCount; ++i) {
      const auto& e = f.eyes[static_cast<std::size_t>(i)];
      if (e[0].section.line == 0 && e[1].section.line == 0) continue;
      if (!have.empty()) have += ", ";
      have += resolution_name(kResolutions[static_cast<std::size_t>(i)]);
    }
    if (have.empty()) have = "none";
    return report.fail(0, "no calibration for resolution %s ([LEFT_CAM_%s], [RIGHT_CAM_%s]); the file has: %s. Run "
                          "the camera at one of those or download the file again",
                       res, res, res, have.c_str());
  }

  ZedCalibration out;
  out.serial = serial;
  out.resolution = resolution;
  const EyeSize size = eye_size(resolution);
  out.stereo.width = size.width;
  out.stereo.height = size.height;
  if (!eye_intrinsics(f, r, 0, report, &out.stereo.left)) return false;
  if (!eye_intrinsics(f, r, 1, report, &out.stereo.right)) return false;

  if (f.stereo.line == 0) {
    return report.fail(0, "missing section [STEREO] (Baseline, TY, TZ, CV_%s, RX_%s, RZ_%s)", res, res, res);
  }
  double baseline_mm = 0.0, ty_mm = 0.0, tz_mm = 0.0, cv = 0.0, rx = 0.0, rz = 0.0;
  if (!stereo_value(f, r, kBaseline, -1, report, &baseline_mm)) return false;
  if (!(baseline_mm > 0.0)) {
    return report.fail(f.stereo_keys[kBaseline].line,
                       "[STEREO] Baseline = %g: must be > 0 mm (about 120 for a ZED, 63 for a ZED Mini)", baseline_mm);
  }
  if (!stereo_value(f, r, kTy, kTyRes, report, &ty_mm)) return false;
  if (!stereo_value(f, r, kTz, kTzRes, report, &tz_mm)) return false;
  if (!rotation_value(f, r, kCvRes, report, &cv)) return false;
  if (!rotation_value(f, r, kRxRes, report, &rx)) return false;
  if (!rotation_value(f, r, kRzRes, report, &rz)) return false;

  // See the header for where this convention comes from.
  out.stereo.rotation = Eigen::Vector3d(rx, cv, rz);
  out.stereo.translation = Eigen::Vector3d(-baseline_mm, -ty_mm, -tz_mm) * 1e-3;
  *calibration = out;
  return true;
}

bool read_zed_calibration_file(const std::string& path, std::string* text, std::string* error) {
  Reporter report(path, error);
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) {
    const int e = errno;
    return report.fail(0, "cannot open: %s%s", std::strerror(e),
                       e == ENOENT ? " (download it from https://calib.stereolabs.com/?SN=<serial>)" : "");
  }
  std::string bytes;
  char buf[4096];
  bool too_big = false;
  bool read_error = false;
  for (;;) {
    const std::size_t n = std::fread(buf, 1, sizeof buf, file);
    bytes.append(buf, n);
    if (bytes.size() > kMaxZedCalibrationBytes) {
      too_big = true;
      break;
    }
    if (n < sizeof buf) {
      read_error = std::ferror(file) != 0;
      break;
    }
  }
  const int e = errno;
  std::fclose(file);
  if (read_error) return report.fail(0, "read failed: %s", std::strerror(e));
  if (too_big) {
    return report.fail(0, "larger than %zu bytes: this is not a ZED calibration file", kMaxZedCalibrationBytes);
  }
  *text = std::move(bytes);
  return true;
}

bool load_zed_calibration(const std::string& path, ZedResolution resolution, std::int64_t expected_serial,
                          ZedCalibration* calibration, std::string* error) {
  std::string text;
  return read_zed_calibration_file(path, &text, error) &&
         parse_zed_calibration(text, path, resolution, expected_serial, calibration, error);
}

}  // namespace rtfuse::drivers
