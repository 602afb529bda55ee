#include "runtime/config_loader.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <utility>

#include <Eigen/Eigenvalues>
#include <toml++/toml.h>

#include "geometry/rotation.hpp"

namespace rtfuse {

std::string ConfigError::to_string() const {
  std::string s = file;
  if (line > 0) s += ":" + std::to_string(line) + ":" + std::to_string(column);
  s += ": ";
  if (!key.empty()) s += key + ": ";
  s += message;
  return s;
}

namespace {

using est::StateMatrix;
using est::UpdateMask;
using Keys = std::initializer_list<std::string_view>;

constexpr std::array<std::string_view, est::kStateSize> kStateNames = {
    "x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz",
    "vroll", "vpitch", "vyaw", "ax", "ay", "az"};
constexpr const char* kStateList = "x y z roll pitch yaw vx vy vz vroll vpitch vyaw ax ay az";
constexpr int kMaxSuggestDistance = 3;

// robot_localization's ekf defaults, so a config without the key behaves
// exactly like an ekf.yaml without it.
constexpr std::array<double, est::kStateSize> kDefaultProcessNoise = {
    0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015};
constexpr double kDefaultInitialVariance = 1e-9;

std::string fmt(double v) {
  std::ostringstream os;
  os << std::setprecision(12) << v;
  return os.str();
}

std::string in_quotes(std::string_view s) { return "'" + std::string(s) + "'"; }

std::string type_name(toml::node_type t) {
  switch (t) {
    case toml::node_type::table: return "table";
    case toml::node_type::array: return "array";
    case toml::node_type::string: return "string";
    case toml::node_type::integer: return "integer";
    case toml::node_type::floating_point: return "float";
    case toml::node_type::boolean: return "boolean";
    case toml::node_type::date: return "date";
    case toml::node_type::time: return "time";
    case toml::node_type::date_time: return "date-time";
    case toml::node_type::none: break;
  }
  return "nothing";
}

// Optimal string alignment distance: a swapped pair of letters, the most
// common typo after a missing one, counts as a single edit.
int edit_distance(std::string_view a, std::string_view b) {
  const std::size_t n = a.size();
  const std::size_t m = b.size();
  std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1, 0));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = static_cast<int>(i);
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = static_cast<int>(j);
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const int cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[n][m];
}

std::optional<double> as_number(const toml::node& n) {
  if (const auto* f = n.as_floating_point()) return f->get();
  // TOML has no implicit conversion, but `frequency = 200` is what people write.
  if (const auto* i = n.as_integer()) return static_cast<double>(i->get());
  return std::nullopt;
}

class Diagnostics {
 public:
  explicit Diagnostics(const std::string& file) : file_(file) {}

  void add(const toml::source_region& where, std::string key, std::string message) {
    errors_.push_back(ConfigError{file_, static_cast<int>(where.begin.line),
                                  static_cast<int>(where.begin.column), std::move(key),
                                  std::move(message)});
  }
  bool empty() const { return errors_.empty(); }

  // Sections are checked in schema order and toml++ tables iterate by key, so
  // sort to give the user the errors in the order they read the file.
  std::vector<ConfigError> take() {
    std::stable_sort(errors_.begin(), errors_.end(), [](const ConfigError& a, const ConfigError& b) {
      return std::make_pair(a.line, a.column) < std::make_pair(b.line, b.column);
    });
    return std::move(errors_);
  }

 private:
  const std::string& file_;
  std::vector<ConfigError> errors_;
};

// One TOML table and its dotted path in messages ("filter", "sensor[2]").
// A null table is an absent section: every read leaves the default alone.
class Section {
 public:
  Section(const toml::table* table, std::string path, Diagnostics& diag)
      : table_(table), path_(std::move(path)), diag_(diag) {}

  Diagnostics& diag() const { return diag_; }
  std::string key(std::string_view k) const {
    return path_.empty() ? std::string(k) : path_ + "." + std::string(k);
  }
  const toml::node* find(std::string_view k) const { return table_ ? table_->get(k) : nullptr; }
  bool has(std::string_view k) const { return find(k) != nullptr; }

  // Errors about a key (unknown, missing, wrong length) point at the key, or
  // at the table header when the key is absent; errors about a value at it.
  toml::source_region key_where(std::string_view k) const {
    if (!table_) return {};
    const auto it = table_->find(k);
    return it != table_->end() ? it->first.source() : table_->source();
  }
  toml::source_region value_where(std::string_view k) const {
    const toml::node* n = find(k);
    return n ? n->source() : key_where(k);
  }
  void key_error(std::string_view k, std::string msg) const { diag_.add(key_where(k), key(k), std::move(msg)); }
  void value_error(std::string_view k, std::string msg) const { diag_.add(value_where(k), key(k), std::move(msg)); }
  void table_error(std::string key, std::string msg) const {
    diag_.add(table_ ? table_->source() : toml::source_region{}, std::move(key), std::move(msg));
  }

  void reject_unknown(Keys allowed) const {
    if (!table_) return;
    for (auto&& [k, v] : *table_) {
      (void)v;
      const std::string_view name = k.str();
      if (std::find(allowed.begin(), allowed.end(), name) != allowed.end()) continue;
      std::string msg = "unknown key";
      int best = kMaxSuggestDistance + 1;
      std::string_view suggestion;
      for (std::string_view a : allowed) {
        const int dist = edit_distance(name, a);
        if (dist < best) { best = dist; suggestion = a; }
      }
      if (!suggestion.empty()) msg += " (did you mean " + in_quotes(suggestion) + "?)";
      diag_.add(k.source(), key(name), std::move(msg));
    }
  }

  void require(Keys keys) const {
    for (std::string_view k : keys) {
      if (!has(k)) table_error(key(k), "missing required key");
    }
  }

  bool type_error(std::string_view k, const toml::node& n, std::string_view expected) const {
    value_error(k, "expected " + std::string(expected) + ", got " + type_name(n.type()));
    return false;
  }

  // Typed reads: true and `out` set when present and well typed; an absent key
  // returns false silently, a wrong type returns false with an error.
  bool read(std::string_view k, bool& out) const {
    const toml::node* n = find(k);
    if (!n) return false;
    if (const auto* b = n->as_boolean()) { out = b->get(); return true; }
    return type_error(k, *n, "boolean");
  }
  bool read(std::string_view k, double& out) const {
    const toml::node* n = find(k);
    if (!n) return false;
    if (const auto v = as_number(*n)) { out = *v; return true; }
    return type_error(k, *n, "float");
  }
  bool read(std::string_view k, std::int64_t& out) const {
    const toml::node* n = find(k);
    if (!n) return false;
    if (const auto* i = n->as_integer()) { out = i->get(); return true; }
    return type_error(k, *n, "integer");
  }
  bool read(std::string_view k, std::string& out) const {
    const toml::node* n = find(k);
    if (!n) return false;
    if (const auto* s = n->as_string()) { out = s->get(); return true; }
    return type_error(k, *n, "string");
  }
  bool read_name(std::string_view k, Name& out) const {
    std::string s;
    if (!read(k, s)) return false;
    if (s.empty()) { value_error(k, "must not be empty"); return false; }
    if (!out.assign(s)) {
      value_error(k, "longer than " + std::to_string(Name::max_size()) + " characters (" +
                         std::to_string(s.size()) + ")");
      return false;
    }
    return true;
  }
  const toml::array* array(std::string_view k) const {
    const toml::node* n = find(k);
    if (!n) return nullptr;
    if (const auto* a = n->as_array()) return a;
    type_error(k, *n, "array");
    return nullptr;
  }

 private:
  const toml::table* table_;
  std::string path_;
  Diagnostics& diag_;
};

// --- value checks -----------------------------------------------------------

bool positive(double v) { return v > 0; }  // +inf allowed: "no limit"
bool positive_finite(double v) { return v > 0 && std::isfinite(v); }
bool non_negative_finite(double v) { return v >= 0 && std::isfinite(v); }

template <class Ok>
bool read_number(const Section& s, std::string_view k, double& out, Ok ok, std::string_view rule) {
  double v = out;
  if (!s.read(k, v)) return false;
  if (!ok(v)) {
    s.value_error(k, std::string(rule) + ", got " + fmt(v));
    return false;
  }
  out = v;
  return true;
}

template <class Int>
void read_int(const Section& s, std::string_view k, Int& out, std::int64_t lo, std::int64_t hi) {
  std::int64_t v = 0;
  if (!s.read(k, v)) return;
  if (v < lo || v > hi) {
    s.value_error(k, "must be between " + std::to_string(lo) + " and " + std::to_string(hi) +
                         ", got " + std::to_string(v));
    return;
  }
  out = static_cast<Int>(v);
}

// A numeric array whose elements are all finite numbers; element errors are
// reported at the element ("filter.initial_state[3]").
std::optional<std::vector<double>> read_numbers(const Section& s, std::string_view k) {
  const toml::array* a = s.array(k);
  if (!a) return std::nullopt;
  std::vector<double> values;
  bool ok = true;
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::node& e = *a->get(i);
    const std::string element = s.key(k) + "[" + std::to_string(i) + "]";
    const auto v = as_number(e);
    if (!v) {
      s.diag().add(e.source(), element, "expected float, got " + type_name(e.type()));
      ok = false;
    } else if (!std::isfinite(*v)) {
      s.diag().add(e.source(), element, "must be finite, got " + fmt(*v));
      ok = false;
    } else {
      values.push_back(*v);
    }
  }
  if (!ok) return std::nullopt;
  return values;
}

std::optional<std::vector<double>> read_fixed(const Section& s, std::string_view k, std::size_t n,
                                              std::string_view what) {
  auto values = read_numbers(s, k);
  if (!values) return std::nullopt;
  if (values->size() != n) {
    s.key_error(k, "expected " + std::to_string(n) + " floats (" + std::string(what) + "), got " +
                       std::to_string(values->size()));
    return std::nullopt;
  }
  return values;
}

// 15 numbers are the diagonal, 225 the row-major matrix; either way it must
// be a valid covariance or the filter diverges long after start-up.
void read_covariance(const Section& s, std::string_view k, StateMatrix& out) {
  const auto values = read_numbers(s, k);
  if (!values) return;
  const toml::array& nodes = *s.find(k)->as_array();
  constexpr int n = est::kStateSize;
  if (values->size() == static_cast<std::size_t>(n)) {
    bool ok = true;
    for (int i = 0; i < n; ++i) {
      if ((*values)[i] < 0) {
        s.diag().add(nodes.get(i)->source(), s.key(k) + "[" + std::to_string(i) + "]",
                     "a variance must be >= 0, got " + fmt((*values)[i]));
        ok = false;
      }
    }
    if (ok) out = Eigen::Map<const est::StateVector>(values->data()).asDiagonal();
    return;
  }
  if (values->size() != static_cast<std::size_t>(n * n)) {
    s.key_error(k, "expected 15 (diagonal) or 225 (row-major 15x15) floats, got " +
                       std::to_string(values->size()));
    return;
  }
  const StateMatrix m = Eigen::Map<const Eigen::Matrix<double, n, n, Eigen::RowMajor>>(values->data());
  const double tol = 1e-9 * m.cwiseAbs().maxCoeff();
  for (int r = 1; r < n; ++r) {
    for (int c = 0; c < r; ++c) {
      if (std::abs(m(r, c) - m(c, r)) > tol) {
        const std::string rc = "[" + std::to_string(r) + "][" + std::to_string(c) + "]";
        const std::string cr = "[" + std::to_string(c) + "][" + std::to_string(r) + "]";
        s.diag().add(nodes.get(static_cast<std::size_t>(r * n + c))->source(), s.key(k),
                     "not symmetric: " + rc + " = " + fmt(m(r, c)) + " but " + cr + " = " + fmt(m(c, r)));
        return;
      }
    }
  }
  const Eigen::SelfAdjointEigenSolver<StateMatrix> eig(m, Eigen::EigenvaluesOnly);
  const double lo = eig.eigenvalues().minCoeff();
  const double hi = eig.eigenvalues().maxCoeff();
  if (lo < -1e-9 * std::max(hi, 0.0)) {
    s.key_error(k, "not positive semi-definite: smallest eigenvalue " + fmt(lo) + " (largest " + fmt(hi) + ")");
    return;
  }
  out = 0.5 * (m + m.transpose());  // drop the tolerated asymmetry
}

// --- sections ---------------------------------------------------------------

const toml::table* section_table(const Section& root, std::string_view k) {
  const toml::node* n = root.find(k);
  if (!n) return nullptr;
  if (const auto* t = n->as_table()) return t;
  root.type_error(k, *n, "table");
  return nullptr;
}

// A frame constraint names the key the user wrote, so prefer that one when
// the other side of the comparison is a default.
void frames_must_differ(const Section& s, std::string_view a, const Name& va, std::string_view b,
                        const Name& vb) {
  if (va != vb) return;
  const std::string_view at = s.has(b) ? b : a;
  const std::string_view other = at == b ? a : b;
  s.value_error(at, "must differ from " + std::string(other) + " (both " + in_quotes(va.view()) + ")");
}

void read_filter(const Section& s, RuntimeConfig& cfg) {
  s.reject_unknown({"frequency", "sensor_timeout", "two_d_mode", "world_frame", "odom_frame",
                    "base_link_frame", "map_frame", "process_noise_covariance",
                    "initial_estimate_covariance", "dynamic_process_noise_covariance",
                    "initial_state", "max_variance", "smooth_lagged_data", "history_length",
                    "gravitational_acceleration", "yaw_conflict_gate"});
  est::FilterParams& f = cfg.filter;
  read_number(s, "frequency", cfg.rate_hz, [](double v) { return v > 0 && v <= 10000; },
              "must be > 0 and <= 10000 Hz");
  f.sensor_timeout_s = 1.0 / cfg.rate_hz;
  read_number(s, "sensor_timeout", f.sensor_timeout_s, positive_finite, "must be > 0 s and finite");
  s.read("two_d_mode", f.two_d_mode);

  s.read_name("odom_frame", cfg.odom_frame);
  s.read_name("base_link_frame", cfg.base_link_frame);
  s.read_name("map_frame", cfg.map_frame);
  cfg.world_frame = cfg.odom_frame;
  if (s.read_name("world_frame", cfg.world_frame) && cfg.world_frame != cfg.odom_frame &&
      cfg.world_frame != cfg.map_frame) {
    s.value_error("world_frame", "must equal odom_frame (" + in_quotes(cfg.odom_frame.view()) +
                                     ") or map_frame (" + in_quotes(cfg.map_frame.view()) + "), got " +
                                     in_quotes(cfg.world_frame.view()));
  }
  // robot_localization refuses the same name for two of these; base_link
  // differing from both also makes it differ from world_frame.
  frames_must_differ(s, "odom_frame", cfg.odom_frame, "base_link_frame", cfg.base_link_frame);
  frames_must_differ(s, "map_frame", cfg.map_frame, "base_link_frame", cfg.base_link_frame);
  frames_must_differ(s, "odom_frame", cfg.odom_frame, "map_frame", cfg.map_frame);

  f.process_noise = Eigen::Map<const est::StateVector>(kDefaultProcessNoise.data()).asDiagonal();
  read_covariance(s, "process_noise_covariance", f.process_noise);
  f.initial_covariance = StateMatrix::Identity() * kDefaultInitialVariance;
  read_covariance(s, "initial_estimate_covariance", f.initial_covariance);
  s.read("dynamic_process_noise_covariance", f.dynamic_process_noise);
  if (const auto x0 = read_fixed(s, "initial_state", est::kStateSize, kStateList)) {
    f.has_initial_state = true;
    f.initial_state = Eigen::Map<const est::StateVector>(x0->data());
  }
  read_number(s, "max_variance", f.max_variance, positive, "must be > 0");
  s.read("smooth_lagged_data", f.smooth_lagged_data);
  const bool history_ok = read_number(s, "history_length", f.history_length_s, non_negative_finite,
                                      "must be >= 0 s and finite");
  if (f.smooth_lagged_data && !(f.history_length_s > 0) && (history_ok || !s.has("history_length"))) {
    const std::string_view at = s.has("history_length") ? "history_length" : "smooth_lagged_data";
    s.diag().add(s.value_where(at), s.key("history_length"),
                 "must be > 0 s when smooth_lagged_data is true, got " + fmt(f.history_length_s));
  }
  read_number(s, "gravitational_acceleration", f.gravity, non_negative_finite, "must be >= 0 and finite");
  read_number(s, "yaw_conflict_gate", f.yaw_conflict_gate_sigma, positive, "must be > 0");
}

void read_realtime(const Section& s, RealtimeConfig& rt) {
  s.reject_unknown({"lock_memory", "priority", "cpu", "require"});
  s.read("lock_memory", rt.lock_memory);
  read_int(s, "priority", rt.priority, 0, 99);
  read_int(s, "cpu", rt.cpu, -1, 1023);  // CPU_SETSIZE
  s.read("require", rt.require);
}

void read_lcm(const Section& s, std::string& url_out) {
  s.reject_unknown({"url"});
  std::string url;
  if (!s.read("url", url)) return;
  const std::size_t sep = url.find("://");
  if (url.empty()) {
    s.value_error("url", "must not be empty");
  } else if (sep == std::string::npos || sep == 0) {
    // LCM picks the provider from "name://"; without it lcm_create fails at
    // start-up with a far less helpful message.
    s.value_error("url", "must be '<provider>://...' (udpm://, memq://, file://, ...), got " + in_quotes(url));
  } else {
    url_out = url;
  }
}

// A channel in use, remembered so later sections can report a collision.
struct ChannelUse {
  Name name;
  std::string key;
};

void read_publish(const Section& s, PublishConfig& p, std::vector<ChannelUse>& channels) {
  s.reject_unknown({"odometry_channel", "odometry_rate", "pose_channel", "pose_rate", "tf_channel",
                    "tf_rate", "state_channel", "state_rate", "diagnostics_channel",
                    "diagnostics_rate", "set_pose_channel", "publish_tf"});
  const std::pair<std::string_view, Name*> names[] = {
      {"odometry_channel", &p.odometry_channel}, {"pose_channel", &p.pose_channel},
      {"tf_channel", &p.tf_channel},             {"state_channel", &p.state_channel},
      {"diagnostics_channel", &p.diagnostics_channel}, {"set_pose_channel", &p.set_pose_channel}};
  for (const auto& [k, name] : names) {
    s.read_name(k, *name);
    for (const ChannelUse& used : channels) {
      if (used.name == *name) {
        s.value_error(k, "channel " + in_quotes(name->view()) + " is also " + used.key);
        break;
      }
    }
    channels.push_back({*name, s.key(k)});
  }
  const std::pair<std::string_view, double*> rates[] = {
      {"odometry_rate", &p.odometry_rate_hz}, {"pose_rate", &p.pose_rate_hz},
      {"tf_rate", &p.tf_rate_hz},             {"state_rate", &p.state_rate_hz},
      {"diagnostics_rate", &p.diagnostics_rate_hz}};
  for (const auto& [k, rate] : rates) {
    read_number(s, k, *rate, [](double v) { return v >= 0 && v <= 10000; },
                "must be >= 0 and <= 10000 Hz (0 disables)");
  }
  s.read("publish_tf", p.publish_tf);
}

std::optional<est::SensorKind> parse_kind(std::string_view t) {
  if (t == "odometry") return est::SensorKind::kOdometry;
  if (t == "pose") return est::SensorKind::kPose;
  if (t == "twist") return est::SensorKind::kTwist;
  if (t == "imu") return est::SensorKind::kImu;
  return std::nullopt;
}

std::string_view kind_name(est::SensorKind k) {
  switch (k) {
    case est::SensorKind::kOdometry: return "odometry";
    case est::SensorKind::kPose: return "pose";
    case est::SensorKind::kTwist: return "twist";
    case est::SensorKind::kImu: return "imu";
  }
  return "?";
}

// What each message type carries (nav_msgs/Odometry has no acceleration,
// sensor_msgs/Imu no position or linear velocity).
UpdateMask providable(est::SensorKind k) {
  switch (k) {
    case est::SensorKind::kOdometry: return est::kPoseMask | est::kTwistMask;
    case est::SensorKind::kPose: return est::kPoseMask;
    case est::SensorKind::kTwist: return est::kTwistMask;
    case est::SensorKind::kImu:
      return est::kOrientationMask | est::kAngularVelocityMask | est::kAccelerationMask;
  }
  return 0;
}

std::string mask_names(UpdateMask m) {
  std::string out;
  for (int i = 0; i < est::kStateSize; ++i) {
    if (!est::mask_has(m, i)) continue;
    if (!out.empty()) out += ' ';
    out += kStateNames[static_cast<std::size_t>(i)];
  }
  return out;
}

std::optional<UpdateMask> read_mask(const Section& s, std::string_view k) {
  const toml::array* a = s.array(k);
  if (!a) return std::nullopt;
  if (a->size() != static_cast<std::size_t>(est::kStateSize)) {
    s.key_error(k, std::string("expected 15 booleans (") + kStateList + "), got " + std::to_string(a->size()));
    return std::nullopt;
  }
  UpdateMask mask = 0;
  bool ok = true;
  for (int i = 0; i < est::kStateSize; ++i) {
    const toml::node& e = *a->get(static_cast<std::size_t>(i));
    if (const auto* b = e.as_boolean()) {
      if (b->get()) mask |= est::mask_bit(i);
    } else {
      s.diag().add(e.source(), s.key(k) + "[" + std::to_string(i) + "]",
                   "expected boolean, got " + type_name(e.type()));
      ok = false;
    }
  }
  if (!ok) return std::nullopt;
  return mask;
}

struct SensorEntry {
  SensorConfig cfg;
  bool has_name = false;
  bool has_channel = false;
};

SensorEntry read_sensor(const Section& s) {
  s.reject_unknown({"name", "type", "channel", "config", "differential", "relative", "queue_size",
                    "pose_rejection_threshold", "twist_rejection_threshold",
                    "linear_acceleration_rejection_threshold", "remove_gravitational_acceleration"});
  s.require({"name", "type", "channel", "config"});
  SensorEntry e;
  est::SensorParams& p = e.cfg.params;
  e.has_name = s.read_name("name", e.cfg.name);
  e.has_channel = s.read_name("channel", e.cfg.channel);

  std::optional<est::SensorKind> kind;
  std::string type;
  if (s.read("type", type)) {
    kind = parse_kind(type);
    if (kind) {
      p.kind = *kind;
    } else {
      s.value_error("type", "must be one of odometry, pose, twist, imu, got " + in_quotes(type));
    }
  }

  const auto mask = read_mask(s, "config");
  if (mask) {
    p.update_mask = *mask;
    if (*mask == 0) s.key_error("config", "fuses nothing: at least one entry must be true");
  }
  if (mask && kind) {
    const UpdateMask extra = *mask & static_cast<UpdateMask>(~providable(*kind));
    if (extra) {
      int first = 0;
      while (!est::mask_has(extra, first)) ++first;
      s.diag().add(s.find("config")->as_array()->get(static_cast<std::size_t>(first))->source(),
                   s.key("config"),
                   "type " + in_quotes(kind_name(*kind)) + " cannot provide " + mask_names(extra) +
                       " (it provides " + mask_names(providable(*kind)) + ")");
    }
  }

  s.read("differential", p.differential);
  s.read("relative", p.relative);
  if (p.differential && p.relative) s.value_error("relative", "differential and relative cannot both be true");
  read_int(s, "queue_size", p.queue_size, 1, 1024);
  read_number(s, "pose_rejection_threshold", p.pose_rejection_threshold, positive, "must be > 0");
  read_number(s, "twist_rejection_threshold", p.twist_rejection_threshold, positive, "must be > 0");
  read_number(s, "linear_acceleration_rejection_threshold", p.linear_acceleration_rejection_threshold,
              positive, "must be > 0");
  s.read("remove_gravitational_acceleration", p.remove_gravitational_acceleration);
  if (kind && *kind != est::SensorKind::kImu) {
    for (std::string_view k : {"linear_acceleration_rejection_threshold", "remove_gravitational_acceleration"}) {
      if (s.has(k)) s.key_error(k, "only valid for type 'imu'");
    }
  }
  return e;
}

// Returns the array of tables under `k` ([[sensor]], [[static_transform]]).
const toml::array* table_array(const Section& root, std::string_view k) {
  const toml::node* n = root.find(k);
  if (!n) return nullptr;
  if (const auto* a = n->as_array()) return a;
  root.value_error(k, "expected array of tables ([[" + std::string(k) + "]]), got " + type_name(n->type()));
  return nullptr;
}

template <class Fn>
void for_each_table(const Section& root, std::string_view k, int max_entries, Fn fn) {
  const toml::array* entries = table_array(root, k);
  if (!entries) return;
  for (std::size_t i = 0; i < entries->size(); ++i) {
    const toml::node& n = *entries->get(i);
    const std::string path = std::string(k) + "[" + std::to_string(i) + "]";
    if (static_cast<int>(i) == max_entries) {
      root.diag().add(n.source(), std::string(k),
                      "at most " + std::to_string(max_entries) + " entries, got " + std::to_string(entries->size()));
    }
    if (const auto* t = n.as_table()) {
      fn(Section(t, path, root.diag()), static_cast<int>(i) < max_entries);
    } else {
      root.diag().add(n.source(), path, "expected table, got " + type_name(n.type()));
    }
  }
}

void read_sensors(const Section& root, RuntimeConfig& cfg, const std::vector<ChannelUse>& publish) {
  for_each_table(root, "sensor", kMaxSensors, [&](const Section& s, bool fits) {
    const SensorEntry e = read_sensor(s);
    for (int j = 0; j < cfg.num_sensors && e.has_name; ++j) {
      if (cfg.sensors[static_cast<std::size_t>(j)].name == e.cfg.name) {
        s.value_error("name", "duplicate sensor name " + in_quotes(e.cfg.name.view()) + " (also sensor[" +
                                  std::to_string(j) + "])");
        break;
      }
    }
    bool channel_taken = false;
    for (int j = 0; j < cfg.num_sensors && e.has_channel; ++j) {
      if (cfg.sensors[static_cast<std::size_t>(j)].channel == e.cfg.channel) {
        s.value_error("channel", "channel " + in_quotes(e.cfg.channel.view()) + " is also sensor[" +
                                     std::to_string(j) + "].channel");
        channel_taken = true;
        break;
      }
    }
    for (const ChannelUse& used : publish) {
      if (!channel_taken && e.has_channel && used.name == e.cfg.channel) {
        s.value_error("channel", "channel " + in_quotes(e.cfg.channel.view()) + " is also " + used.key);
        break;
      }
    }
    // Unnamed entries are still stored (the config is rejected anyway) so
    // that "also sensor[j]" indices match the file.
    if (fits) cfg.sensors[static_cast<std::size_t>(cfg.num_sensors++)] = e.cfg;
  });
}

void read_static_transform(const Section& s, StaticTransformConfig& out) {
  s.reject_unknown({"parent", "child", "translation", "rpy", "quaternion"});
  s.require({"parent", "child", "translation"});
  const bool parent = s.read_name("parent", out.parent);
  if (s.read_name("child", out.child) && parent && out.parent == out.child) {
    s.value_error("child", "must differ from parent (both " + in_quotes(out.child.view()) + ")");
  }
  if (const auto t = read_fixed(s, "translation", 3, "x y z")) {
    out.parent_T_child.translation = Eigen::Vector3d((*t)[0], (*t)[1], (*t)[2]);
  }
  const bool has_rpy = s.has("rpy");
  const bool has_quaternion = s.has("quaternion");
  if (has_rpy && has_quaternion) {
    s.key_error("quaternion", "rpy and quaternion are both given: give exactly one");
    return;
  }
  if (!has_rpy && !has_quaternion) {
    s.table_error(s.key("rpy"), "missing rotation: give exactly one of rpy or quaternion");
    return;
  }
  if (has_rpy) {
    if (const auto r = read_fixed(s, "rpy", 3, "roll pitch yaw")) {
      out.parent_T_child.rotation = geometry::quaternion_from_rpy((*r)[0], (*r)[1], (*r)[2]);
    }
    return;
  }
  if (const auto q = read_fixed(s, "quaternion", 4, "x y z w")) {
    const Eigen::Quaterniond quat((*q)[3], (*q)[0], (*q)[1], (*q)[2]);
    if (std::abs(quat.norm() - 1.0) > 1e-3) {
      s.value_error("quaternion", "norm must be within 1e-3 of 1, got " + fmt(quat.norm()));
    } else {
      out.parent_T_child.rotation = quat.normalized();
    }
  }
}

void read_static_transforms(const Section& root, RuntimeConfig& cfg) {
  for_each_table(root, "static_transform", kMaxStaticTransforms, [&](const Section& s, bool fits) {
    StaticTransformConfig t;
    read_static_transform(s, t);
    if (fits) cfg.static_transforms[static_cast<std::size_t>(cfg.num_static_transforms++)] = t;
  });
}

void read_sim(const Section& s, SimConfig& sim) {
  s.reject_unknown({"enabled", "seed", "radius", "speed", "imu_rate", "odom_rate", "imu_channel",
                    "odom_channel", "truth_channel", "gyro_noise", "gyro_bias", "accel_noise",
                    "accel_bias", "orientation_noise", "yaw_error", "yaw_error_time", "odom_speed_noise",
                    "odom_yaw_rate_noise", "wheel_slip"});
  s.read("enabled", sim.enabled);
  read_int(s, "seed", sim.seed, 0, std::numeric_limits<std::int64_t>::max());
  read_number(s, "radius", sim.figure_eight_radius_m, positive_finite, "must be > 0 m and finite");
  read_number(s, "speed", sim.speed_mps, positive_finite, "must be > 0 m/s and finite");
  read_number(s, "imu_rate", sim.imu_rate_hz, positive_finite, "must be > 0 Hz and finite");
  read_number(s, "odom_rate", sim.odom_rate_hz, positive_finite, "must be > 0 Hz and finite");
  s.read_name("imu_channel", sim.imu_channel);
  s.read_name("odom_channel", sim.odom_channel);
  s.read_name("truth_channel", sim.truth_channel);
  const std::pair<std::string_view, double*> magnitudes[] = {
      {"gyro_noise", &sim.gyro_noise_rad_s},
      {"gyro_bias", &sim.gyro_bias_rad_s},
      {"accel_noise", &sim.accel_noise_mps2},
      {"accel_bias", &sim.accel_bias_mps2},
      {"orientation_noise", &sim.orientation_noise_rad},
      {"yaw_error", &sim.yaw_error_rad},
      {"odom_speed_noise", &sim.odom_speed_noise_mps},
      {"odom_yaw_rate_noise", &sim.odom_yaw_rate_noise_rad_s}};
  for (const auto& [k, v] : magnitudes) read_number(s, k, *v, non_negative_finite, "must be >= 0 and finite");
  read_number(s, "yaw_error_time", sim.yaw_error_time_s, positive_finite, "must be > 0 s and finite");
  read_number(s, "wheel_slip", sim.wheel_slip, [](double v) { return v >= 0 && v < 1; },
              "must be >= 0 and < 1");
}

void read_root(const Section& root, RuntimeConfig& cfg) {
  root.reject_unknown({"filter", "realtime", "lcm", "publish", "sensor", "static_transform", "sim"});
  Diagnostics& d = root.diag();
  read_filter(Section(section_table(root, "filter"), "filter", d), cfg);
  read_realtime(Section(section_table(root, "realtime"), "realtime", d), cfg.realtime);
  read_lcm(Section(section_table(root, "lcm"), "lcm", d), cfg.lcm_url);
  std::vector<ChannelUse> publish_channels;
  read_publish(Section(section_table(root, "publish"), "publish", d), cfg.publish, publish_channels);
  read_sensors(root, cfg, publish_channels);
  read_static_transforms(root, cfg);
  read_sim(Section(section_table(root, "sim"), "sim", d), cfg.sim);
}

// toml++ quotes the offending input verbatim, newline included; a message
// must stay on one line to be usable in logs and editors' error lists.
std::string one_line(std::string_view text) {
  std::string out;
  for (const char ch : text) {
    if (ch == '\n') {
      out += "\\n";
    } else if (ch == '\r') {
      out += "\\r";
    } else if (ch == '\t') {
      out += "\\t";
    } else {
      out += ch;
    }
  }
  return out;
}

ConfigLoadResult unreadable(const std::string& path, int err) {
  ConfigLoadResult r;
  r.errors.push_back(ConfigError{path, 0, 0, "", std::string("cannot read file: ") + std::strerror(err)});
  return r;
}

}  // namespace

ConfigLoadResult load_config_string(std::string_view toml_text, const std::string& source_name) {
  ConfigLoadResult result;
  Diagnostics diag(source_name);
  toml::table root;
#if TOML_EXCEPTIONS
  try {
    root = toml::parse(toml_text, std::string_view(source_name));
  } catch (const toml::parse_error& e) {
    diag.add(e.source(), "", one_line(e.description()));
  }
#else
  toml::parse_result parsed = toml::parse(toml_text, std::string_view(source_name));
  if (parsed) {
    root = std::move(parsed).table();
  } else {
    diag.add(parsed.error().source(), "", one_line(parsed.error().description()));
  }
#endif
  if (diag.empty()) {
    RuntimeConfig& cfg = result.config.emplace();
    cfg.source = source_name;
    read_root(Section(&root, "", diag), cfg);
  }
  if (!diag.empty()) result.config.reset();
  result.errors = diag.take();
  return result;
}

ConfigLoadResult load_config_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return unreadable(path, errno);
  std::string text;
  char buf[1 << 14];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
  // A directory opens fine on Linux and fails here with EISDIR.
  const int err = std::ferror(f) ? (errno != 0 ? errno : EIO) : 0;
  std::fclose(f);
  if (err != 0) return unreadable(path, err);
  return load_config_string(text, path);
}

}  // namespace rtfuse
