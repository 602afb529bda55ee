#include "runtime/config/toml_reader.hpp"

#include "runtime/config/toml_guard.hpp"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include <Eigen/Eigenvalues>

namespace rtfuse {

std::string ConfigError::to_string() const {
  std::string s = file;
  if (line > 0) s += ":" + std::to_string(line) + ":" + std::to_string(column);
  s += ": ";
  if (!key.empty()) s += key + ": ";
  s += message;
  return s;
}

namespace config {
namespace {

constexpr int kMaxSuggestDistance = 3;

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

}  // namespace

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

// --- diagnostics ------------------------------------------------------------

void Diagnostics::add(const toml::source_region& where, std::string key, std::string message) {
  errors_.push_back(ConfigError{file_, static_cast<int>(where.begin.line), static_cast<int>(where.begin.column),
                                std::move(key), std::move(message)});
}

// Sections are checked in schema order and toml++ tables iterate by key, so
// sort to give the user the errors in the order they read the file.
std::vector<ConfigError> Diagnostics::take() {
  std::stable_sort(errors_.begin(), errors_.end(), [](const ConfigError& a, const ConfigError& b) {
    return std::make_pair(a.line, a.column) < std::make_pair(b.line, b.column);
  });
  return std::move(errors_);
}

std::optional<toml::table> parse(std::string_view text, const std::string& source_name, Diagnostics& diag) {
  // What would abort or misbehave in toml++ never reaches it (toml_guard.hpp).
  if (const std::optional<TomlHazard> h = find_toml_hazard(text)) {
    toml::source_region where;
    where.begin = {static_cast<toml::source_index>(h->line), static_cast<toml::source_index>(h->column)};
    where.end = where.begin;
    diag.add(where, "", h->message);
    return std::nullopt;
  }
#if TOML_EXCEPTIONS
  try {
    return toml::parse(text, std::string_view(source_name));
  } catch (const toml::parse_error& e) {
    diag.add(e.source(), "", one_line(e.description()));
  } catch (const TomlInternalCheck& e) {
    // toml++ gives no position here (runtime/toml.hpp).
    diag.add(toml::source_region{}, "",
             std::string("not valid TOML: the parser (toml++ 3.3) stopped on its internal check `") + e.what() +
                 "` instead of naming the error; look for a stray bracket, brace, quote or comma");
  }
#else
  toml::parse_result parsed = toml::parse(text, std::string_view(source_name));
  if (parsed) return std::move(parsed).table();
  diag.add(parsed.error().source(), "", one_line(parsed.error().description()));
#endif
  return std::nullopt;
}

// --- Section ----------------------------------------------------------------

toml::source_region Section::key_where(std::string_view k) const {
  if (!table_) return {};
  const auto it = table_->find(k);
  return it != table_->end() ? it->first.source() : table_->source();
}

toml::source_region Section::value_where(std::string_view k) const {
  const toml::node* n = find(k);
  return n ? n->source() : key_where(k);
}

void Section::key_error(std::string_view k, std::string msg) const { diag_.add(key_where(k), key(k), std::move(msg)); }

void Section::value_error(std::string_view k, std::string msg) const {
  diag_.add(value_where(k), key(k), std::move(msg));
}

void Section::table_error(std::string key, std::string msg) const {
  diag_.add(table_ ? table_->source() : toml::source_region{}, std::move(key), std::move(msg));
}

void Section::reject_unknown(Keys allowed) const { reject_unknown(std::vector<std::string_view>(allowed)); }

void Section::reject_unknown(const std::vector<std::string_view>& allowed) const {
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

void Section::require(Keys keys) const {
  for (std::string_view k : keys) {
    if (!has(k)) table_error(key(k), "missing required key");
  }
}

bool Section::type_error(std::string_view k, const toml::node& n, std::string_view expected) const {
  value_error(k, "expected " + std::string(expected) + ", got " + type_name(n.type()));
  return false;
}

bool Section::read(std::string_view k, bool& out) const {
  const toml::node* n = find(k);
  if (!n) return false;
  if (const auto* b = n->as_boolean()) { out = b->get(); return true; }
  return type_error(k, *n, "boolean");
}

bool Section::read(std::string_view k, double& out) const {
  const toml::node* n = find(k);
  if (!n) return false;
  if (const auto v = as_number(*n)) { out = *v; return true; }
  return type_error(k, *n, "float");
}

bool Section::read(std::string_view k, std::int64_t& out) const {
  const toml::node* n = find(k);
  if (!n) return false;
  if (const auto* i = n->as_integer()) { out = i->get(); return true; }
  return type_error(k, *n, "integer");
}

bool Section::read(std::string_view k, std::string& out) const {
  const toml::node* n = find(k);
  if (!n) return false;
  if (const auto* s = n->as_string()) { out = s->get(); return true; }
  return type_error(k, *n, "string");
}

bool Section::read_name(std::string_view k, Name& out) const {
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

const toml::array* Section::array(std::string_view k) const {
  const toml::node* n = find(k);
  if (!n) return nullptr;
  if (const auto* a = n->as_array()) return a;
  type_error(k, *n, "array");
  return nullptr;
}

// --- values -----------------------------------------------------------------

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

void read_covariance(const Section& s, std::string_view k, est::StateMatrix& out) {
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
  const est::StateMatrix m = Eigen::Map<const Eigen::Matrix<double, n, n, Eigen::RowMajor>>(values->data());
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
  const Eigen::SelfAdjointEigenSolver<est::StateMatrix> eig(m, Eigen::EigenvaluesOnly);
  const double lo = eig.eigenvalues().minCoeff();
  const double hi = eig.eigenvalues().maxCoeff();
  if (lo < -1e-9 * std::max(hi, 0.0)) {
    s.key_error(k, "not positive semi-definite: smallest eigenvalue " + fmt(lo) + " (largest " + fmt(hi) + ")");
    return;
  }
  out = 0.5 * (m + m.transpose());  // drop the tolerated asymmetry
}

// --- tables -----------------------------------------------------------------

const toml::table* section_table(const Section& root, std::string_view k) {
  const toml::node* n = root.find(k);
  if (!n) return nullptr;
  if (const auto* t = n->as_table()) return t;
  root.type_error(k, *n, "table");
  return nullptr;
}

const toml::array* table_array(const Section& root, std::string_view k) {
  const toml::node* n = root.find(k);
  if (!n) return nullptr;
  if (const auto* a = n->as_array()) return a;
  root.value_error(k, "expected array of tables ([[" + std::string(k) + "]]), got " + type_name(n->type()));
  return nullptr;
}

}  // namespace config
}  // namespace rtfuse
