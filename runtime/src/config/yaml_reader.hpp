#pragma once
// Internal: strict YAML reading shared by the profile and world loaders (not installed).
// Every map lists its allowed keys up front (unknown and duplicate keys are errors, with a
// "did you mean" suggestion), every scalar is parsed by hand so that "0.05" (quoted), "yes" or
// "1.5" for an integer are type errors, and every message carries file:line:column and the
// key path.
#include <duet/kernels/error.hpp>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <locale>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace duet::detail {

// Ranges: [lo, hi] with open/closed ends and a unit, for messages and checks.
struct Range {
  double lo, hi;
  bool lo_open, hi_open;
  const char* unit;  // "" for none
};


inline std::string format_number(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  if (v == std::floor(v) && std::fabs(v) < 1e15) return std::to_string(static_cast<long long>(v));  // integers exactly
  std::ostringstream os;
  os.imbue(std::locale::classic());
  os.precision(9);
  os << v;
  return os.str();
}

inline std::string describe(const Range& r) {
  std::string s;
  s += r.lo_open ? "(" : "[";
  s += format_number(r.lo) + ", " + format_number(r.hi);
  s += r.hi_open ? ")" : "]";
  if (*r.unit != '\0') {
    s += ' ';
    s += r.unit;
  }
  return s;
}

inline bool in_range(double v, const Range& r) {
  if (!std::isfinite(v)) return false;
  if (r.lo_open ? !(v > r.lo) : !(v >= r.lo)) return false;
  if (r.hi_open ? !(v < r.hi) : !(v <= r.hi)) return false;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Where a key path came from: "file:line:col" if the parser saw it, else the source name.

class Locator {
 public:
  explicit Locator(std::string source) : source_(std::move(source)) {}
  /// Nodes that came from an overlay (config/profile.hpp: --config, --set) are located in it.
  void add_overlay(const YAML::Node& n, const std::string& source) {
    overlay_.emplace_back(n, source);
    if (n.IsMap())
      for (const auto& kv : n) {
        add_overlay(kv.first, source);
        add_overlay(kv.second, source);
      }
    else if (n.IsSequence())
      for (const auto& e : n) add_overlay(e, source);
  }
  void record(const std::string& path, const YAML::Node& n) { marks_[path] = {source_of(n), n.Mark()}; }
  void record(const std::string& path, const YAML::Mark& mark) { marks_[path] = {source_, mark}; }
  [[nodiscard]] std::string at(const YAML::Mark& mark) const { return at(source_, mark); }
  [[nodiscard]] std::string at(const YAML::Node& n) const { return at(source_of(n), n.Mark()); }
  [[nodiscard]] std::string where(const std::string& path) const {
    // The key itself, else its nearest recorded parent.
    std::string p = path;
    while (true) {
      auto it = marks_.find(p);
      if (it != marks_.end()) return at(it->second.first, it->second.second);
      const auto cut = p.find_last_of(".[");
      if (cut == std::string::npos || cut == 0) return source_;
      p.resize(cut);
    }
  }
  [[nodiscard]] const std::string& source() const noexcept { return source_; }
  [[nodiscard]] bool has(const std::string& path) const { return marks_.count(path) != 0; }
  /// The key at `path` was read from an overlay.
  [[nodiscard]] bool from_overlay(const std::string& path) const {
    const auto it = marks_.find(path);
    return it != marks_.end() && it->second.first != source_;
  }

 private:
  [[nodiscard]] std::string source_of(const YAML::Node& n) const {
    for (const auto& [o, src] : overlay_)
      if (o.is(n)) return src;
    return source_;
  }
  /// "file:line:col"; an overlay from the command line (--set) has no lines.
  [[nodiscard]] static std::string at(const std::string& source, const YAML::Mark& mark) {
    if (mark.is_null() || mark.line < 0 || source.starts_with("--set")) return source;
    return source + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
  }
  std::string source_;
  std::unordered_map<std::string, std::pair<std::string, YAML::Mark>> marks_;
  std::vector<std::pair<YAML::Node, std::string>> overlay_;
};

inline std::string join_path(const std::string& parent, std::string_view key) {
  return parent.empty() ? std::string(key) : parent + "." + std::string(key);
}

// ---------------------------------------------------------------------------------------------
// Strict YAML reading.

inline std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0u : 1u)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

inline std::string node_kind(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Null: return "an empty value";
    case YAML::NodeType::Map: return "a mapping";
    case YAML::NodeType::Sequence: return "a sequence of " + std::to_string(n.size()) + " elements";
    case YAML::NodeType::Scalar: {
      std::string s = n.Scalar();
      if (s.size() > 40) s = s.substr(0, 37) + "...";
      std::string out = n.Tag() == "!" ? "the quoted string '" : "'";
      out += s;
      out += '\'';
      return out;
    }
    default: return "nothing";
  }
}

class Reader {
 public:
  explicit Reader(Locator& loc) : loc_(loc) {}

  [[noreturn]] void parse_error(const YAML::Node& n, const std::string& path, const std::string& msg) const {
    fail(ErrorCode::kParse, loc_.at(n) + ": " + path + ": " + msg);
  }
  /// A value of the right type out of its range (kInvalidArgument).
  [[noreturn]] void invalid(const YAML::Node& n, const std::string& path, const std::string& msg) const {
    fail(ErrorCode::kInvalidArgument, loc_.at(n) + ": " + path + ": " + msg);
  }
  void record(const std::string& path, const YAML::Node& n) { loc_.record(path, n); }
  [[nodiscard]] Locator& locator() noexcept { return loc_; }

  double number(const YAML::Node& n, const std::string& path) {
    record(path, n);
    if (!n.IsScalar() || n.Tag() == "!") parse_error(n, path, "expected a number, got " + node_kind(n));
    std::string_view s = n.Scalar();
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    double v = 0.0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || s.empty())
      parse_error(n, path, "expected a number, got " + node_kind(n));
    if (!std::isfinite(v) || std::fabs(v) > static_cast<double>(std::numeric_limits<float>::max()))
      fail(ErrorCode::kInvalidArgument,
           loc_.at(n) + ": " + path + ": must be a finite number, got " + n.Scalar());
    return v;
  }
  float real(const YAML::Node& n, const std::string& path) { return static_cast<float>(number(n, path)); }

  std::int64_t integer(const YAML::Node& n, const std::string& path, const Range& r) {
    record(path, n);
    if (!n.IsScalar() || n.Tag() == "!") parse_error(n, path, "expected an integer, got " + node_kind(n));
    std::string_view s = n.Scalar();
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    std::int64_t v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec == std::errc::result_out_of_range)
      fail(ErrorCode::kInvalidArgument,
           loc_.at(n) + ": " + path + ": must be in " + describe(r) + ", got " + n.Scalar());
    if (ec != std::errc() || end != s.data() + s.size() || s.empty())
      parse_error(n, path, "expected an integer, got " + node_kind(n));
    if (!in_range(static_cast<double>(v), r))
      fail(ErrorCode::kInvalidArgument, loc_.at(n) + ": " + path + ": must be in " + describe(r) +
                                            ", got " + std::to_string(v));
    return v;
  }

  void range(const YAML::Node& n, const std::string& path, double v, const Range& r) const {
    if (!in_range(v, r))
      fail(ErrorCode::kInvalidArgument,
           loc_.at(n) + ": " + path + ": must be in " + describe(r) + ", got " + format_number(v));
  }

  bool boolean(const YAML::Node& n, const std::string& path) {
    record(path, n);
    if (n.IsScalar() && n.Tag() != "!") {
      std::string s = n.Scalar();
      std::transform(s.begin(), s.end(), s.begin(), [](unsigned char ch) { return std::tolower(ch); });
      if (s == "true") return true;
      if (s == "false") return false;
    }
    parse_error(n, path, "expected true or false, got " + node_kind(n));
  }

  std::string string(const YAML::Node& n, const std::string& path) {
    record(path, n);
    if (!n.IsScalar()) parse_error(n, path, "expected a string, got " + node_kind(n));
    return n.Scalar();
  }

  Eigen::Vector3f vec3(const YAML::Node& n, const std::string& path, const char* what) {
    record(path, n);
    if (!n.IsSequence())
      parse_error(n, path, std::string("expected a sequence of 3 numbers ") + what + ", got " + node_kind(n));
    if (n.size() != 3)
      parse_error(n, path, std::string("expected a sequence of 3 numbers ") + what + ", got " +
                               std::to_string(n.size()) + " elements");
    Eigen::Vector3f v;
    for (std::size_t i = 0; i < 3; ++i) v[static_cast<int>(i)] = real(n[i], path + "[" + std::to_string(i) + "]");
    return v;
  }

 private:
  Locator& loc_;
};

/// A YAML mapping with a fixed set of allowed keys; unknown and duplicate keys are rejected
/// on construction (so a misspelt required key is reported as a misspelling, not as missing).
class MapReader {
 public:
  MapReader(Reader& r, const YAML::Node& node, std::string path, std::initializer_list<const char*> keys)
      : MapReader(r, node, std::move(path), std::vector<std::string_view>(keys.begin(), keys.end())) {}
  MapReader(Reader& r, const YAML::Node& node, std::string path, std::vector<std::string_view> keys)
      : r_(r), node_(node), path_(std::move(path)), keys_(std::move(keys)) {
    const std::string shown = path_.empty() ? "top level" : path_;
    if (!node_.IsMap())
      r_.parse_error(node_, shown, "expected a mapping with keys {" + key_list() + "}, got " + node_kind(node_));
    if (!path_.empty()) r_.record(path_, node_);
    std::unordered_set<std::string> seen;
    for (const auto& kv : node_) {
      const YAML::Node k = kv.first;  // a copy: kv is a proxy
      if (!k.IsScalar()) r_.parse_error(k, shown, "keys must be plain strings, got " + node_kind(k));
      const std::string& key = k.Scalar();
      const std::string kp = join_path(path_, key);
      if (std::find(keys_.begin(), keys_.end(), key) == keys_.end()) {
        std::string msg = "unknown key";
        if (const std::string s = suggestion(key); !s.empty()) msg += " (did you mean '" + s + "'?)";
        msg += "; allowed keys here: {" + key_list() + "}";
        r_.parse_error(k.Mark().is_null() ? YAML::Node(kv.second) : k, kp, msg);  // an overlay's key: located by its value
      }
      if (!seen.insert(key).second) r_.parse_error(k, kp, "duplicate key");
    }
  }

  [[nodiscard]] const std::string& path() const noexcept { return path_; }
  [[nodiscard]] std::string path_of(std::string_view key) const { return join_path(path_, key); }

  /// The value of `key`, or an undefined node if absent.
  [[nodiscard]] YAML::Node get(const char* key) const {
    check_known(key);
    return node_[key];
  }
  [[nodiscard]] bool has(const char* key) const { return static_cast<bool>(get(key)); }

  /// The value of a required key; a missing key is an error that says what was expected.
  [[nodiscard]] YAML::Node need(const char* key, const std::string& expected) const {
    YAML::Node n = get(key);
    if (!n) r_.parse_error(node_, path_of(key), "required key is missing (expected " + expected + ")");
    return n;
  }

  // Typed accessors: required (need_*) and optional (opt_*: leaves `out` unchanged if absent).
  void need_real(const char* key, float& out, const char* expected = "a number") {
    out = r_.real(need(key, expected), path_of(key));
  }
  void opt_real(const char* key, float& out) {
    if (const YAML::Node n = get(key)) out = r_.real(n, path_of(key));
  }
  template <class T>
  void need_int(const char* key, T& out, const Range& range) {
    out = static_cast<T>(r_.integer(need(key, "an integer in " + describe(range)), path_of(key), range));
  }
  template <class T>
  void opt_int(const char* key, T& out, const Range& range) {
    if (const YAML::Node n = get(key)) out = static_cast<T>(r_.integer(n, path_of(key), range));
  }
  void opt_bool(const char* key, bool& out) {
    if (const YAML::Node n = get(key)) out = r_.boolean(n, path_of(key));
  }
  void need_string(const char* key, std::string& out) { out = r_.string(need(key, "a string"), path_of(key)); }
  void opt_string(const char* key, std::string& out) {
    if (const YAML::Node n = get(key)) out = r_.string(n, path_of(key));
  }
  void opt_vec3(const char* key, Eigen::Vector3f& out, const char* what) {
    if (const YAML::Node n = get(key)) out = r_.vec3(n, path_of(key), what);
  }
  void need_vec3(const char* key, Eigen::Vector3f& out, const char* what) {
    out = r_.vec3(need(key, std::string("a sequence of 3 numbers ") + what), path_of(key), what);
  }

 private:
  void check_known(const char* key) const {
    if (std::find(keys_.begin(), keys_.end(), std::string_view(key)) == keys_.end())
      fail(ErrorCode::kInternal, "YAML reader asked for undeclared key " + path_of(key));
  }
  [[nodiscard]] std::string key_list() const {
    std::string s;
    for (const std::string_view k : keys_) s += (s.empty() ? "" : ", ") + std::string(k);
    return s;
  }
  [[nodiscard]] std::string suggestion(std::string_view key) const {
    std::string best;
    std::size_t best_d = std::max<std::size_t>(2, key.size() / 3) + 1;
    for (const std::string_view k : keys_) {
      const std::size_t d = edit_distance(key, k);
      if (d < best_d) {
        best_d = d;
        best = std::string(k);
      }
    }
    return best;
  }

  Reader& r_;
  YAML::Node node_;
  std::string path_;
  std::vector<std::string_view> keys_;
};

}  // namespace duet::detail
