/// @file settings_yaml.cpp
/// The settings tree's YAML: reading the runtime's sections, writing the whole tree
/// (to_yaml()), overlays (see settings_yaml.hpp and config/profile.hpp).
#include "config/settings_yaml.hpp"

#include <duet/kernels/error.hpp>

#include "config/settings_fields.hpp"

#include <charconv>
#include <cmath>
#include <functional>
#include <limits>
#include <regex>
#include <type_traits>

namespace duet::detail {
namespace {

constexpr Range kIntRange{-2147483648.0, 2147483647.0, false, false, ""};
constexpr Range kUnsignedRange{0.0, 9007199254740992.0, false, false, ""};

/// Collects a field list's keys (for the reader's allowed keys).
struct KeyCollector {
  std::vector<std::string_view> keys;
  template <class T>
  void operator()(const char* key, T&) {
    keys.emplace_back(key);
  }
  template <class E>
  void choice(const char* key, E&, Names<E>) {
    keys.emplace_back(key);
  }
  void up_to_inf(const char* key, float&) { keys.emplace_back(key); }
  template <class F>
  void section(const char* key, F&&) {
    keys.emplace_back(key);
  }
};

/// Reads a field list from a mapping node; absent keys keep their values.
class FieldReader {
 public:
  /// check_keys: unknown keys are errors (false when another reader owns the mapping too).
  FieldReader(Reader& r, YAML::Node node, std::string path, std::vector<std::string_view> keys, bool check_keys)
      : r_(r), node_(std::move(node)), path_(std::move(path)) {
    if (check_keys) MapReader(r_, node_, path_, std::move(keys));
  }

  template <class T>
  void operator()(const char* key, T& field) {
    const YAML::Node n = node_[key];
    if (!n) return;
    const std::string path = join_path(path_, key);
    if constexpr (std::is_same_v<T, bool>) {
      field = r_.boolean(n, path);
    } else if constexpr (std::is_same_v<T, float>) {
      field = r_.real(n, path);
    } else if constexpr (std::is_same_v<T, double>) {
      field = r_.number(n, path);
    } else if constexpr (std::is_same_v<T, int>) {
      field = static_cast<int>(r_.integer(n, path, kIntRange));
    } else if constexpr (std::is_same_v<T, std::uint64_t>) {
      // Seeds use the whole 64-bit range (with_run_seed): a plain decimal integer is read
      // exactly; anything else goes through the number reader and its messages.
      if (n.IsScalar()) {
        const std::string& text = n.Scalar();
        std::uint64_t v = 0;
        const auto res = std::from_chars(text.data(), text.data() + text.size(), v);
        if (res.ec == std::errc() && res.ptr == text.data() + text.size()) {
          r_.record(path, n);
          field = v;
          return;
        }
      }
      field = static_cast<T>(r_.integer(n, path, kUnsignedRange));
    } else if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T>) {
      const std::int64_t v = r_.integer(n, path, kUnsignedRange);
      if (static_cast<std::uint64_t>(v) > std::numeric_limits<T>::max())
        r_.invalid(n, path, "must be at most " + std::to_string(std::numeric_limits<T>::max()) + ", got " + std::to_string(v));
      field = static_cast<T>(v);
    } else if constexpr (std::is_same_v<T, std::string>) {
      field = r_.string(n, path);
    } else {
      static_assert(std::is_same_v<T, Eigen::Vector3f>, "no reader for this field type");
      field = r_.vec3(n, path, "[x, y, z]");
    }
  }
  /// A number or +infinity (YAML ".inf", "inf"): a limit that may be "none".
  void up_to_inf(const char* key, float& field) {
    const YAML::Node n = node_[key];
    if (!n) return;
    if (n.IsScalar()) {
      std::string_view s = n.Scalar();
      if (!s.empty() && s.front() == '+') s.remove_prefix(1);
      if (s == ".inf" || s == ".Inf" || s == ".INF" || s == "inf") {
        r_.record(join_path(path_, key), n);
        field = std::numeric_limits<float>::infinity();
        return;
      }
    }
    field = r_.real(n, join_path(path_, key));
  }
  template <class E>
  void choice(const char* key, E& field, Names<E> names) {
    const YAML::Node n = node_[key];
    if (!n) return;
    const std::string path = join_path(path_, key);
    const std::string s = r_.string(n, path);
    std::string list;
    for (const auto& [name, value] : names) {
      if (s == name) {
        field = value;
        return;
      }
      list += (list.empty() ? "" : ", ") + std::string(name);
    }
    r_.parse_error(n, path, "must be one of: " + list + "; got '" + s + "'");
  }
  template <class F>
  void section(const char* key, F&& fn) {
    const YAML::Node n = node_[key];
    if (!n) return;
    KeyCollector kc;
    fn(kc);
    FieldReader sub(r_, n, join_path(path_, key), std::move(kc.keys), true);
    fn(sub);
  }

 private:
  Reader& r_;
  YAML::Node node_;
  std::string path_;
};

/// Reads `node` (may be undefined) at `path` through field list `fn` into `out`.
template <class S, class Fn>
void read_fields(Reader& r, const YAML::Node& node, const std::string& path, S& out, Fn fn, bool check_keys = true) {
  if (!node) return;
  KeyCollector kc;
  fn(kc, out);
  FieldReader fr(r, node, path, std::move(kc.keys), check_keys);
  fn(fr, out);
}

/// The first mapping key named `key` in `node`'s subtree, with its path.
bool find_key(const YAML::Node& node, const std::string& path, const std::string& key, YAML::Node& found, std::string& found_path) {
  if (!node || !node.IsMap()) return false;
  if (const YAML::Node n = node[key]) {
    found = n;
    found_path = join_path(path, key);
    return true;
  }
  for (const auto& kv : node)
    if (kv.second.IsMap() && find_key(kv.second, join_path(path, kv.first.Scalar()), key, found, found_path)) return true;
  return false;
}

/// Runs a validate() and names the key it rejects: "Struct::field ..." or "Struct.field ..."
/// is looked up in the sections `where` (path, node); else the first section is named.
void validated(Reader& r, std::initializer_list<std::pair<std::string, YAML::Node>> where, const std::function<void()>& check) {
  try {
    check();
  } catch (const Error& e) {
    const std::string msg = e.what();
    static const std::regex field(R"(^[A-Za-z]+(?:::|\.)\s*([a-z_0-9]+)\b)");
    std::smatch m;
    auto name_key = [&](const std::string& key) {
      for (const auto& [path, node] : where) {
        YAML::Node n;
        std::string p;
        if (find_key(node, path, key, n, p)) r.invalid(n, p, msg);
      }
    };
    if (std::regex_search(msg, m, field)) name_key(m[1].str());
    // A check across fields ("min_height_m < max_height_m ...") names the first; the value at
    // fault may be another one the message names: the first of them the sections hold.
    static const std::regex other(R"(\b([a-z][a-z0-9]*_[a-z_0-9]+)\b)");
    for (auto it = std::sregex_iterator(msg.begin(), msg.end(), other); it != std::sregex_iterator(); ++it) name_key((*it)[1].str());
    const auto& [path, node] = *where.begin();
    if (node) r.invalid(node, path, msg);
    fail(ErrorCode::kInvalidArgument, r.locator().source() + ": " + path + ": " + msg);
  }
}

}  // namespace

std::vector<std::string_view> exploration_goal_keys() {
  KeyCollector kc;
  ExplorerSettings s;
  goal_fields(kc, s);
  return kc.keys;
}

RuntimeSettings read_runtime_settings(Reader& r, const YAML::Node& root, RuntimeSettings s) {
  const YAML::Node exploration = root["exploration"], control = root["control"], localization = root["localization"],
                   runtime = root["runtime"];
  // `exploration` is also the kernels' section: profile.cpp's reader checked its keys.
  read_fields(r, exploration, "exploration", s.explorer, [](auto& v, ExplorerSettings& e) { goal_fields(v, e); }, false);
  read_fields(r, control, "control", s.explorer, [](auto& v, ExplorerSettings& e) { control_fields(v, e); });
  read_fields(r, localization, "localization", s, [](auto& v, RuntimeSettings& rs) { localization_fields(v, rs); });
  read_fields(r, runtime, "runtime", s, [](auto& v, RuntimeSettings& rs) { runtime_fields(v, rs); });
  validated(r, {{"exploration", exploration}, {"control", control}}, [&] { validate(s.explorer); });
  validated(r, {{"localization.pose_correction", localization ? localization["pose_correction"] : YAML::Node()}},
            [&] { validate(s.pose_correction); });
  validated(r, {{"localization.loop_closure", localization ? localization["loop_closure"] : YAML::Node()}},
            [&] { validate(s.loop_closure); });
  validated(r, {{"localization.visual_odometry", localization ? localization["visual_odometry"] : YAML::Node()}},
            [&] { validate(s.visual_odometry); });
  validated(r, {{"runtime", runtime}}, [&] { validate(s); });
  return s;
}

MappingSettings read_mapping(Reader& r, const YAML::Node& node) {
  MappingSettings m;
  read_fields(r, node, "mapping", m, [](auto& v, MappingSettings& ms) { fields(v, ms); });
  return m;
}

void read_exploration_kernels(Reader& r, const YAML::Node& node, ExplorationProfile& ex) {
  read_fields(r, node, "exploration", ex, [](auto& v, ExplorationProfile& e) { fields(v, e); }, false);
}

void merge_overlay(YAML::Node base, const YAML::Node& overlay, Locator& loc, const std::string& source) {
  if (!overlay.IsMap()) fail(ErrorCode::kParse, loc.at(overlay) + ": an overlay must be a mapping of profile keys, got " + node_kind(overlay));
  for (const auto& kv : overlay) {
    const std::string key = kv.first.Scalar();
    const YAML::Node value = kv.second;
    YAML::Node target = base[key];
    if (target && target.IsMap() && value.IsMap()) {
      merge_overlay(target, value, loc, source);
    } else if (target && target.IsSequence() && value.IsMap()) {
      // A list's element by its 0-based index (`--set sensors.1.extrinsics.xyz_m=[0,0,0.5]`):
      // the keys of `value` must be indices of the list; each element is overlaid as a mapping.
      for (const auto& element : value) {
        const std::string index = element.first.Scalar();
        const bool digits = !index.empty() && index.size() <= 6 && index.find_first_not_of("0123456789") == std::string::npos;
        const std::size_t i = digits ? std::stoul(index) : 0;
        if (!digits || i >= target.size())
          fail(ErrorCode::kInvalidArgument, source + ": '" + key + "' is a list of " + std::to_string(target.size()) +
                                                " elements; '" + index + "' is not one of its indices (0-based)");
        YAML::Node item = target[i];
        if (item.IsMap() && element.second.IsMap()) {
          merge_overlay(item, element.second, loc, source);
        } else {
          loc.add_overlay(element.second, source);
          target[i] = element.second;
        }
      }
    } else {
      loc.add_overlay(value, source);
      base[key] = value;
    }
  }
}

}  // namespace duet::detail

namespace duet {
namespace {

/// Writes a field list as YAML; numbers in their shortest form that reads back exactly.
class FieldWriter {
 public:
  explicit FieldWriter(YAML::Emitter& out) : out_(out) {}
  template <class T>
  void operator()(const char* key, const T& v) {
    out_ << YAML::Key << key << YAML::Value;
    emit(v);
  }
  void up_to_inf(const char* key, float v) {
    out_ << YAML::Key << key << YAML::Value;
    if (std::isinf(v) && v > 0.0f) {
      out_ << ".inf";
    } else {
      emit(v);
    }
  }
  template <class E>
  void choice(const char* key, const E& v, detail::Names<E> names) {
    for (const auto& [name, value] : names)
      if (value == v) {
        out_ << YAML::Key << key << YAML::Value << name;
        return;
      }
    fail(ErrorCode::kInternal, std::string("to_yaml: ") + key + " has no name");
  }
  template <class F>
  void section(const char* key, F&& fn) {
    out_ << YAML::Key << key << YAML::Value << YAML::BeginMap;
    fn(*this);
    out_ << YAML::EndMap;
  }

 private:
  template <class T>
  static std::string shortest(T v) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
  }
  void emit(bool v) { out_ << (v ? "true" : "false"); }
  void emit(float v) { out_ << shortest(v); }
  void emit(double v) { out_ << shortest(v); }
  void emit(const std::string& v) { out_ << YAML::DoubleQuoted << v; }
  void emit(const Eigen::Vector3f& v) { out_ << YAML::Flow << YAML::BeginSeq << shortest(v.x()) << shortest(v.y()) << shortest(v.z()) << YAML::EndSeq; }
  template <class T>
  void emit(T v) {
    static_assert(std::is_integral_v<T>, "no writer for this field type");
    out_ << std::to_string(v);
  }
  YAML::Emitter& out_;
};

}  // namespace

std::string to_yaml(const Profile& profile) {
  Profile p = profile;  // the field lists take references
  YAML::Emitter out;
  out.SetIndent(2);
  out << YAML::BeginMap;
  FieldWriter w(out);
  w("name", p.name);
  w("description", p.description);
  w.section("chassis", [&](FieldWriter& v) { detail::fields(v, p.chassis); });
  out << YAML::Key << "sensors" << YAML::Value << YAML::BeginSeq;
  for (SensorProfile& s : p.sensors) {
    out << YAML::BeginMap;
    detail::fields(w, s);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  w.section("mapping", [&](FieldWriter& v) { detail::fields(v, p.mapping); });
  w.section("exploration", [&](FieldWriter& v) {
    detail::fields(v, p.exploration);
    detail::goal_fields(v, p.runtime.explorer);
  });
  w.section("control", [&](FieldWriter& v) { detail::control_fields(v, p.runtime.explorer); });
  w.section("localization", [&](FieldWriter& v) { detail::localization_fields(v, p.runtime); });
  w.section("runtime", [&](FieldWriter& v) { detail::runtime_fields(v, p.runtime); });
  if (!p.faults.empty()) {
    out << YAML::Key << "faults" << YAML::Value << YAML::BeginSeq;
    for (const std::string& f : p.faults) out << YAML::DoubleQuoted << f;
    out << YAML::EndSeq;
  }
  out << YAML::EndMap;
  if (!out.good()) fail(ErrorCode::kInternal, std::string("to_yaml: ") + out.GetLastError());
  return std::string(out.c_str()) + "\n";
}

ProfileOverlay set_overlay(std::string_view assignment) {
  const std::size_t eq = assignment.find('=');
  const std::string source = "--set " + std::string(assignment);
  if (eq == std::string_view::npos || eq == 0)
    fail(ErrorCode::kInvalidArgument, source + ": expected KEY=VALUE with a dotted key, e.g. exploration.view_range_m=3");
  const std::string key(assignment.substr(0, eq)), value(assignment.substr(eq + 1));
  std::vector<std::string> parts;
  for (std::size_t b = 0; b <= key.size();) {
    const std::size_t e = std::min(key.find('.', b), key.size());
    if (e == b) fail(ErrorCode::kInvalidArgument, source + ": empty key part in '" + key + "'");
    parts.push_back(key.substr(b, e - b));
    b = e + 1;
  }
  // Built as a document of nested mappings, the value as YAML (a number, true/false, a name).
  std::string text;
  for (std::size_t i = 0; i < parts.size(); ++i) text += std::string(2 * i, ' ') + parts[i] + ":" + (i + 1 < parts.size() ? "\n" : " ");
  text += value.empty() ? "\"\"" : value;
  text += "\n";
  return ProfileOverlay{source, text};
}

}  // namespace duet
