#pragma once
// Typed reads from a parsed TOML document that collect every problem with its
// file:line:col instead of stopping at the first, so one run of the loader
// tells the user everything wrong with their file. Knows nothing of the
// rtfuse schema; config_loader.cpp is that.
//
// Configuration time only: this allocates freely.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "runtime/config/toml.hpp"

#include "estimation/state.hpp"
#include "runtime/config/config.hpp"
#include "runtime/config/config_loader.hpp"

namespace rtfuse::config {

using Keys = std::initializer_list<std::string_view>;

std::string fmt(double v);
std::string in_quotes(std::string_view s);
std::string type_name(toml::node_type t);

class Diagnostics {
 public:
  explicit Diagnostics(const std::string& file) : file_(file) {}

  void add(const toml::source_region& where, std::string key, std::string message);
  bool empty() const { return errors_.empty(); }
  // In file order, whatever order the errors were found in.
  std::vector<ConfigError> take();

 private:
  const std::string& file_;
  std::vector<ConfigError> errors_;
};

// A syntax error goes to `diag` and gives nullopt.
std::optional<toml::table> parse(std::string_view text, const std::string& source_name, Diagnostics& diag);

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
  const std::string& path() const { return path_; }
  // The table's own place in the file (its header).
  toml::source_region where() const { return table_ ? table_->source() : toml::source_region{}; }

  // Errors about a key (unknown, missing, wrong length) point at the key, or
  // at the table header when the key is absent; errors about a value at it.
  toml::source_region key_where(std::string_view k) const;
  toml::source_region value_where(std::string_view k) const;
  void key_error(std::string_view k, std::string msg) const;
  void value_error(std::string_view k, std::string msg) const;
  void table_error(std::string key, std::string msg) const;

  void reject_unknown(Keys allowed) const;
  void reject_unknown(const std::vector<std::string_view>& allowed) const;
  void require(Keys keys) const;
  bool type_error(std::string_view k, const toml::node& n, std::string_view expected) const;

  // Typed reads: true and `out` set when present and well typed; an absent key
  // returns false silently, a wrong type returns false with an error.
  bool read(std::string_view k, bool& out) const;
  bool read(std::string_view k, double& out) const;
  bool read(std::string_view k, std::int64_t& out) const;
  bool read(std::string_view k, std::string& out) const;
  bool read_name(std::string_view k, Name& out) const;
  const toml::array* array(std::string_view k) const;

 private:
  const toml::table* table_;
  std::string path_;
  Diagnostics& diag_;
};

inline bool positive(double v) { return v > 0; }  // +inf allowed: "no limit"
inline bool positive_finite(double v) { return v > 0 && std::isfinite(v); }
inline bool non_negative_finite(double v) { return v >= 0 && std::isfinite(v); }

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
std::optional<std::vector<double>> read_numbers(const Section& s, std::string_view k);
std::optional<std::vector<double>> read_fixed(const Section& s, std::string_view k, std::size_t n,
                                              std::string_view what);
// 15 numbers are the diagonal, 225 the row-major matrix; either way it must
// be a valid covariance or the filter diverges long after start-up.
void read_covariance(const Section& s, std::string_view k, est::StateMatrix& out);

const toml::table* section_table(const Section& root, std::string_view k);
// Returns the array of tables under `k` ([[sensor]], [[static_transform]]).
const toml::array* table_array(const Section& root, std::string_view k);

// Calls fn(entry, fits) for every table of the array under `k`; entries past
// max_entries are still checked (fits false) so all their errors show too.
template <class Fn>
void for_each_table(const Section& root, std::string_view k, int max_entries, Fn fn) {
  const toml::array* entries = table_array(root, k);
  if (!entries) return;
  for (std::size_t i = 0; i < entries->size(); ++i) {
    const toml::node& n = *entries->get(i);
    const std::string path = root.key(k) + "[" + std::to_string(i) + "]";
    if (static_cast<int>(i) == max_entries) {
      root.diag().add(n.source(), root.key(k),
                      "at most " + std::to_string(max_entries) + " entries, got " + std::to_string(entries->size()));
    }
    if (const auto* t = n.as_table()) {
      fn(Section(t, path, root.diag()), static_cast<int>(i) < max_entries);
    } else {
      root.diag().add(n.source(), path, "expected table, got " + type_name(n.type()));
    }
  }
}

}  // namespace rtfuse::config
